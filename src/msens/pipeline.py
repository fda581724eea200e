"""Run a study's setups through the chain model and reduce them to Table-2 rows.

Order of work (one way, no feedback): calibrate dissipation (paper Eq. 10) if the study asks
for it -> simulate every setup with the calibrated coefficients -> observe each sensor ->
extract pulse features -> compare with the study's reference rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msens.assemble import build_chain
from msens.calibrate import DissipationFit, fit_dissipation
from msens.chain.equilibrium import static_contact_forces
from msens.chain.integrate import ChainResult, simulate
from msens.chain.model import Chain
from msens.features import PulseFeatures, centre_distance, pulse_features, wave_speed
from msens.sensors import SensorKind, observe, time_derivative
from msens.study import MssModel, ReferenceRow, SensorSpec, SetupSpec, Study


@dataclass(frozen=True)
class SensorResult:
    """One sensor's modelled record and features.

    Attributes
    ----------
    sensor : SensorSpec
    position : {"top", "bottom", "single"}
        Order along the chain among the setup's sensors.
    force : ndarray, shape (nt,)
        Dynamic force the sensor reads, N (for the four-contact MsS: mean of its contacts).
    voltage_shape : ndarray, shape (nt,) or None
        For a four-contact MsS, d(force)/dt, N/s — the paper's model of the coil voltage
        (Eq. 5), up to its unknown conversion factor. For a physics MsS, the predicted DAQ
        voltage, V, on the chain's time grid.
    features : PulseFeatures
        Scalar features of ``force``.
    mss : MssRecord or None
        For a physics MsS: flux change, EMF and DAQ voltage (:mod:`msens.magnetics.mss`).
    """

    sensor: SensorSpec
    position: str
    force: np.ndarray
    voltage_shape: np.ndarray | None
    features: PulseFeatures
    mss: object | None = None


@dataclass(frozen=True)
class SetupResult:
    """A simulated setup.

    Attributes
    ----------
    setup : SetupSpec
    chain : Chain
    history : ChainResult
        Contact forces of every contact, shape (nt, n).
    static_force : ndarray, shape (n,)
        Static contact forces at rest (gravity + precompression), N.
    sensors : tuple of SensorResult
    speed_incident, speed_reflected : float
        Pulse speed between the top and bottom sensor, m/s (NaN with one sensor).
    transducers : dict or None
        Physics MsS transducers by coil particle (:class:`msens.magnetics.transducer.Transducer`).
    """

    setup: SetupSpec
    chain: Chain
    history: ChainResult
    static_force: np.ndarray
    sensors: tuple[SensorResult, ...]
    speed_incident: float
    speed_reflected: float
    transducers: dict | None = None


@dataclass(frozen=True)
class StudyResult:
    """Everything a study run produced.

    Attributes
    ----------
    study : Study
    gamma_contact, gamma_wall : float
        Damping coefficients used (fitted when the study asks for the Eq. 10 fit).
    fit : DissipationFit or None
    setups : tuple of SetupResult
    """

    study: Study
    gamma_contact: float
    gamma_wall: float
    fit: DissipationFit | None
    setups: tuple[SetupResult, ...]

    def rows(self) -> list[dict]:
        """Table-2 rows, one per sensor: model features and, where the study has them,
        the published experiment and model with the errors of both."""
        refs = {(r.setup, r.position): r for r in self.study.reference}
        out = []
        for s in self.setups:
            for sr in s.sensors:
                f = sr.features
                row = {
                    "setup": s.setup.name,
                    "sensor": sr.sensor.kind.value,
                    "position": sr.position,
                    "particle": sr.sensor.particle,
                    "tof_us": float(f.tof) * 1e6,
                    "ar": float(f.ar),
                    "incident_peak_N": float(f.f_incident),
                    "reflected_peak_N": float(f.f_reflected),
                    "width_us": float(f.width) * 1e6,
                    "speed_m_per_s": s.speed_incident,
                    "speed_reflected_m_per_s": s.speed_reflected,
                }
                ref = refs.get((s.setup.name, sr.position))
                if ref is not None:
                    row["reference"] = _compare(row, ref)
                out.append(row)
        return out


def _compare(row: dict, ref: ReferenceRow) -> dict:
    """Model against the published experiment, and the published model's own errors."""
    cmp = {
        "experiment_tof_us": ref.tof_us, "experiment_tof_std_us": ref.tof_std_us,
        "experiment_ar": ref.ar, "experiment_ar_std": ref.ar_std,
        "tof_error_pct": 100.0 * (row["tof_us"] - ref.tof_us) / ref.tof_us,
        "ar_error_pct": 100.0 * (row["ar"] - ref.ar) / ref.ar,
    }
    if ref.model_tof_us is not None:
        cmp["paper_model_tof_us"] = ref.model_tof_us
        cmp["paper_model_tof_error_pct"] = 100.0 * (ref.model_tof_us - ref.tof_us) / ref.tof_us
        cmp["tof_vs_paper_model_pct"] = 100.0 * (row["tof_us"] - ref.model_tof_us) \
            / ref.model_tof_us
    if ref.model_ar is not None:
        cmp["paper_model_ar"] = ref.model_ar
        cmp["paper_model_ar_error_pct"] = 100.0 * (ref.model_ar - ref.ar) / ref.ar
        cmp["ar_vs_paper_model"] = row["ar"] - ref.model_ar
    return cmp


def output_times(study: Study) -> np.ndarray:
    """Uniform output times from impact, s, at the study's sample rate."""
    sim = study.simulation
    n = round(sim.t_end_s * sim.sample_rate_hz) + 1
    return np.arange(n) / sim.sample_rate_hz


def _positions(sensors: tuple[SensorSpec, ...]) -> list[str]:
    if len(sensors) == 1:
        return ["single"]
    order = sorted(s.particle for s in sensors)
    return ["top" if s.particle == order[0] else "bottom" if s.particle == order[-1]
            else f"middle-{s.particle}" for s in sensors]


def _physics_mss(sensor: SensorSpec, position: str, history: ChainResult, static: np.ndarray,
                 transducers: dict, study: Study, index: int) -> SensorResult:
    from msens.fieldsetup import coil_geometry
    from msens.magnetics.mss import mss_record, readout, voltage_on
    from msens.study import CoilSpec

    tr = transducers[sensor.particle]
    coil = coil_geometry(sensor.coil or CoilSpec(), sensor.particle)
    circuit = readout(coil, tr.resistance_ohm, tr.inductance_H, study.electronics)
    rec = mss_record(tr, circuit, history.t, history.force, study.electronics,
                     approach=history.approach, static=static, seed_offset=index)
    voltage = voltage_on(rec)
    return SensorResult(sensor=sensor, position=position, force=rec.weighted_force,
                        voltage_shape=voltage,
                        features=pulse_features(rec.weighted_force, history.t), mss=rec)


def observe_setup(setup: SetupSpec, chain: Chain, history: ChainResult, *,
                  transducers: dict | None = None, study: Study | None = None) -> SetupResult:
    """Sensor records, features and speeds of one simulated setup.

    Physics MsS sensors need the setup's ``transducers`` and the ``study`` (electronics).
    """
    t = history.t
    static = static_contact_forces(chain)
    results = []
    for i, (sensor, position) in enumerate(zip(setup.sensors, _positions(setup.sensors),
                                               strict=True)):
        if sensor.model is MssModel.PHYSICS:
            results.append(_physics_mss(sensor, position, history, static, transducers,
                                        study, i))
            continue
        force = observe(sensor.kind, history.force, sensor.particle)
        shape = time_derivative(force, t) if sensor.kind is SensorKind.MSS else None
        results.append(SensorResult(sensor=sensor, position=position, force=force,
                                    voltage_shape=shape, features=pulse_features(force, t)))
    speed_in = speed_out = float("nan")
    by_pos = {r.position: r for r in results}
    if "top" in by_pos and "bottom" in by_pos:
        top, bot = by_pos["top"], by_pos["bottom"]
        d = centre_distance(chain.length, top.sensor.particle, bot.sensor.particle)
        with np.errstate(divide="ignore", invalid="ignore"):  # features may be missing: NaN
            speed_in = float(wave_speed(d, top.features.t_incident, bot.features.t_incident))
            speed_out = float(wave_speed(d, bot.features.t_reflected,
                                         top.features.t_reflected))
    return SetupResult(setup=setup, chain=chain, history=history, static_force=static,
                       sensors=tuple(results), speed_incident=speed_in,
                       speed_reflected=speed_out, transducers=transducers)


def calibrate_dissipation(study: Study, t: np.ndarray) -> DissipationFit | None:
    """Paper Eq. 10 on the study's calibration setup, or None if it asks for none."""
    spec = study.dissipation_fit
    if spec is None:
        return None
    setup = study.setup(spec.setup)
    particles = sorted(s.particle for s in setup.sensors)
    kind = next(s.kind for s in setup.sensors if s.particle == particles[0])
    return fit_dissipation(
        lambda gc, gw: build_chain(study, setup, gamma_contact=gc, gamma_wall=gw),
        sensors=(particles[0], particles[-1]), ar_top=spec.ar_top, ar_bottom=spec.ar_bottom,
        velocity=study.striker.velocity_m_per_s, t_out=t, kind=kind)


def setup_transducers(study: Study, setup: SetupSpec) -> dict | None:
    """Field-model transducers of a setup's physics MsS sensors (cached on disk), or None."""
    if not any(s.model is MssModel.PHYSICS for s in setup.sensors):
        return None
    from msens.fieldsetup import geometry_from_study
    from msens.magnetics.transducer import transducers_for

    return transducers_for(geometry_from_study(study, setup))


def simulate_setup(study: Study, setup: SetupSpec, t: np.ndarray, *, gamma_contact: float,
                   gamma_wall: float, extra: np.ndarray | None = None,
                   transducers: dict | None = None) -> tuple[Chain, ChainResult]:
    """The chain of one setup, with the magnets' static forces, and its history.

    Parameters
    ----------
    study : Study
    setup : SetupSpec
    t : ndarray, shape (nt,)
        Output times, s.
    gamma_contact, gamma_wall : float
        Damping coefficients, kg/s.
    extra : ndarray, shape (n,), optional
        Extra static particle forces, N (+ toward the wall).
    transducers : dict, optional
        The setup's physics MsS transducers: their magnets' pull on the beads becomes
        static precompression (:func:`msens.magnetics.transducer.magnetic_precompression`).
    """
    if transducers:
        from msens.magnetics.transducer import magnetic_precompression

        magnetic = magnetic_precompression(transducers)
        extra = magnetic if extra is None else extra + magnetic
    chain = build_chain(study, setup, gamma_contact=gamma_contact, gamma_wall=gamma_wall,
                        static_force=extra)
    return chain, simulate(chain, study.striker.velocity_m_per_s, t, dt=study.simulation.dt_s)


def run_study(study: Study, *, static_forces: dict[str, np.ndarray] | None = None,
              fit: DissipationFit | None = None) -> StudyResult:
    """Calibrate (if asked), simulate and observe every setup of ``study``.

    Parameters
    ----------
    study : Study
    static_forces : dict, optional
        Extra static particle forces per setup name, shape (n,), N (e.g. the magnet's pull
        predicted by the field model).
    fit : DissipationFit, optional
        A fit already made (skips the Eq. 10 calibration).

    Returns
    -------
    StudyResult
    """
    t = output_times(study)
    fit = fit if fit is not None else calibrate_dissipation(study, t)
    gc = fit.gamma_c if fit is not None else study.chain.gamma_contact
    gw = fit.gamma_w if fit is not None else study.chain.gamma_wall
    setups = []
    for setup in study.setups:
        transducers = setup_transducers(study, setup)
        chain, history = simulate_setup(study, setup, t, gamma_contact=gc, gamma_wall=gw,
                                        extra=(static_forces or {}).get(setup.name),
                                        transducers=transducers)
        setups.append(observe_setup(setup, chain, history, transducers=transducers,
                                    study=study))
    return StudyResult(study=study, gamma_contact=gc, gamma_wall=gw, fit=fit,
                       setups=tuple(setups))

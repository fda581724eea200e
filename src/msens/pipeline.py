"""Run a study's setups through the chain model and reduce them to Table-2 rows.

Order of work (one way, no feedback): calibrate dissipation (paper Eq. 10) if the study asks
for it -> simulate every setup with the calibrated coefficients -> observe each sensor ->
extract pulse features -> compare with the study's reference rows.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np
from tqdm import tqdm

from msens.calibrate import DissipationFit, fit_dissipation
from msens.chain import warmup
from msens.chain.equilibrium import static_contact_forces
from msens.chain.integrate import ChainResult, simulate
from msens.chain.model import Chain
from msens.chain.model import DampingLaw as Damping
from msens.config.assemble import build_chain
from msens.config.schema import MssModel, SensorSpec, SetupSpec
from msens.config.study import Study
from msens.errors import InputError
from msens.numba_cache import BackgroundCompile, compile_in_background
from msens.progress import COMPILE_ESTIMATE_TEXT, heartbeat
from msens.readout.electronics import compile_recursion
from msens.readout.sensors import SensorKind, observe, time_derivative
from msens.results import SensorResult, SetupResult, StudyResult
from msens.signals.features import centre_distance, model_features, wave_speed

_log = logging.getLogger(__name__)


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


def _mss_record(sensor: SensorSpec, history: ChainResult, static: np.ndarray,
                transducers: dict, study: Study, index: int, response=None):
    """The physics MsS record of one coil (:func:`msens.readout.mss.mss_signals`): with the
    coil's eddy-current ``response``, or magnetostatic without it."""
    from msens.config.fieldsetup import coil_geometry
    from msens.readout.mss import MssSensor, mss_signals, noise_model, readout

    tr = transducers[sensor.particle]
    coil = coil_geometry(sensor.coil, sensor.particle)
    circuit = readout(coil, tr.resistance_ohm, tr.inductance_H, study.electronics)
    e = study.electronics
    return mss_signals(MssSensor(tr, circuit), history.t, history.force, e.sample_rate_hz,
                       response=response, approach=history.approach, static=static,
                       noise=noise_model(e), rng=e.seed + index)


def _physics_mss(sensor: SensorSpec, position: str, history: ChainResult, static: np.ndarray,
                 transducers: dict, study: Study, index: int,
                 responses: dict | None = None) -> SensorResult:
    from msens.readout.mss import voltage_on

    rec = _mss_record(sensor, history, static, transducers, study, index,
                      responses[sensor.particle] if responses else None)
    voltage = voltage_on(rec)
    # features of what the DAQ records (integrated, in newtons), as compare and diagnose read
    # them: the read-out circuit reshapes the pulse that ``weighted_force`` has before it
    return SensorResult(sensor=sensor, position=position, force=rec.weighted_force,
                        voltage_shape=voltage,
                        features=model_features(rec.daq_force, history.t), mss=rec)


def observe_setup(setup: SetupSpec, chain: Chain, history: ChainResult, *,
                  transducers: dict | None = None, study: Study | None = None,
                  responses: dict | None = None,
                  magnetostatic: bool = False) -> SetupResult:
    """Sensor records, features and speeds of one simulated setup.

    Physics MsS sensors need the setup's ``transducers`` and the ``study`` (electronics);
    with eddy currents also their ``responses`` (:func:`setup_responses`). ``magnetostatic``:
    with eddy currents, also read each physics coil without them (same chain, transducer and
    circuit; :attr:`SetupResult.magnetostatic`), as ``msens run`` reports beside its values.
    """
    t = history.t
    static = static_contact_forces(chain)
    if any(s.model is MssModel.PHYSICS for s in setup.sensors):  # a few s on a first run
        _log.info("setup %s: coil EMF and DAQ voltage through the read-out circuit",
                  setup.name)
    results = []
    for i, (sensor, position) in enumerate(zip(setup.sensors, _positions(setup.sensors),
                                               strict=True)):
        if sensor.model is MssModel.PHYSICS:
            results.append(_physics_mss(sensor, position, history, static, transducers,
                                        study, i, responses))
            continue
        force = observe(sensor.kind, history.force, sensor.particle)
        shape = time_derivative(force, t) if sensor.kind is SensorKind.MSS else None
        results.append(SensorResult(sensor=sensor, position=position, force=force,
                                    voltage_shape=shape, features=model_features(force, t)))
    statics = None
    if magnetostatic and responses:
        statics = {s.particle: _mss_record(s, history, static, transducers, study, i)
                   for i, s in enumerate(setup.sensors) if s.model is MssModel.PHYSICS}
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
                       speed_reflected=speed_out, transducers=transducers,
                       responses=responses, magnetostatic=statics)


#: Smallest peak of a sensor's force, relative to the striker contact's, that counts as a
#: pulse: below it the wave has not arrived (or has died out) and the features would be
#: fitted to round-off (a pulse of 1e-17 N "found" at a sensor the wave never reached).
MIN_ARRIVAL_FRACTION = 1e-3


def check_arrivals(study: Study, result: SetupResult) -> None:
    """Refuse (InputError naming ``simulation.t_end_s``) a run in which the wave never
    reached one of the setup's sensors: its features would be confident nonsense."""
    force = result.history.force
    striker = float(np.max(np.abs(force[:, 0] - result.static_force[0])))
    for r in result.sensors:
        dynamic = r.force - r.force[0]
        peak = float(np.max(np.abs(dynamic))) if dynamic.size else 0.0
        if not peak >= MIN_ARRIVAL_FRACTION * striker:
            raise InputError(
                f"{study.source}: no pulse reached the {r.sensor.kind.value}@"
                f"{r.sensor.particle} sensor of setup {result.setup.name!r} within "
                f"'simulation.t_end_s' = {study.simulation.t_end_s:g} s (its peak force change "
                f"is {peak:.3g} N against {striker:.3g} N at the striker contact): lengthen "
                "t_end_s so the wave reaches every sensor and its reflection comes back")


def check_speeds(study: Study, result: SetupResult) -> None:
    """Refuse (InputError naming the damping keys) a modelled wave faster than sound in the
    bead material, sqrt(E / rho): a chain of spheres only slows a pulse down, so a faster one
    means the contacts' dashpots, not their elasticity, carry the force (gamma far above the
    contacts' critical damping)."""
    c = study.chain
    rho = c.bead_mass_kg / (np.pi / 6.0 * c.bead_diameter_m**3)
    c_bar = float(np.sqrt(c.youngs_modulus_pa / rho))
    fastest = np.nanmax([abs(result.speed_incident), abs(result.speed_reflected), 0.0])
    if fastest > c_bar:
        keys = ("'chain.gamma_contact_kg_per_s' and 'gamma_wall_kg_per_s'"
                if c.damping is not Damping.HERTZ_KUWABARA_KONO else
                "'chain.hkk_contact_kg_per_s_sqrt_m' and 'hkk_wall_kg_per_s_sqrt_m'")
        raise InputError(
            f"{study.source}: setup {result.setup.name!r}: the modelled wave travels at "
            f"{fastest:.4g} m/s between its sensors, faster than sound in the bead material "
            f"(sqrt(E/rho) = {c_bar:.4g} m/s): the contacts' damping ({keys} = "
            f"{c.gamma_contact:g}, {c.gamma_wall:g}) carries the force instead of their "
            "elasticity; lower it")


def calibrate_dissipation(study: Study, t: np.ndarray) -> DissipationFit | None:
    """Paper Eq. 10 on the study's calibration setup, or None if it asks for none."""
    spec = study.dissipation_fit
    if spec is None:
        return None
    setup = study.setup(spec.setup)
    particles = sorted(s.particle for s in setup.sensors)
    kind = next(s.kind for s in setup.sensors if s.particle == particles[0])
    _log.info("calibrating the dissipation (paper Eq. 10) on setup %s", setup.name)
    start = time.perf_counter()
    # one tick per chain built (the grid, then each refinement step): the count is open-ended
    with tqdm(desc="Eq. 10 calibration", unit=" chains", leave=False,
              disable=not _log.isEnabledFor(logging.INFO)) as bar:
        def make_chain(gc: float, gw: float) -> Chain:
            bar.update(1)
            return build_chain(study, setup, gamma_contact=gc, gamma_wall=gw)

        try:
            with heartbeat(_log, "Eq. 10 calibration",
                           note=" (a first run also compiles the chain kernel)"):
                fit = fit_dissipation(
                    make_chain, sensors=(particles[0], particles[-1]), ar_top=spec.ar_top,
                    ar_bottom=spec.ar_bottom, velocity=study.striker.velocity_m_per_s,
                    t_out=t, kind=kind)
        except InputError as exc:  # name the study's keys behind the fit
            raise InputError(f"{study.source}: 'calibration.dissipation' on setup "
                             f"{setup.name!r}: {exc} (the run ends at 'simulation.t_end_s' = "
                             f"{study.simulation.t_end_s:g} s)") from None
    _log.info("calibrated gamma_c = %.3g kg/s, gamma_w = %.3g kg/s (%d chain runs, %.1f s)",
              fit.gamma_c, fit.gamma_w, fit.n_simulations, time.perf_counter() - start)
    return fit


def setup_transducers(study: Study, setup: SetupSpec) -> dict | None:
    """Field-model transducers of a setup's physics MsS sensors (cached on disk), or None."""
    if not any(s.model is MssModel.PHYSICS for s in setup.sensors):
        return None
    from msens.config.fieldsetup import geometry_from_study
    from msens.magnetics.transducer_cache import transducers_for

    coils = ", ".join(str(s.particle) for s in setup.sensors if s.model is MssModel.PHYSICS)
    _log.info("setup %s: field model and transducers of the coils at particles %s",
              setup.name, coils)
    return transducers_for(geometry_from_study(study, setup),
                           contact_maps=study.field.contact_map)


def setup_responses(study: Study, setup: SetupSpec, *,
                    workers: int | Callable = 1) -> dict | None:
    """Eddy-current frequency responses of a setup's physics MsS coils (cached on disk), or
    None unless the study asks for eddy currents (``[field] eddy_currents = true``).
    ``workers`` (an int or a map-like, e.g. :class:`msens.parallel.TaskMap` on a Dask
    cluster): where the frequency solves run
    (:func:`msens.magnetics.dynamic_cache.dynamic_report`)."""
    if not study.field.eddy_currents or not any(s.model is MssModel.PHYSICS
                                                for s in setup.sensors):
        return None
    from msens.config.fieldsetup import eddy_settings, geometry_from_study
    from msens.magnetics.dynamic_cache import dynamic_report

    eddy = eddy_settings(study)
    _log.info("setup %s: eddy-current frequency responses (steel %.3g MS/m)", setup.name,
              eddy.steel / 1e6)
    return dynamic_report(geometry_from_study(study, setup), steel=eddy.steel,
                          options=eddy.options, workers=workers).responses


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
    try:
        static_contact_forces(chain)
    except ValueError as exc:  # the magnets' pull is a consequence of the study's sensors
        raise InputError(f"{study.source}: setup {setup.name!r}: {exc}: the bias magnets of "
                         "its [[sensor]] tables pull the beads apart more than gravity and "
                         "[[precompression]] hold them together; use a weaker magnet "
                         "('sensor.magnet.grade'), move it ('axial_offset_m') or add "
                         "precompression") from None
    # the long wait of a first run: numba compiles the kernel once per install (kept in the
    # user cache folder), with a heartbeat line every few seconds meanwhile
    compiling = warmup.cached(warmup.SIMULATE) is not True
    _log.info("setup %s: simulating the chain (%d particles, %.3g ms%s)", setup.name,
              chain.n_particles, t[-1] * 1e3,
              f"; compiling the chain kernel first, {COMPILE_ESTIMATE_TEXT} on an idle 2-core "
              "machine, once per install" if compiling else "")
    start = time.perf_counter()
    with heartbeat(_log, f"setup {setup.name}: simulating the chain",
                   note=" (compiling the chain kernel)" if compiling else ""):
        history = simulate(chain, study.striker.velocity_m_per_s, t, dt=study.simulation.dt_s)
    _log.info("setup %s: simulated in %.1f s", setup.name, time.perf_counter() - start)
    return chain, history


def run_study(study: Study, *, static_forces: dict[str, np.ndarray] | None = None,
              fit: DissipationFit | None = None, workers: int | Callable = 1) -> StudyResult:
    """Calibrate (if asked), simulate and observe every setup of ``study``.

    Parameters
    ----------
    study : Study
    static_forces : dict, optional
        Extra static particle forces per setup name, shape (n,), N (e.g. the magnet's pull
        predicted by the field model).
    fit : DissipationFit, optional
        A fit already made (skips the Eq. 10 calibration).
    workers : int or map-like callable, optional
        Where the eddy-current frequency solves run: 1 (default) here, an int n local
        processes, or a map-like ``workers(fn, iterable)`` such as
        :class:`msens.parallel.TaskMap` on a Dask cluster.

    Returns
    -------
    StudyResult
    """
    from msens import budget

    fitting = fit is None and study.dissipation_fit is not None
    job = kernel_in_background(((warmup.BATCH,) if fitting else ()) + (warmup.SIMULATE,))
    try:
        _log.info("study %s: checking its memory and time budget", study.name)
        with heartbeat(_log, f"study {study.name}: checking its budget"):
            budget.check(study)  # before any work: refuse what would exhaust memory or time
        t = output_times(study)
        if fitting:
            await_kernel(job, warmup.BATCH)
        fit = fit if fit is not None else calibrate_dissipation(study, t)
        gc = fit.gamma_c if fit is not None else study.chain.gamma_contact
        gw = fit.gamma_w if fit is not None else study.chain.gamma_wall
        setups = []
        for setup in study.setups:
            transducers = setup_transducers(study, setup)
            # the read-out compiles its recursion while this process would only wait
            await_kernel(job, warmup.SIMULATE, meanwhile=compile_recursion if any(
                s.model is MssModel.PHYSICS for s in setup.sensors) else None)
            chain, history = simulate_setup(study, setup, t, gamma_contact=gc, gamma_wall=gw,
                                            extra=(static_forces or {}).get(setup.name),
                                            transducers=transducers)
            observed = observe_setup(setup, chain, history, transducers=transducers,
                                     study=study,
                                     responses=setup_responses(study, setup, workers=workers),
                                     magnetostatic=True)
            check_arrivals(study, observed)
            observed = budget.flag_unresolved(study, observed)  # no reflection: no TOF/AR
            check_speeds(study, observed)
            setups.append(observed)
    finally:
        if job is not None:
            job.stop()  # interrupted or failed before the kernel was needed: no orphan
    return StudyResult(study=study, gamma_contact=gc, gamma_wall=gw, fit=fit,
                       setups=tuple(setups))


def kernel_in_background(variants: tuple[str, ...]) -> BackgroundCompile | None:
    """Start compiling those of the chain kernel's ``variants`` (:mod:`msens.chain.warmup`)
    that numba's cache lacks, in a second process, in this order; None if the cache holds
    them all (or cannot tell, or no process could be started: each is then compiled here
    on first use).

    The first run after installing then uses the second core: the kernel compiles while
    this process reads the study, checks its budget and loads the field model; and it loads
    the kernel from the cache, so it computes the same bits as every later run.
    """
    missing = tuple(v for v in variants if warmup.cached(v) is False)
    if not missing:
        return None
    job = compile_in_background("msens.chain.warmup", *missing)
    if job is not None:
        _log.info("compiling the chain kernel in a second process (once per install, %s on "
                  "an idle 2-core machine) while this one prepares the run",
                  COMPILE_ESTIMATE_TEXT)
    return job


def await_kernel(job: BackgroundCompile | None, variant: str,
                 meanwhile: Callable[[], object] | None = None) -> None:
    """Wait (with a heartbeat) until ``job`` has compiled ``variant`` into numba's cache,
    doing ``meanwhile`` first if there is a wait; if it failed, say so: the variant is then
    compiled in this process on first use."""
    if job is None or warmup.done_line(variant) in job.said:
        return
    with heartbeat(_log, "waiting for the chain kernel's compilation in a second process"):
        if meanwhile is not None and job.running():
            meanwhile()
        problem = job.wait_for(warmup.done_line(variant))
    if problem is not None or warmup.cached(variant) is not True:
        _log.warning("compiling the chain kernel in a second process failed (%s); compiling "
                     "it here instead, %s on an idle 2-core machine",
                     problem or "nothing was cached", COMPILE_ESTIMATE_TEXT)

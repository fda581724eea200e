"""One forward model evaluation per row of input values: the run's own code paths.

For each row of sampled input values a study is changed (chain, striker and read-out keys
through :meth:`msens.config.study.Study.replace`, validated as a file would be), each
physics MsS gets the transducer of its field model as the inputs say (remanence through the
:class:`~msens.magnetics.variants.RemanenceFamily`, coil offset through its tabulated offset
profiles, as ``msens diagnose`` varies them: :class:`msens.diagnose.models.FieldModel`; the
steel's reversibility through the spline surrogate
:class:`~msens.magnetics.reversibility.ReversibilityFamily`, see :func:`at_reversibility`;
turns by :func:`with_turns`), and with eddy currents the coil's frequency response changed
the same way (:func:`response_at`: the remanence and reversibility families of eddy-current
models, the offset profiles, the turns). The chains of a chunk of rows are integrated in one
batch (:func:`msens.chain.integrate.simulate_batch`), and each run is observed by
:func:`msens.pipeline.observe_setup`, the function ``msens run`` observes its setups with.
So a row at the nominal values reproduces ``msens run`` exactly, and every feature is the
run's feature.

Nothing here keeps state between calls: :func:`evaluate` builds its field models from the
artifact store (cached transducers: milliseconds) each call, so it can run in any worker.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from msens.chain.equilibrium import static_contact_forces
from msens.chain.integrate import ChainResult, simulate_batch
from msens.config.assemble import build_chain
from msens.config.fieldsetup import coil_geometry, eddy_settings, geometry_from_study
from msens.config.schema import CoilSpec, MssModel, SetupSpec
from msens.config.study import Study
from msens.diagnose import physics
from msens.diagnose.models import ModelBank, PhysicsMss
from msens.errors import InputError
from msens.magnetics.frequency_response import FrequencyResponse
from msens.magnetics.reversibility import (
    ReversibilityFamily,
    ReversibilityResponses,
    reversibility_family,
    reversibility_responses,
)
from msens.magnetics.transducer import Transducer, magnetic_precompression
from msens.pipeline import observe_setup, output_times, setup_responses
from msens.results import SetupResult
from msens.uq.inputs import CHAIN, FIELD_TABLE, InputSet

#: Chain runs integrated per batch call (all contacts at the paper's 10 MHz over 1 ms:
#: 4.8 MB per run for forces and approaches).
BATCH_RUNS = 16


def with_turns(tr: Transducer, turns: int) -> Transducer:
    """The coil with ``turns`` turns in the same winding window.

    The field model's coil is a current sheet of N turns over its cross-section: every flux
    linkage (each contact's sensitivity, the offset profiles) scales as N, the small-signal
    inductance as N², and the winding's resistance as N (the same mean turn, N times). The
    bias state does not change (no DC current in the coil).
    """
    s = turns / tr.turns
    return replace(tr, turns=int(turns),
                   sensitivity_villari=np.asarray(tr.sensitivity_villari) * s,
                   dlambda_dapproach=np.asarray(tr.dlambda_dapproach) * s,
                   villari_by_offset=None if tr.villari_by_offset is None
                   else np.asarray(tr.villari_by_offset) * s,
                   approach_by_offset=None if tr.approach_by_offset is None
                   else np.asarray(tr.approach_by_offset) * s,
                   inductance_H=tr.inductance_H * s * s, resistance_ohm=tr.resistance_ohm * s)


def response_at(nominal: FrequencyResponse, at_c: FrequencyResponse | None = None,
                remanent: FrequencyResponse | None = None,
                moved: tuple[FrequencyResponse, float] | None = None,
                turns_ratio: float | None = None) -> FrequencyResponse:
    """A coil's eddy-current frequency response with the row's field inputs changed, as
    :func:`at_reversibility` and :func:`with_turns` change its transducer.

    Parameters
    ----------
    nominal : FrequencyResponse
        The study's (``msens run``'s) response of the coil.
    at_c : FrequencyResponse, optional
        The coil at another steel reversibility
        (:class:`~msens.magnetics.reversibility.ReversibilityResponses`).
    remanent : FrequencyResponse, optional
        The coil with the magnets' remanence changed, nominal c
        (:class:`~msens.magnetics.variants.RemanenceResponses`): taken as it is, or with
        ``at_c`` added on top of it as :func:`at_reversibility` does (the change at the
        nominal c scaled by the size of each quantity at c).
    moved : (FrequencyResponse, float), optional
        A response with offset profiles (the diagnosis model's) and the coil's axial offset,
        m: the change of S_c(ω), D_c(ω) that moving the coil makes
        (:meth:`FrequencyResponse.shifted`) is added on top, scaled the same way; Z(ω) is
        kept, as :meth:`~msens.magnetics.transducer.Transducer.shifted` keeps R and L.
    turns_ratio : float, optional
        New turns over the solved coil's: S_c and D_c scale as N, R_dc as N, Z − R_dc and
        the static inductance as N² (:func:`with_turns`).

    Returns
    -------
    FrequencyResponse
        Without offset profiles or screening split.
    """
    r = nominal if at_c is None else at_c
    if remanent is not None:
        if at_c is None:
            r = remanent
        else:
            r = replace(r, **{name: _on_top(getattr(r, name), getattr(nominal, name),
                                            getattr(remanent, name))
                              for name in ("villari", "approach")},
                        impedance=r.resistance_ohm + _on_top(
                            r.impedance - r.resistance_ohm,
                            nominal.impedance - nominal.resistance_ohm,
                            remanent.impedance - remanent.resistance_ohm),
                        static_inductance_H=float(_on_top(
                            np.array([r.static_inductance_H]),
                            np.array([nominal.static_inductance_H]),
                            np.array([remanent.static_inductance_H]))[0]))
    if moved is not None:
        profiles, offset = moved
        shifted = profiles.shifted(offset)
        r = replace(r, **{name: _on_top(getattr(r, name), getattr(profiles, name),
                                        getattr(shifted, name))
                          for name in ("villari", "approach")})
    if turns_ratio is not None:
        s = float(turns_ratio)
        r = replace(r, villari=np.asarray(r.villari) * s, approach=np.asarray(r.approach) * s,
                    impedance=r.resistance_ohm * s + (np.asarray(r.impedance)
                                                      - r.resistance_ohm) * s * s,
                    resistance_ohm=r.resistance_ohm * s,
                    static_inductance_H=r.static_inductance_H * s * s)
    if r is nominal:
        return nominal
    return replace(r, offsets=None, villari_by_offset=None, approach_by_offset=None,
                   screening=None)


def _on_top(value: np.ndarray | None, nominal: np.ndarray | None,
            changed: np.ndarray | None) -> np.ndarray | None:
    # value + (changed - nominal), scaled by the size (2-norm) of value over that of nominal
    if value is None or nominal is None or changed is None:
        return value
    # complex values (frequency responses) stay complex; |.| is the 2-norm of the moduli
    kind = np.result_type(value, nominal, changed, float)
    value, nominal = np.asarray(value, dtype=kind), np.asarray(nominal, dtype=kind)
    size = np.linalg.norm(nominal)
    scale = np.linalg.norm(value) / size if size > 0.0 else 1.0
    return value + scale * (np.asarray(changed, dtype=kind) - nominal)


def at_reversibility(surrogate: Transducer, nominal: Transducer,
                     remanent: Transducer | None = None) -> Transducer:
    """A coil at another steel reversibility c, with the magnets' remanence change on top.

    Parameters
    ----------
    surrogate : Transducer
        The coil at c with nominal magnets
        (:meth:`msens.magnetics.reversibility.ReversibilityFamily.transducer`).
    nominal : Transducer
        The study's coil (nominal c and magnets; its contact maps, if any, are read).
    remanent : Transducer, optional
        The study's coil with the magnets' remanence changed (nominal c), from the
        :class:`~msens.magnetics.variants.RemanenceFamily`.

    Returns
    -------
    Transducer
        ``surrogate`` reading the contact maps of ``nominal``; with ``remanent``, each
        interpolated quantity q (sensitivities in Wb/N and Wb/m, offset profiles, inductance
        in H) becomes q(c) + (|q(c)| / |q(c0)|) (q_r(c0) - q(c0)): the remanence family's
        change at the nominal c0, scaled by how much c changes the quantity's size (|.|:
        the 2-norm over its elements). This is an APPROXIMATION (the families are solved
        along two lines of the (c, remanence) plane, not on its grid): it is exact when c
        and the remanence act as independent factors on each quantity's shape. Against
        direct solves of both changes on the main study (``python
        benchmarks/uq_reversibility.py --composed``) the coils' peak DAQ voltage and EMF
        agree within 0.75 %.
    """
    tr = surrogate.reading_maps_of(nominal)
    if remanent is None:
        return tr
    changes = {name: _on_top(getattr(tr, name), getattr(nominal, name),
                             getattr(remanent, name))
               for name in ("sensitivity_villari", "dlambda_dapproach", "villari_by_offset",
                            "approach_by_offset")}
    inductance = float(_on_top(np.array([tr.inductance_H]), np.array([nominal.inductance_H]),
                               np.array([remanent.inductance_H]))[0])
    return replace(tr, inductance_H=inductance, **changes,
                   source=f"{tr.source}; remanence change of {remanent.source}")


@dataclass(frozen=True)
class Task:
    """A chunk of rows to evaluate (picklable: one worker task).

    Attributes
    ----------
    study : Study
    inputs : InputSet
    values : ndarray, shape (rows, p)
        Values of the propagated inputs, SI, in :attr:`InputSet.propagated` order.
    keep : ndarray of bool, shape (rows,)
        Rows whose waveforms are returned.
    setups : tuple of str, optional
        Names of the setups to evaluate (default all).
    precise : bool
        Waveforms in float64 (a likelihood's records) instead of float32 (bands).
    """

    study: Study
    inputs: InputSet
    values: np.ndarray
    keep: np.ndarray
    setups: tuple[str, ...] | None = None
    precise: bool = False


@dataclass(frozen=True)
class Evaluation:
    """What :func:`evaluate` returns for a chunk.

    Attributes
    ----------
    features : dict of str -> ndarray, shape (rows,)
        Each output by name (``setup/sensor/feature``), SI-named units (NaN: not found).
    waveforms : dict of str -> ndarray, shape (kept rows, nt)
        Each sensor's record (a physics MsS's DAQ voltage in V, others their force in N).
    runs : int
        Chain runs made.
    """

    features: dict[str, np.ndarray]
    waveforms: dict[str, np.ndarray]
    runs: int


def sensor_name(setup: SetupSpec, index: int) -> str:
    """``setup/kind@particle`` of a setup's sensor."""
    s = setup.sensors[index]
    return f"{setup.name}/{s.kind.value}@{s.particle}"


def waveform_unit(setup: SetupSpec, index: int) -> str:
    """Unit of a sensor's waveform: V for a physics MsS (its DAQ voltage), N otherwise."""
    return "V" if setup.sensors[index].model is MssModel.PHYSICS else "N"


def row_features(result: SetupResult) -> dict[str, float]:
    """The reported features of one observed setup, by output name."""
    out: dict[str, float] = {}
    setup = result.setup
    for i, r in enumerate(result.sensors):
        name, f = sensor_name(setup, i), r.features
        out[f"{name}/tof_us"] = float(f.tof) * 1e6
        out[f"{name}/ar"] = float(f.ar)
        out[f"{name}/incident_peak_N"] = float(f.f_incident)
        if r.mss is not None:
            v, e = np.abs(r.mss.voltage), np.abs(r.mss.emf)
            out[f"{name}/peak_voltage_V"] = float(np.max(v))
            out[f"{name}/peak_voltage_time_us"] = float(r.mss.t_daq[np.argmax(v)]) * 1e6
            out[f"{name}/peak_emf_V"] = float(np.max(e))
            out[f"{name}/peak_emf_time_us"] = float(r.mss.t[np.argmax(e)]) * 1e6
    if len(result.sensors) > 1:
        out[f"{setup.name}/speed_incident_m_per_s"] = float(result.speed_incident)
        out[f"{setup.name}/speed_reflected_m_per_s"] = float(result.speed_reflected)
    return out


def row_waveforms(result: SetupResult, dtype: type = np.float32) -> dict[str, np.ndarray]:
    """Each sensor's record of one observed setup (float32 by default), by ``setup/sensor``
    name: a physics MsS's DAQ voltage (V), any other sensor's force (N)."""
    return {sensor_name(result.setup, i): np.asarray(
        r.voltage_shape if r.mss is not None else r.force, dtype=dtype)
        for i, r in enumerate(result.sensors)}


class _Setup:
    # the nominal physics of one setup: its physics MsS specs (the run's field model)
    def __init__(self, study: Study, setup: SetupSpec, bank: ModelBank):
        self.setup = setup
        self.index = study.setups.index(setup)
        self.specs: tuple[PhysicsMss | None, ...] = ()
        self.responses_nominal = setup_responses(study, setup)
        self.store = bank.store
        self._reversibility: ReversibilityFamily | None = None
        self._responses: ReversibilityResponses | None = None
        self.eddy = eddy_settings(study) if study.field.eddy_currents else None
        if any(s.model is MssModel.PHYSICS for s in setup.sensors):
            model = bank.register(geometry_from_study(study, setup), self.eddy,
                                  contact_maps=study.field.contact_map)
            self.specs = tuple(
                PhysicsMss(model=model, particle=s.particle,
                           coil=coil_geometry(s.coil or CoilSpec(), s.particle),
                           electronics=study.electronics)
                if s.model is MssModel.PHYSICS else None for s in setup.sensors)

    def family(self) -> ReversibilityFamily:
        # the reversibility surrogate of the setup's field model (solved or read once)
        if self._reversibility is None:
            model = next(p for p in self.specs if p is not None).model
            self._reversibility = reversibility_family(model.geometry, store=self.store)
        return self._reversibility

    def response_family(self) -> ReversibilityResponses:
        # with eddy currents: the coils' frequency responses over c (solved or read once)
        if self._responses is None:
            model = next(p for p in self.specs if p is not None).model
            self._responses = reversibility_responses(
                model.geometry, options=self.eddy.options, steel=self.eddy.steel,
                store=self.store)
        return self._responses

    def responses(self, field: dict) -> dict | None:
        # the coils' eddy-current responses of a row (None without eddy currents): the
        # study's, changed as the row's field inputs say (response_at)
        if self.responses_nominal is None or not self.specs:
            return self.responses_nominal
        model = next(p for p in self.specs if p is not None).model
        c = field.get("reversibility")
        if c == model.geometry.reversibility:
            c = None
        factor = field.get("remanence", 1.0)
        out = {}
        for i, p in enumerate(self.specs):
            if p is None:
                continue
            nominal = self.responses_nominal[p.particle]
            offset, turns = field.get(("offset", i), 0.0), field.get(("turns", i))
            out[p.particle] = response_at(
                nominal, None if c is None else self.response_family().response(p.particle, c),
                None if factor == 1.0 else model.response_family().response(p.particle, factor),
                None if offset == 0.0 else (model.responses[p.particle], offset),
                None if turns is None else turns / p.coil.turns)
        return out

    def row(self, changed: Study, field: dict) -> tuple[dict | None, np.ndarray | None]:
        # the transducers of the row's physics MsS and their magnets' pull on the beads
        if not self.specs:
            return None, None
        specs = tuple(None if p is None else replace(
            p, remanence_factor=field.get("remanence", 1.0),
            offset_m=field.get(("offset", i), 0.0))
            for i, p in enumerate(self.specs))
        c = field.get("reversibility")
        model = next(p for p in specs if p is not None).model
        if c is not None and c == model.geometry.reversibility:
            c = None  # the study's own field model, exactly as msens run reads it
        transducers = {}
        for i, p in enumerate(specs):
            if p is None:
                continue
            if c is None:
                tr = physics.sensor(p).transducer
            else:
                nominal = model.transducers[p.particle]
                remanent = None if p.remanence_factor == 1.0 else \
                    model.family().transducer(p.particle, p.remanence_factor)
                tr = at_reversibility(self.family().transducer(p.particle, c), nominal,
                                      remanent)
                if p.offset_m != 0.0:
                    tr = tr.shifted(p.offset_m)
            turns = field.get(("turns", i))
            transducers[p.particle] = tr if turns is None else with_turns(tr, turns)
        if c is None:
            return transducers, physics.magnetic_force(specs)
        pull = self.family().particle_force(c)
        factor = field.get("remanence", 1.0)
        if factor != 1.0:
            nominal_pull = magnetic_precompression(model.transducers)
            pull = _on_top(pull, nominal_pull, model.family().particle_force(factor))
        return transducers, pull


def _row_changes(inputs: InputSet, row: np.ndarray) -> tuple[dict, dict]:
    # study-key changes and field-model changes of one row of values
    study_changes, field = {}, {}
    for p, v in zip(inputs.propagated, row, strict=True):
        pattern = p.kind.pattern
        if pattern == "sensor[i].coil.turns":
            n = round(float(v))
            study_changes[p.name] = n  # the winding capacitance of its read-out
            field[("turns", p.sensor)] = n
        elif pattern == "sensor[i].coil.axial_offset_m":
            field[("offset", p.sensor)] = float(v)
        elif pattern == "sensor.magnet.remanence_factor":
            field["remanence"] = float(v)
        elif pattern == "field.reversibility":
            field["reversibility"] = float(v)
        elif p.route == CHAIN:
            study_changes[p.name] = float(v)
        else:  # pragma: no cover - inputs.py routes every other field input to HELD
            raise AssertionError(f"no route for {p.name} ({p.route}, {FIELD_TABLE})")
    return study_changes, field


@contextmanager
def _quiet(name: str) -> Iterator[None]:
    # the run's per-setup progress messages, once per row, would bury the uq's own
    log = logging.getLogger(name)
    level = log.level
    log.setLevel(max(level, logging.WARNING))
    try:
        yield
    finally:
        log.setLevel(level)


def evaluate(task: Task) -> Evaluation:
    """Features (and the kept rows' waveforms) of every row of ``task``.

    Raises
    ------
    InputError
        A row whose magnets pull the beads apart (as ``msens run`` refuses it).
    """
    study = task.study
    t = output_times(study)
    bank = ModelBank()
    setups = [_Setup(study, s, bank) for s in study.setups
              if task.setups is None or s.name in task.setups]
    rows = np.atleast_2d(task.values)
    features: dict[str, list[float]] = {}
    waves: dict[str, list[np.ndarray]] = {}
    runs = 0
    for start in range(0, rows.shape[0], BATCH_RUNS):
        block = range(start, min(start + BATCH_RUNS, rows.shape[0]))
        changed = []
        for r in block:
            changes, field = _row_changes(task.inputs, rows[r])
            changed.append((study.replace(changes) if changes else study, field))
        for nominal in setups:
            chains, velocities, extras = [], [], []
            for s, field in changed:
                setup = s.setups[nominal.index]
                trs, magnetic = nominal.row(s, field)
                chain = build_chain(s, setup, static_force=magnetic)
                try:
                    static_contact_forces(chain)
                except ValueError as exc:
                    raise InputError(f"{task.inputs.source}: at input values {field} the bias "
                                     f"magnets pull the beads apart ({exc}): narrow the "
                                     "magnet inputs' distributions") from None
                chains.append(chain)
                velocities.append(s.striker.velocity_m_per_s)
                extras.append((s, setup, trs, nominal.responses(field)))
            batch = simulate_batch(chains, np.array(velocities), t, dt=study.simulation.dt_s)
            runs += len(chains)
            for j, (r, (s, setup, trs, resp)) in enumerate(zip(block, extras, strict=True)):
                # contiguous copies: the read-out gathers a coil's contacts column-wise
                history = ChainResult(t=t, force=np.ascontiguousarray(batch.force[j]),
                                      approach=np.ascontiguousarray(batch.approach[j]))
                with _quiet("msens.pipeline"):
                    result = observe_setup(setup, chains[j], history, transducers=trs,
                                           study=s, responses=resp)
                for k, v in row_features(result).items():
                    features.setdefault(k, [np.nan] * rows.shape[0])[r] = v
                if task.keep[r]:
                    for k, w in row_waveforms(
                            result, np.float64 if task.precise else np.float32).items():
                        waves.setdefault(k, []).append(w)
    return Evaluation(features={k: np.asarray(v, dtype=float) for k, v in features.items()},
                      waveforms={k: np.asarray(v) for k, v in waves.items()}, runs=runs)


__all__ = ["BATCH_RUNS", "Evaluation", "Task", "at_reversibility", "evaluate", "response_at",
           "row_features",
           "row_waveforms",
           "sensor_name", "waveform_unit", "with_turns"]

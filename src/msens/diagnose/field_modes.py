"""The field model's accuracy as directions in which a physics MsS's record may move.

A physics MsS's record is a linear read-out of its contacts' states weighted by the field
model's numbers: each contact's Villari sensitivity ∂Λ/∂F_c and approach sensitivity
∂Λ/∂δ_c, the nonlinear part of the mapped contacts' Λ_c(δ), the coil's R, L and winding
capacitance, and (through the chain's static precompression) the magnets' pull on the
beads. Each of them is known to the accuracy of the
field model, about 1 % (two good field solvers differ by that much in the pull and the
sensitivities). A correct physics computed by another solver therefore gives a record

    y ≈ m + Σ_k s_k u_k,    s_k ~ N(0, 1),

where ``u_k`` is the record's change for a one-standard-deviation change of quantity k. The
modes are not small against the noise where contacts of opposite sign cancel: a 1 % error of
one contact's sensitivity moves coil 13's negative lobe of the main study by several per cent
of the record. A diagonal variance cannot express that (it is correlated over the whole
pulse), so the likelihood profiles the ``s_k`` as nuisance parameters with their Gaussian
prior (:class:`msens.diagnose.objective.WaveformObjective`), which is the marginal
likelihood of the low-rank covariance Σ u_k u_kᵀ up to a constant: an effect is named only
when it explains what no combination of field-model errors within their accuracy explains,
and the curvature of the profiled criterion widens each parameter's interval by the field
model's uncertainty where it enters.

The modes are computed once per diagnosis, from the baseline model (as the diagonal model
variance of :mod:`msens.diagnose.likelihood` is), by the run's own read-out
(:func:`msens.readout.mss.mss_signals`): it is linear in the sensitivities, so a contact's
mode is its own contribution to the record times the accuracy (exact); the circuit's modes
and each particle's pull mode are one-sided differences of a 1 % change (a pull mode by one
more chain run: about 30 runs for the main study, in one batch). The pull's effect is not
linear near lightly loaded contacts, so :data:`PULL_DRAWS` joint draws of every bead's pull
error add the second moment of what the linear modes miss (a Monte Carlo covariance). The
pull modes move every
sensor of the chain; they are profiled per channel, like the others (a simplification that
ignores their correlation between channels, on the side of calling data explained).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from msens.diagnose import physics
from msens.diagnose.effects.base import ModelState
from msens.diagnose.predict import Predictor, observe_state
from msens.readout.mss import MssSensor, mss_signals, voltage_on

#: Relative standard deviation of each field-model quantity (contact sensitivities, the
#: magnets' pull, the coil's R, L and winding capacitance): the difference of two good
#: field solvers (issue 35: about 1 % in the pull and the contact sensitivities; msens's
#: field model agrees with an independent solver to about 1 %, docs/validation).
FIELD_ACCURACY = 0.01
#: Joint draws of every bead's pull error (each N(0, accuracy)) whose records, less the
#: linear pull modes' prediction, give the modes of the pull's nonlinear effect: near the
#: main study's lightly loaded contacts 10 and 20 (0.08 and 0.13 N static) the joint 1 %
#: errors move coil 13's record by ~5.6 % of its peak, ~5 % of it not linear.
PULL_DRAWS = 16
#: Seed of those draws (the modes are the same for every diagnosis of a study).
PULL_SEED = 7
#: Joint draws of the field model's errors by which a named parameter's interval is widened
#: (:func:`field_draws`), and their seed (not the modes' own: the draws test the modes).
BOOTSTRAP_DRAWS = 16
BOOTSTRAP_SEED = 11
#: Modes whose peak is below this fraction of the sensor's largest mode peak are dropped
#: (contacts the chain does not reach, far from the coil): they cannot move the record.
MIN_MODE = 1e-6


@dataclass(frozen=True)
class RecordModes:
    """The directions of one sensor's record within the field model's accuracy.

    Attributes
    ----------
    names : tuple of str
        What each mode varies (``"villari@c"``, ``"approach@c"`` of contact c, ``"map@c"``:
        the nonlinear part of contact c's map Λ_c(δ), ``"R"``,
        ``"L"``, ``"C_winding"``, ``"Z"``: with eddy currents, the coil's impedance less its
        copper resistance, ``"pull@p"``: the magnets' pull on particle p,
        ``"pull-nonlinear#d"``: draw d of the pull's nonlinear remainder).
    records : ndarray, shape (k, nt)
        The record's change for a one-standard-deviation change of each quantity, in the
        record's unit (V), on the model's output times.
    accuracy : float
        The relative standard deviation used.
    """

    names: tuple[str, ...]
    records: np.ndarray
    accuracy: float

    def without(self, names) -> RecordModes:
        """These modes less those named in ``names``."""
        keep = [i for i, n in enumerate(self.names) if n not in names]
        return RecordModes(names=tuple(self.names[i] for i in keep),
                           records=self.records[keep], accuracy=self.accuracy)

    def to_json(self) -> dict:
        """Names and RMS size of each mode (V), for reports."""
        rms = np.sqrt(np.mean(self.records**2, axis=1)) if self.records.size else []
        return {"accuracy": self.accuracy, "modes": len(self.names),
                "largest": [{"quantity": n, "rms_v": float(r)} for n, r in
                            sorted(zip(self.names, rms, strict=True), key=lambda x: -x[1])[:5]]}


def _voltage(sensor: MssSensor, spec, t: np.ndarray, force: np.ndarray, approach: np.ndarray,
             cols: np.ndarray, response=None) -> np.ndarray:
    rec = mss_signals(sensor, t, force, spec.electronics.sample_rate_hz, response=response,
                      approach=approach, columns=cols)
    return voltage_on(rec)


def _post(state: ModelState, records: np.ndarray, dt: float) -> np.ndarray:
    for op in state.post:
        records = op(records, dt)
    return records


def _pulled(state: ModelState, magnets: np.ndarray, index: np.ndarray,
            errors: np.ndarray) -> list[ModelState]:
    # the state with the magnets' pull on particles ``index`` (0-based) off by the relative
    # ``errors`` (draws, len(index)): one state per draw
    chain = state.chain
    out = []
    for e in errors:
        extra = np.zeros_like(magnets)
        extra[index] = e * magnets[index]
        out.append(dataclasses.replace(state, chain=dataclasses.replace(
            chain, static_force=chain.static_force + extra)))
    return out


def field_draws(state: ModelState, predictor: Predictor, draws: int = BOOTSTRAP_DRAWS,
                seed: int = BOOTSTRAP_SEED, accuracy: float = FIELD_ACCURACY
                ) -> np.ndarray | None:
    """Records of ``state`` under joint draws of the field model's errors, less its own
    record: what another field solver would change, cross terms and the pull's nonlinear
    effect included.

    Each draw multiplies, each by its own (1 + accuracy e) with e standard normal, the
    magnets' pull on every pulled particle (one chain run per draw, in one batch) and, per
    physics MsS, every contact's Villari and approach sensitivity and the coil's R, L and
    winding capacitance (with eddy currents: the impedance beyond the copper instead of R
    and L), as the modes do one at a time. The nonlinear part of the contact maps is not
    drawn (it is a mode of its own and small). The draws are independent of the modes'
    own (:data:`PULL_SEED`), so they test what the modes span rather than repeat it.

    Parameters
    ----------
    state : ModelState
        The model (its speed spread is ignored: the changes are shapes).
    predictor : Predictor
    draws : int
    seed : int
    accuracy : float
        Relative standard deviation of every field-model quantity.

    Returns
    -------
    ndarray, shape (draws, sensors, nt), or None
        Record changes (the records' units: V for a physics MsS, N otherwise); None when the
        state has no physics MsS.
    """
    phys = state.physics or (None,) * len(state.particles)
    if all(p is None for p in phys):
        return None
    rng = np.random.default_rng(seed)
    plain = dataclasses.replace(state, velocity_spread=0.0)
    magnets = physics.magnetic_force(phys)
    if magnets is None:
        runs = [plain]
    else:
        magnets = np.asarray(magnets, dtype=float)
        index = np.flatnonzero(np.abs(magnets) > MIN_MODE * np.abs(magnets).max())
        runs = [plain, *_pulled(plain, magnets, index,
                                accuracy * rng.standard_normal((draws, index.size)))]
    sims = predictor._simulate(runs)
    if magnets is None:  # no pull to draw: the sensitivities and circuits only
        runs, sims = runs * (draws + 1), sims * (draws + 1)
    t = predictor.t
    dt = float(t[1] - t[0])
    base = observe_state(plain, *sims[0][:2], dt, sims[0][2])
    out = []
    for run, (force, contacts, approach) in zip(runs[1:], sims[1:], strict=True):
        # the other sensors' records (the physics MsS's rows are read below, drawn)
        raw = observe_state(dataclasses.replace(run, post=(), physics=()), force, contacts, dt,
                            approach)
        cols = None if contacts is None else np.asarray(contacts) + 1
        for j, spec in enumerate(phys):
            if spec is None:
                continue
            sensor = physics.sensor(spec)
            tr, circuit = sensor.transducer, sensor.circuit
            n_c = np.asarray(tr.contacts).size
            fv = 1.0 + accuracy * rng.standard_normal(n_c)
            fa = 1.0 + accuracy * rng.standard_normal(n_c)
            fr, fl, fc, fz = 1.0 + accuracy * rng.standard_normal(4)
            tr1 = dataclasses.replace(
                tr, sensitivity_villari=np.asarray(tr.sensitivity_villari) * fv,
                dlambda_dapproach=np.asarray(tr.dlambda_dapproach) * fa)
            resp = physics.response(spec) if spec.model.eddy_currents else None
            if resp is None:
                circuit = dataclasses.replace(circuit, resistance=circuit.resistance * fr,
                                              inductance=circuit.inductance * fl)
            else:
                z = np.asarray(resp.impedance)
                resp = dataclasses.replace(
                    resp, villari=resp.villari * fv[None, :], approach=resp.approach * fa[None, :],
                    impedance=resp.resistance_ohm + fz * (z - resp.resistance_ohm))
            circuit = dataclasses.replace(
                circuit, winding_capacitance=circuit.winding_capacitance * fc)
            raw[j] = _voltage(MssSensor(tr1, circuit), spec, t, force, approach, cols, resp)
        out.append(_post(plain, raw, dt) - base)
    return np.array(out)


def record_modes(state: ModelState, predictor: Predictor,
                 accuracy: float = FIELD_ACCURACY) -> tuple[RecordModes | None, ...]:
    """Per sensor of ``state``, the modes of its record within the field model's accuracy
    (None for a sensor that is not a physics MsS).

    Parameters
    ----------
    state : ModelState
        The baseline model (its speed spread is ignored: the modes are shapes).
    predictor : Predictor
    accuracy : float
        Relative standard deviation of every field-model quantity.

    Returns
    -------
    tuple of (RecordModes or None), one per sensor
    """
    phys = state.physics or (None,) * len(state.particles)
    if all(p is None for p in phys):
        return tuple(None for _ in state.particles)
    plain = dataclasses.replace(state, velocity_spread=0.0)
    magnets = physics.magnetic_force(phys)
    runs, pulled = [plain], []
    if magnets is not None:
        magnets = np.asarray(magnets, dtype=float)
        for p in np.flatnonzero(np.abs(magnets) > MIN_MODE * np.abs(magnets).max()):
            # central difference: the pull's ±1 %
            runs += _pulled(plain, magnets, np.array([p]), accuracy * np.array([[1.0], [-1.0]]))
            pulled.append(int(p) + 1)
        # joint draws of every bead's pull error, for what the linear modes miss
        draws = np.random.default_rng(PULL_SEED).standard_normal((PULL_DRAWS, len(pulled)))
        runs += _pulled(plain, magnets, np.array(pulled) - 1, accuracy * draws)
    sims = predictor._simulate(runs)
    force, contacts, approach = sims[0]
    t = predictor.t
    dt = float(t[1] - t[0])
    # the records before the state's record operations (e.g. a DAQ filter effect), and after
    raw = observe_state(dataclasses.replace(plain, post=()), force, contacts, dt, approach)
    base = _post(plain, raw, dt)
    moved = [observe_state(run, f1, c1, dt, a1)
             for run, (f1, c1, a1) in zip(runs[1:], sims[1:], strict=True)]
    n_pull = 2 * len(pulled)
    pull = [0.5 * (up - down)
            for up, down in zip(moved[:n_pull:2], moved[1:n_pull:2], strict=True)]
    # each draw's record less the linear modes' prediction: the nonlinear remainder, whose
    # second moment (over the draws) the modes r_d / sqrt(D) carry
    nonlinear = []
    if pulled:
        for e, rec in zip(draws, moved[n_pull:], strict=True):
            lin = np.tensordot(e, np.array(pull), axes=1)
            nonlinear.append((rec - base - lin) / np.sqrt(PULL_DRAWS))
    cols = None if contacts is None else np.asarray(contacts) + 1

    def after_post(j: int, v: np.ndarray) -> np.ndarray:
        # the change of sensor j's final record when its raw record changes by v
        if not plain.post:
            return v
        x = raw.copy()
        x[j] = raw[j] + v
        return _post(plain, x, dt)[j] - base[j]

    out: list[RecordModes | None] = []
    for j, spec in enumerate(phys):
        if spec is None:
            out.append(None)
            continue
        sensor = physics.sensor(spec)
        tr = sensor.transducer
        resp = physics.response(spec) if spec.model.eddy_currents else None
        names, recs = [], []
        n_c = np.asarray(tr.contacts).size
        for mech in ("villari", "approach"):
            for i, c in enumerate(np.asarray(tr.contacts)):
                unit = np.zeros(n_c)
                unit[i] = 1.0
                sv = unit if mech == "villari" else np.zeros(n_c)
                sa = unit if mech == "approach" else np.zeros(n_c)
                one = dataclasses.replace(
                    tr, sensitivity_villari=np.asarray(tr.sensitivity_villari) * sv,
                    dlambda_dapproach=np.asarray(tr.dlambda_dapproach) * sa)
                r1 = None if resp is None else dataclasses.replace(
                    resp, villari=resp.villari * sv[None, :],
                    approach=resp.approach * sa[None, :])
                v = _voltage(MssSensor(one, sensor.circuit), spec, t, force, approach, cols, r1)
                names.append(f"{mech}@{int(c)}")
                recs.append(accuracy * v)
        if tr.approach_map is not None:
            # the nonlinear part of each mapped contact's Λ_c(δ): its contribution with the
            # map less that without (the linear source alone)
            for c in sorted(int(x) for x in tr.approach_map.contacts):
                sa = (np.asarray(tr.contacts) == c).astype(float)
                one = dataclasses.replace(
                    tr, sensitivity_villari=np.zeros(n_c),
                    dlambda_dapproach=np.asarray(tr.dlambda_dapproach) * sa)
                r1 = None if resp is None else dataclasses.replace(
                    resp, villari=resp.villari * 0.0, approach=resp.approach * sa[None, :])
                v = (_voltage(MssSensor(one, sensor.circuit), spec, t, force, approach, cols, r1)
                     - _voltage(MssSensor(dataclasses.replace(one, approach_map=None),
                                          sensor.circuit), spec, t, force, approach, cols, r1))
                names.append(f"map@{c}")
                recs.append(accuracy * v)
        circuit = sensor.circuit
        quantities = [("C_winding", "winding_capacitance")]
        if resp is None:  # with eddy currents Z(ω) replaces R and L
            quantities = [("R", "resistance"), ("L", "inductance"), *quantities]
        for name, field in quantities:
            moved = dataclasses.replace(circuit, **{field: getattr(circuit, field)
                                                    * (1.0 + accuracy)})
            v = _voltage(MssSensor(tr, moved), spec, t, force, approach, cols, resp)
            names.append(name)
            recs.append(v - raw[j])
        if resp is not None:  # the coil's impedance beyond its copper: jωL(ω), eddy losses
            z = np.asarray(resp.impedance)
            moved = dataclasses.replace(
                resp, impedance=resp.resistance_ohm + (1.0 + accuracy) * (z - resp.resistance_ohm))
            v = _voltage(MssSensor(tr, circuit), spec, t, force, approach, cols, moved)
            names.append("Z")
            recs.append(v - raw[j])
        recs = [after_post(j, v) for v in recs]
        for p, change in zip(pulled, pull, strict=True):
            names.append(f"pull@{p}")
            recs.append(change[j])
        for d, rest in enumerate(nonlinear):
            names.append(f"pull-nonlinear#{d + 1}")
            recs.append(rest[j])
        arr = np.array(recs)
        peak = np.max(np.abs(arr), axis=1)
        keep = peak > MIN_MODE * float(peak.max()) if peak.size else peak > 0
        out.append(RecordModes(names=tuple(n for n, k in zip(names, keep, strict=True) if k),
                               records=arr[keep], accuracy=accuracy))
    return tuple(out)


__all__ = ["FIELD_ACCURACY", "RecordModes", "field_draws", "record_modes"]

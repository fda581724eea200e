"""Batched prediction of sensor records for many model states.

States that share a chain and striker speed (they differ only in the observation, e.g. the
sensor particles or the acquisition filter) share one simulation; the rest are run in
batches with :func:`msens.chain.simulate_batch` grouped by damping law. A batch outputs only
the contacts its states' sensors average (``contacts=``): at the paper's 10 MHz all 30
contacts take 4.8 MB per run, the eight of two four-contact MsS 1.3 MB.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from msens.chain.equilibrium import static_contact_forces
from msens.chain.integrate import ChainResult, simulate_batch
from msens.config.assemble import build_chain
from msens.diagnose import physics
from msens.diagnose.effects.base import Context, ModelState
from msens.readout.mss import voltage_on
from msens.readout.sensors import SensorKind, observe, read_contacts, time_derivative
from msens.results import SensorResult, SetupResult
from msens.signals.features import PulseFeatures, integrated, model_features

#: Nodes (in standard deviations) and weights of the 3-point Gauss-Hermite rule for the mean
#: over a normal distribution.
GH3_NODES = (-np.sqrt(3.0), 0.0, np.sqrt(3.0))
GH3_WEIGHTS = (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0)
#: Output memory of one simulate_batch call, bytes (forces and approaches, runs x nt x
#: contacts doubles each): bounds the runs per call.
BATCH_BYTES = 2**27
#: Chain runs a predictor keeps (the most recent), by state and contacts read.
RECENT_RUNS = 12


@dataclass
class Predictor:
    """Sensor force records of model states on the common output times.

    Attributes
    ----------
    t : ndarray, shape (nt,)
        Output times from impact, s.
    simulations : int
        Chain runs made so far (a counter for reports).
    """

    t: np.ndarray
    simulations: int = 0
    _recent: dict = field(default_factory=dict, repr=False, compare=False)

    def records(self, states: Sequence[ModelState]) -> np.ndarray:
        """Dynamic sensor forces (N) after the states' record operations; for a state with a
        ``velocity_spread``, their mean over that spread of striker speeds (3-point
        Gauss-Hermite rule, exact for a record quadratic in the speed over the spread).

        Returns
        -------
        ndarray, shape (runs, sensors, nt)
        """
        if any(s.velocity_spread > 0 for s in states):
            nodes, owners, weights = [], [], []
            for i, s in enumerate(states):
                if s.velocity_spread > 0:
                    for x, w in zip(GH3_NODES, GH3_WEIGHTS, strict=True):
                        nodes.append(dataclasses.replace(
                            s, velocity=s.velocity * (1.0 + s.velocity_spread * x),
                            velocity_spread=0.0))
                        owners.append(i)
                        weights.append(w)
                else:
                    nodes.append(s)
                    owners.append(i)
                    weights.append(1.0)
            each = self.records(nodes)
            out = np.zeros((len(states), *each.shape[1:]))
            for r, i, w in zip(each, owners, weights, strict=True):
                out[i] += w * r
            return out
        keys = [_sim_key(s) for s in states]
        unique: dict[tuple, int] = {}
        for k in keys:
            unique.setdefault(k, len(unique))
        firsts = {unique[k]: s for k, s in zip(keys, states, strict=True)}
        order = [firsts[i] for i in range(len(unique))]
        # Each simulation outputs the contacts that the sensors of all its states read.
        needs: dict[int, list[ModelState]] = {}
        for k, s in zip(keys, states, strict=True):
            needs.setdefault(unique[k], []).append(s)
        wanted = [_read_contacts(needs[i]) for i in range(len(order))]
        tags = [(k, w.tobytes()) for k, w in zip(unique, wanted, strict=True)]
        found = {t: self._recent[t] for t in tags if t in self._recent}
        missing = [i for i, t in enumerate(tags) if t not in found]
        if missing:
            runs = self._simulate([order[i] for i in missing], [wanted[i] for i in missing])
            found.update({tags[i]: r for i, r in zip(missing, runs, strict=True)})
        forces = [found[t] for t in tags]
        # the last few chain runs are kept: a state read again with another read-out (e.g.
        # a coil's inductance profiled, :mod:`msens.diagnose.inductance`) is not rerun
        for t in tags[-RECENT_RUNS:]:
            self._recent.pop(t, None)
            self._recent[t] = found[t]
        while len(self._recent) > RECENT_RUNS:
            self._recent.pop(next(iter(self._recent)))
        dt = float(self.t[1] - self.t[0])
        out = np.empty((len(states), len(states[0].particles), self.t.size))
        # a coil read once per chain run and spec (a coil offset moves one sensor; a record
        # operation none): the grid of such an effect reads each coil's few specs only
        memos: list[dict] = [{} for _ in order]
        for r, (k, s) in enumerate(zip(keys, states, strict=True)):
            force, contacts, approach = forces[unique[k]]
            out[r] = observe_state(s, force, contacts, dt, approach, memo=memos[unique[k]])
        return out

    def _simulate(self, states: list[ModelState], needs: list[np.ndarray] | None = None,
                  ) -> list[tuple[np.ndarray, np.ndarray | None, np.ndarray]]:
        # Contact forces (nt, c) of each state, the contacts of their columns (those in
        # ``needs``, the union over a batch, or all: None) and the contact approaches (nt, c).
        result: list = [None] * len(states)
        groups: dict = {}
        for i, s in enumerate(states):
            groups.setdefault(s.chain.damping_law, []).append(i)
        for idx in groups.values():
            start = 0
            while start < len(idx):
                part, contacts = self._batch(states, needs, idx[start:])
                res = simulate_batch([states[i].chain for i in part],
                                     np.array([states[i].velocity for i in part]), self.t,
                                     contacts=contacts)
                self.simulations += len(part)
                for j, i in enumerate(part):
                    result[i] = (res.force[j], contacts, res.approach[j])
                start += len(part)
        return result

    def _batch(self, states, needs, idx) -> tuple[list[int], np.ndarray | None]:
        # The leading runs of idx whose output (of the union of their contacts) fits in
        # BATCH_BYTES (at least one), and that union (None: all contacts).
        per_contact = 16 * self.t.size  # force and approach, bytes per run and contact
        part: list[int] = []
        contacts = None
        for i in idx:
            union = None if needs is None else (
                needs[i] if contacts is None else np.union1d(contacts, needs[i]))
            width = states[i].chain.n_particles if union is None else union.size
            if part and (len(part) + 1) * width * per_contact > BATCH_BYTES:
                break
            part.append(i)
            contacts = union
        return part, contacts


def _read_contacts(states: list[ModelState]) -> np.ndarray:
    # The 0-based contacts that the sensors of states of one chain read (sorted); a physics
    # MsS reads every contact its transducer covers (1-based numbers there).
    n = states[0].chain.n_particles
    pairs = [(kind, p) for s in states
             for kind, p, ph in zip(s.kinds, s.particles, _physics(s), strict=True)
             if ph is None]
    coils = [physics.sensor(ph).transducer.contacts - 1 for s in states
             for ph in _physics(s) if ph is not None]
    parts = ([read_contacts(pairs, n)] if pairs else []) + coils
    both = np.unique(np.concatenate(parts))
    return both[(both >= 0) & (both < n)].astype(int)


def _physics(state: ModelState) -> tuple:
    return state.physics or (None,) * len(state.particles)


def observe_state(state: ModelState, force: np.ndarray, contacts: np.ndarray | None,
                  dt: float, approach: np.ndarray | None = None, memo: dict | None = None
                  ) -> np.ndarray:
    """Sensor records (sensors, nt) of a state from contact forces (nt, c): column j is the
    0-based contact ``contacts[j]``, or contact j if ``contacts`` is None. Bead, rod and
    four-contact MsS records are forces (N); a physics MsS record is its DAQ voltage (V),
    driven by the contact approaches ``approach`` (nt, c; m) when given. ``memo``: physics
    MsS records already read from this same chain run, by spec (read and added here)."""
    t = np.arange(force.shape[0]) * dt
    cols = None if contacts is None else np.asarray(contacts) + 1  # 1-based contact numbers

    def read(ph) -> np.ndarray:
        if memo is not None and ph in memo:
            return memo[ph]
        v = voltage_on(physics.signals(ph, t, force, approach=approach, columns=cols))
        if memo is not None:
            memo[ph] = v
        return v

    out = np.array([
        observe(kind, force, p, contacts=contacts) if ph is None else read(ph)
        for kind, p, ph in zip(state.kinds, state.particles, _physics(state), strict=True)])
    for op in state.post:
        out = op(out, dt)
    return out


def same_run(a: ModelState, b: ModelState) -> bool:
    """Whether two states run the same chain (they differ in their read-out only)."""
    return _sim_key(a) == _sim_key(b) and a.velocity_spread == b.velocity_spread


def _sim_key(state: ModelState) -> tuple:
    c = state.chain
    return (c.mass.tobytes(), c.stiffness.tobytes(), c.damping.tobytes(),
            c.static_force.tobytes(), c.drag.tobytes(), c.gravity, c.damping_law,
            float(state.velocity))


def baseline_state(ctx: Context, gamma_contact: float, gamma_wall: float) -> ModelState:
    """The study's model of the setup with the given (calibrated) dissipation: for physics
    MsS sensors with their magnets' pull on the beads, as :func:`msens.pipeline.run_study`."""
    ph = physics.setup_physics(ctx)
    chain = build_chain(ctx.study, ctx.setup, gamma_contact=gamma_contact,
                        gamma_wall=gamma_wall, static_force=physics.magnetic_force(ph))
    return ModelState(chain=chain, velocity=float(ctx.study.striker.velocity_m_per_s),
                      particles=tuple(s.particle for s in ctx.setup.sensors),
                      kinds=tuple(s.kind for s in ctx.setup.sensors), physics=ph)


def signal(kind: SensorKind, force: np.ndarray, t: np.ndarray, physics: bool = False
           ) -> np.ndarray:
    """What a channel's voltage is proportional to: force (bead, rod), dF/dt (four-contact
    MsS, Eq. 5), or the record itself (a physics MsS record is its DAQ voltage)."""
    if physics:
        return force
    return time_derivative(force, t) if kind is SensorKind.MSS else force


def feature_records(records: np.ndarray, physics: Sequence[bool], t: np.ndarray
                    ) -> np.ndarray:
    """Records whose pulse features are read: forces as they are, a physics MsS voltage
    integrated from impact (V s; as :func:`msens.compare.model_record`)."""
    out = np.array(records, dtype=float, copy=True)
    for j, ph in enumerate(physics):
        if ph:
            out[..., j, :] = integrated(records[..., j, :], t)
    return out


def model_features_of(records: np.ndarray, t: np.ndarray) -> PulseFeatures:
    """Features of feature records (..., nt) as diagnose reads them: the pipeline of
    ``msens run`` (:func:`msens.signals.features.model_features`) after the low-pass the
    measured records get, as ``compare`` reads them."""
    return model_features(records, t, lowpass_records=True)


def setup_result(ctx: Context, state: ModelState, predictor: Predictor) -> SetupResult:
    """A :class:`~msens.results.SetupResult` whose records come from ``state``.

    The sensors keep the setup's nominal specs (so synthetic channels are labelled as the
    study says) while their records are read where ``state`` says. The contact-force history
    is that of the state's chain; speeds are not computed (NaN).
    """
    res, _, approach = predictor._simulate([state])[0]
    t = predictor.t
    records = observe_state(state, res, None, float(t[1] - t[0]), approach)
    static = static_contact_forces(state.chain)
    sensors = []
    where = positions([s.particle for s in ctx.setup.sensors])
    for spec, pos, rec, ph in zip(ctx.setup.sensors, where, records, _physics(state),
                                  strict=True):
        if ph is not None:  # the record is the DAQ voltage; force: the weighted force
            mss = physics.signals(ph, t, res, approach=approach, static=static)
            sensors.append(SensorResult(sensor=spec, position=pos, force=mss.weighted_force,
                                        voltage_shape=rec,
                                        features=model_features(mss.daq_force, t), mss=mss))
            continue
        shape = time_derivative(rec, t) if spec.kind is SensorKind.MSS else None
        sensors.append(SensorResult(sensor=spec, position=pos, force=rec, voltage_shape=shape,
                                    features=model_features(rec, t)))
    return SetupResult(setup=ctx.setup, chain=state.chain,
                       history=ChainResult(t=t, force=res, approach=approach),
                       static_force=static, sensors=tuple(sensors),
                       speed_incident=float("nan"), speed_reflected=float("nan"))


def positions(particles: Sequence[int]) -> list[str]:
    """"top" / "bottom" (or "single") of each sensor by its particle."""
    if len(particles) == 1:
        return ["single"]
    lo, hi = min(particles), max(particles)
    return ["top" if p == lo else "bottom" if p == hi else f"middle-{p}" for p in particles]

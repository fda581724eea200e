"""Batched prediction of sensor records for many model states.

States that share a chain and striker speed (they differ only in the observation, e.g. the
sensor particles or the acquisition filter) share one simulation; the rest are run in
batches with :func:`msens.chain.simulate_batch` grouped by damping law. A batch outputs only
the contacts its states' sensors average (``contacts=``): at the paper's 10 MHz all 30
contacts take 4.8 MB per run, the eight of two four-contact MsS 1.3 MB.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from msens.assemble import build_chain
from msens.chain.equilibrium import static_contact_forces
from msens.chain.integrate import ChainResult, simulate_batch
from msens.compare import smoothed_features as model_features_of
from msens.diagnose.effects.base import Context, ModelState
from msens.pipeline import SensorResult, SetupResult
from msens.sensors import SensorKind, observe, read_contacts, time_derivative

#: Output memory of one simulate_batch call, bytes (forces and approaches, runs x nt x
#: contacts doubles each): bounds the runs per call.
BATCH_BYTES = 2**27


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

    def records(self, states: Sequence[ModelState]) -> np.ndarray:
        """Dynamic sensor forces (N) after the states' record operations.

        Returns
        -------
        ndarray, shape (runs, sensors, nt)
        """
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
        forces = self._simulate(order, [_read_contacts(needs[i]) for i in range(len(order))])
        dt = float(self.t[1] - self.t[0])
        out = np.empty((len(states), len(states[0].particles), self.t.size))
        for r, (k, s) in enumerate(zip(keys, states, strict=True)):
            out[r] = observe_state(s, *forces[unique[k]], dt)
        return out

    def _simulate(self, states: list[ModelState], needs: list[np.ndarray] | None = None,
                  ) -> list[tuple[np.ndarray, np.ndarray | None]]:
        # Contact forces (nt, c) of each state and the contacts of their columns: those in
        # ``needs`` (the union over a batch), or all (None) without.
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
                    result[i] = (res.force[j], contacts)
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
    # The contacts that the sensors of states of one chain read (sorted).
    return read_contacts([(kind, p) for s in states
                          for kind, p in zip(s.kinds, s.particles, strict=True)],
                         states[0].chain.n_particles)


def observe_state(state: ModelState, force: np.ndarray, contacts: np.ndarray | None,
                  dt: float) -> np.ndarray:
    """Sensor records (sensors, nt) of a state, N, from contact forces (nt, c): column j is
    contact ``contacts[j]``, or contact j if ``contacts`` is None."""
    out = np.array([observe(kind, force, p, contacts=contacts)
                    for kind, p in zip(state.kinds, state.particles, strict=True)])
    for op in state.post:
        out = op(out, dt)
    return out


def _sim_key(state: ModelState) -> tuple:
    c = state.chain
    return (c.mass.tobytes(), c.stiffness.tobytes(), c.damping.tobytes(),
            c.static_force.tobytes(), c.gravity, c.damping_law, float(state.velocity))


def baseline_state(ctx: Context, gamma_contact: float, gamma_wall: float) -> ModelState:
    """The study's model of the setup with the given (calibrated) dissipation."""
    chain = build_chain(ctx.study, ctx.setup, gamma_contact=gamma_contact,
                        gamma_wall=gamma_wall)
    return ModelState(chain=chain, velocity=float(ctx.study.striker.velocity_m_per_s),
                      particles=tuple(s.particle for s in ctx.setup.sensors),
                      kinds=tuple(s.kind for s in ctx.setup.sensors))


def signal(kind: SensorKind, force: np.ndarray, t: np.ndarray) -> np.ndarray:
    """What a channel's voltage is proportional to: force (bead, rod) or dF/dt (MsS, Eq. 5)."""
    return time_derivative(force, t) if kind is SensorKind.MSS else force


def setup_result(ctx: Context, state: ModelState, predictor: Predictor) -> SetupResult:
    """A :class:`~msens.pipeline.SetupResult` whose records come from ``state``.

    The sensors keep the setup's nominal specs (so synthetic channels are labelled as the
    study says) while their records are read where ``state`` says. The contact-force history
    is that of the state's chain; speeds are not computed (NaN).
    """
    res, _ = predictor._simulate([state])[0]
    t = predictor.t
    forces = observe_state(state, res, None, float(t[1] - t[0]))
    sensors = []
    where = positions([s.particle for s in ctx.setup.sensors])
    for spec, pos, f in zip(ctx.setup.sensors, where, forces, strict=True):
        shape = time_derivative(f, t) if spec.kind is SensorKind.MSS else None
        sr = SensorResult(sensor=spec, position=pos, force=f, voltage_shape=shape,
                          features=model_features_of(f, t))
        sensors.append(sr)
    return SetupResult(setup=ctx.setup, chain=state.chain,
                       history=ChainResult(t=t, force=res, approach=np.zeros_like(res)),
                       static_force=static_contact_forces(state.chain), sensors=tuple(sensors),
                       speed_incident=float("nan"), speed_reflected=float("nan"))


def positions(particles: Sequence[int]) -> list[str]:
    """"top" / "bottom" (or "single") of each sensor by its particle."""
    if len(particles) == 1:
        return ["single"]
    lo, hi = min(particles), max(particles)
    return ["top" if p == lo else "bottom" if p == hi else f"middle-{p}" for p in particles]

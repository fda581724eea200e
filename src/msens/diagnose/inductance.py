"""Each coil's inductance as a nonlinear nuisance of the likelihood.

A physics MsS's coil, its winding and its cable form a resonant circuit whose resonance lies
inside the signal band (77 kHz for the paper's coil with 1 m of cable). The field model
gives the coil's inductance to its accuracy (:data:`~msens.diagnose.field_modes.
FIELD_ACCURACY`, 1 %). A relative error e of L moves the resonance by about e/2; at the
read-out's quality factor that is comparable to the resonance's bandwidth for e of a few
per cent, so over a few standard deviations the record does not move linearly in L. The
field model's linear mode ``"L"`` (``"Z"`` with eddy currents; :mod:`msens.diagnose.
field_modes`) then cannot hold the error, and a candidate that also moves the resonance
(the cable's capacitance, a change far below its significance floor) takes it up and
outscores the effect that is really there.

A diagnosis therefore first profiles each coil's inductance factor f_j of its baseline
exactly, minimising

    chi^2(records(baseline, f)) + sum_j ((f_j - 1) / a)^2,

with a the field model's accuracy (the factor's Gaussian prior) and chi^2 the likelihood
without the linear inductance modes (:meth:`~msens.diagnose.objective.WaveformObjective.
without_modes`), which f replaces. The candidates are then fitted on that baseline, with the
likelihood's modes taken there (they linearise the remaining error about the profiled
factor). The factor changes the read-out only: the chain is run once (the predictor keeps
its recent runs) and each coil's factor is searched on a grid of :data:`GRID` points over
±:data:`SPAN` accuracies, then refined between the best point's neighbours, one coil after
the other. A factor whose optimum lies at the end of that range is set back to 1: the data
then want a change the field model's error cannot make (a longer cable, another coil), and
that is for the candidates to find, not for the nuisance to take up in part.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import minimize_scalar

from msens.diagnose.effects.base import ModelState
from msens.diagnose.field_modes import FIELD_ACCURACY
from msens.diagnose.predict import Predictor

#: Names of the field model's linear inductance modes that the profiled factor replaces.
MODES = ("L", "Z")
#: Search range of each factor, in accuracies either side of 1.
SPAN = 5.0
#: Points of the start grid over that range.
GRID = 11


def factors(state: ModelState) -> tuple[float | None, ...]:
    """Each sensor's inductance factor (None: not a physics MsS); empty without one."""
    return tuple(None if p is None else p.inductance_factor for p in state.physics)


def with_factors(state: ModelState, values: tuple[float | None, ...]) -> ModelState:
    """``state`` with its physics MsS's inductance factors set to ``values`` (as
    :func:`factors` gives them; empty: unchanged)."""
    if not values:
        return state
    return dataclasses.replace(state, physics=tuple(
        None if p is None else dataclasses.replace(p, inductance_factor=float(f))
        for p, f in zip(state.physics, values, strict=True)))


def prior_terms(state: ModelState, accuracy: float = FIELD_ACCURACY) -> np.ndarray:
    """Per sensor, ((f - 1) / accuracy)^2 of its coil's inductance factor (0 for others)."""
    return np.array([0.0 if f is None else ((f - 1.0) / accuracy) ** 2
                     for f in factors(state)] or [0.0] * len(state.particles))


def criterion(objective, records: np.ndarray, state: ModelState,
              accuracy: float = FIELD_ACCURACY) -> float:
    """The profile's criterion of ``state`` whose records are ``records``: chi^2 under
    ``objective`` (the likelihood without :data:`MODES`) plus its factors' prior terms."""
    return float(objective.rss(records).sum()) + float(prior_terms(state, accuracy).sum())


def profile(state: ModelState, predictor: Predictor, objective,
            accuracy: float = FIELD_ACCURACY) -> ModelState:
    """``state`` with each coil's inductance factor at the optimum of the criterion of the
    module docstring; a factor whose optimum is at the end of its search is set back to 1.

    Parameters
    ----------
    state : ModelState
    predictor : Predictor
    objective : WaveformObjective
        The likelihood without the linear inductance modes (:data:`MODES`).
    accuracy : float
        Relative standard deviation of the field model's inductance.

    Returns
    -------
    ModelState
    """
    edge = (SPAN - SPAN / (GRID - 1)) * accuracy  # half a grid step inside the end
    for j, spec in enumerate(state.physics):
        if spec is None:
            continue

        def at(values, j=j, state=state) -> list[ModelState]:
            out = []
            for f in values:
                now = list(factors(state))
                now[j] = float(f)
                out.append(with_factors(state, tuple(now)))
            return out

        def crit(f: float) -> float:
            (s,) = at([f])
            return criterion(objective, predictor.records([s])[0], s, accuracy)

        grid = 1.0 + accuracy * np.linspace(-SPAN, SPAN, GRID)
        states = at(grid)
        values = [criterion(objective, r, s, accuracy)
                  for r, s in zip(predictor.records(states), states, strict=True)]
        k = int(np.argmin(values))
        best, f_best = float(grid[k]), values[k]
        opt = minimize_scalar(crit,
                              bounds=(grid[max(k - 1, 0)], grid[min(k + 1, GRID - 1)]),
                              method="bounded", options={"xatol": 0.02 * accuracy})
        if opt.fun < f_best:
            best = float(opt.x)
        if abs(best - 1.0) > edge:
            # the data want more than the field model's error: not this nuisance's to take
            best = 1.0
        state = at([best])[0]
    return state


__all__ = ["GRID", "MODES", "SPAN", "criterion", "factors", "prior_terms", "profile",
           "with_factors"]

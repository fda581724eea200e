"""Fit one effect's parameters: a batched grid, then a bounded refinement.

The criterion minimised is the weighted residual sum over sensors, sum_c RSS_c / sigma_c^2
(sigma_c from the objective; 1 where unknown). Continuous parameters: a grid of
``effect.grid_points`` per parameter (log-spaced for scale parameters) run as one batch, then
a bounded Brent search (one parameter) or Nelder–Mead (several) between the grid neighbours
of the best point. Integer parameters: every combination (one batch; states that need no new
simulation share one); continuous parameters beside them are refined at the best
combination.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize, minimize_scalar

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.diagnose.predict import Predictor

#: Refinement tolerance in the search variable (log10 of the parameter for log parameters):
#: 1e-3 decades is 0.23 % of the value.
XATOL = 1e-3


@dataclass(frozen=True)
class EffectFit:
    """Best parameters of one effect.

    Attributes
    ----------
    effect : str
    parameters : dict
        Fitted values, SI (integers as ints).
    state : ModelState
        Baseline with the effect at the fitted values.
    rss : ndarray, shape (sensors,)
        Residual sum of squares per sensor at the optimum (objective units).
    n_parameters : int
    evaluations : int
        Model states evaluated (grid + refinement).
    """

    effect: str
    parameters: dict
    state: ModelState
    rss: np.ndarray
    n_parameters: int
    evaluations: int


def _to_x(p: Parameter, value: float) -> float:
    return float(np.log10(value)) if p.log else float(value)


def _from_x(p: Parameter, x: float) -> float:
    v = 10.0 ** x if p.log else x
    return float(np.clip(v, p.lower, p.upper))


def _grid(p: Parameter, points: int) -> np.ndarray:
    if p.integer:
        return np.arange(int(np.ceil(p.lower)), int(np.floor(p.upper)) + 1, dtype=float)
    return np.linspace(_to_x(p, p.lower), _to_x(p, p.upper), points)


def fit_effect(effect: Effect, ctx: Context, base: ModelState, predictor: Predictor,
               objective, weights: np.ndarray) -> EffectFit:
    """Fit ``effect`` on top of ``base`` to the measurement behind ``objective``.

    Parameters
    ----------
    effect : Effect
    ctx : Context
    base : ModelState
    predictor : Predictor
    objective : WaveformObjective or FeatureObjective
        Anything with ``rss(records (sensors, nt)) -> (sensors,)``.
    weights : ndarray, shape (sensors,)
        1 / sigma^2 per sensor.

    Returns
    -------
    EffectFit
    """
    space = effect.space(ctx, base)
    grids = [_grid(p, effect.grid_points) for p in space]
    points = list(itertools.product(*grids))

    def params_of(x) -> dict:
        return {p.name: (round(v) if p.integer else _from_x(p, v))
                for p, v in zip(space, x, strict=True)}

    count = [0]
    cache: dict[tuple, np.ndarray] = {}

    def evaluate(xs: list) -> list[np.ndarray]:
        todo = [tuple(map(float, x)) for x in xs if tuple(map(float, x)) not in cache]
        if todo:
            states = [effect.apply(ctx, base, params_of(x)) for x in todo]
            records = predictor.records(states)
            for x, r in zip(todo, records, strict=True):
                cache[x] = objective.rss(r)
            count[0] += len(todo)
        return [cache[tuple(map(float, x))] for x in xs]

    rss = evaluate(points)
    crit = np.array([float(weights @ r) for r in rss])
    best = np.array(points[int(np.argmin(crit))], dtype=float)

    continuous = [i for i, p in enumerate(space) if not p.integer]
    if continuous:
        # refine the continuous parameters between their grid neighbours, the integer ones
        # held at their best grid value
        lo, hi = [], []
        for i in continuous:
            g = grids[i]
            k = int(np.argmin(np.abs(g - best[i])))
            lo.append(g[max(k - 1, 0)])
            hi.append(g[min(k + 1, g.size - 1)])

        def full(xc) -> np.ndarray:
            x = best.copy()
            x[continuous] = xc
            return x

        def f(xc) -> float:
            return float(weights @ evaluate([full(np.atleast_1d(xc))])[0])

        if len(continuous) == 1:
            opt = minimize_scalar(lambda x: f([x]), bounds=(lo[0], hi[0]), method="bounded",
                                  options={"xatol": XATOL})
            x_opt = full(np.array([opt.x]))
        else:
            opt = minimize(f, best[continuous], method="Nelder-Mead",
                           bounds=list(zip(lo, hi, strict=True)),
                           options={"xatol": XATOL, "fatol": 1e-6, "maxfev": 60})
            x_opt = full(np.asarray(opt.x))
        if f(x_opt[continuous]) < f(best[continuous]):
            best = x_opt
    params = params_of(best)
    return EffectFit(effect=effect.name, parameters=params,
                     state=effect.apply(ctx, base, params),
                     rss=evaluate([best])[0], n_parameters=len(space), evaluations=count[0])


def refit_jointly(named: list[tuple[Effect, dict]], ctx: Context, plain: ModelState,
                  predictor: Predictor, objective, weights: np.ndarray,
                  maxfev: int = 80) -> tuple[list[dict], ModelState, np.ndarray]:
    """Refine the continuous parameters of several named effects together.

    Each pass of the workflow fits a new effect with the earlier ones frozen; the earlier
    ones were then fitted without the new one and have absorbed part of it. A bounded
    Nelder–Mead over all their continuous parameters at once (search variables as in
    :func:`fit_effect`; integer parameters stay fixed) removes that bias.

    Parameters
    ----------
    named : list of (Effect, parameters)
        The effects in the order they are applied to ``plain``.
    plain : ModelState
        The baseline without any of them.

    Returns
    -------
    parameters : list of dict
        Refined parameters, one dict per effect.
    state : ModelState
    rss : ndarray, shape (sensors,)
    """
    slots = []  # (effect index, Parameter)
    for i, (effect, _) in enumerate(named):
        slots += [(i, p) for p in effect.space(ctx, plain) if not p.integer]

    def build(x) -> tuple[list[dict], ModelState]:
        params = [dict(p) for _, p in named]
        for (i, p), v in zip(slots, x, strict=True):
            params[i][p.name] = _from_x(p, float(v))
        state = plain
        for (effect, _), ps in zip(named, params, strict=True):
            state = effect.apply(ctx, state, ps)
        return params, state

    def f(x) -> float:
        return float(weights @ objective.rss(predictor.records([build(x)[1]])[0]))

    x0 = np.array([_to_x(p, named[i][1][p.name]) for i, p in slots])
    if slots:
        bounds = [(_to_x(p, p.lower), _to_x(p, p.upper)) for _, p in slots]
        step = np.array([0.02 if p.log else 0.02 * (p.upper - p.lower) for _, p in slots])
        simplex = np.vstack([x0, x0 + np.diag(step)])
        f0 = f(x0)
        opt = minimize(f, x0, method="Nelder-Mead", bounds=bounds,
                       options={"initial_simplex": simplex, "xatol": XATOL, "fatol": 1e-3,
                                "maxfev": maxfev})
        if opt.fun < f0:
            x0 = np.asarray(opt.x)
    params, state = build(x0)
    return params, state, objective.rss(predictor.records([state])[0])

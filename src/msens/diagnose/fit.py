"""Fit one effect's parameters: a batched grid, then a bounded refinement.

The criterion minimised is the weighted residual sum over sensors, sum_c RSS_c / sigma_c^2
(sigma_c from the objective; 1 where unknown). Continuous parameters: a grid of
``effect.grid_points`` per parameter (log-spaced for scale parameters) run as one batch, then
a bounded Brent search (one parameter) or Nelder–Mead (several) between the grid neighbours
of the best point. Integer parameters: every combination (one batch; states that need no new
simulation share one), or, for an effect with ``strides`` (costly states), every stride-th
value first and then every value from the best coarse point's neighbours to its
neighbours (the continuous grid in full in both); continuous parameters beside them are
refined at the best combinations.

Honest parameters: at the optimum the curvature of the criterion (a chi^2: the residual over
the likelihood's variance, :mod:`msens.diagnose.likelihood`) gives each continuous parameter
an interval (:func:`curvature_covariance`: a finite-difference Hessian H in the search
variables, two batches of simulations; covariance 2 H^-1, widened by the reduced chi^2 when
it exceeds 1), and a parameter whose optimum sits within ``BOUND_TOL`` of the edge of its
searched range, or of its physical range inside it, is flagged "at bound": the search or
the physical limit, not the data, stopped it there.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize, minimize_scalar

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.diagnose.predict import Predictor
from msens.errors import internal

#: Refinement tolerance in the search variable (log10 of the parameter for log parameters):
#: 1e-3 decades is 0.23 % of the value; for linear parameters, 1e-3 of the searched span
#: when that is finer (a coil offset searched over 5 mm: 5 um, not 1 mm).
XATOL = 1e-3
#: A continuous optimum within this fraction of its searched span (in the search variable)
#: from either end is "at bound".
BOUND_TOL = 5e-3
#: Integer combinations whose continuous parameters are refined, for effects searched coarse
#: to fine (``Effect.strides``); 1 otherwise.
REFINED_COMBINATIONS = 4
#: A refit near an earlier optimum (``fit_effect(..., near=...)``) searches this many start
#: grid points on either side of it; when its best point is at the end of that window, the
#: whole grid is searched after all.
NEAR_STEPS = 2
#: Coverage of the reported intervals (two-sided, normal approximation).
LEVEL = 0.95
#: Normal quantile of ``LEVEL``.
Z_LEVEL = 1.959963984540054
#: Steps of the curvature's second round, in standard deviations of its first estimate:
#: on the profile of a physics MsS's chi^2 the roughness is ~1 per step of 0.05 % in a
#: parameter, so one-sigma second differences (~2) can be dominated by it; two-sigma ones
#: (~8) are not.
CURVATURE_STEP = 2.0


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
        Model states evaluated (grid + refinement + curvature).
    intervals : dict
        Per continuous parameter, its ``LEVEL`` interval (lower, upper), SI, from the
        curvature at the optimum (clipped to the searched range); integer parameters have
        none.
    at_bound : tuple of str
        Parameters whose optimum is at an end of their searched range.
    curvature : ndarray, shape (k, k), optional
        ``2 H^-1`` of the continuous parameters (their order in the effect's space), in
        search variables (log10 for log parameters): the covariance before the widening by
        the reduced chi^2.
    widening : float
        That widening factor (>= 1); the intervals hold ``widening * curvature``.
    """

    effect: str
    parameters: dict
    state: ModelState
    rss: np.ndarray
    n_parameters: int
    evaluations: int
    intervals: dict = field(default_factory=dict)
    at_bound: tuple[str, ...] = ()
    curvature: np.ndarray | None = None
    widening: float = 1.0


def _to_x(p: Parameter, value: float) -> float:
    return float(np.log10(value)) if p.log else float(value)


def _from_x(p: Parameter, x: float) -> float:
    v = 10.0 ** x if p.log else x
    return float(np.clip(v, p.lower, p.upper))


def _xatol(p: Parameter) -> float:
    return XATOL if p.log else min(XATOL, XATOL * (p.upper - p.lower))


def _grid(p: Parameter, points: int) -> np.ndarray:
    if p.integer:
        return np.arange(int(np.ceil(p.lower)), int(np.floor(p.upper)) + 1, dtype=float)
    return np.linspace(_to_x(p, p.lower), _to_x(p, p.upper), points)


def _stride_grid(g: np.ndarray, stride: int) -> np.ndarray:
    """Every ``stride``-th value of an integer grid, its last value included."""
    out = g[::stride]
    return out if out[-1] == g[-1] else np.append(out, g[-1])


def _window(g: np.ndarray, x: float, steps: int) -> np.ndarray:
    """The points of grid ``g`` within ``steps`` of the one nearest ``x``, and ``x``."""
    k = int(np.argmin(np.abs(g - x)))
    return np.unique(np.append(g[max(k - steps, 0):k + steps + 1], x))


def fit_effect(effect: Effect, ctx: Context, base: ModelState, predictor: Predictor,
               objective, weights: np.ndarray, near: dict | None = None) -> EffectFit:
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
    near : dict, optional
        Parameters of an earlier fit of the effect (another likelihood of the same data):
        the integer parameters are held at their values, and the start grid of each
        continuous one holds only its :data:`NEAR_STEPS` points on either side of its value
        (and the value). When the best of those is at the end of that window (and not of
        the searched range), the whole grid is searched.

    Returns
    -------
    EffectFit
    """
    space = effect.space(ctx, base)
    grids = [_grid(p, effect.grid_points) for p in space]
    if near is not None:
        full_grids = grids
        grids = [np.array([float(round(near[p.name]))]) if p.integer else
                 _window(g, _to_x(p, near[p.name]), NEAR_STEPS)
                 for p, g in zip(space, grids, strict=True)]
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

    strides = {k: int(v) for k, v in effect.strides(ctx).items() if int(v) > 1}
    if near is not None:
        strides = {}
    if strides:
        # coarse to fine: the integer parameters with a stride on every stride-th value,
        # then every integer from the best coarse point's neighbours to its neighbours
        # (they were tried only with the other parameters' coarse values: a run of three
        # contacts can look best as one contact at its end); the continuous ones on their
        # full grid in both (a coarser one leaves gaps in which the effect resembles
        # nothing tried, and the coarse stage then picks another basin)
        coarse = [grids[i] if not p.integer else
                  _stride_grid(grids[i], strides.get(p.name, 1))
                  for i, p in enumerate(space)]
        cpts = list(itertools.product(*coarse))
        ccrit = [float(weights @ r) for r in evaluate(cpts)]
        cbest = cpts[int(np.argmin(ccrit))]
        grids = [g if not p.integer or p.name not in strides else
                 g[np.abs(g - cbest[i]) <= strides[p.name]]
                 for i, (p, g) in enumerate(zip(space, grids, strict=True))]
        points = cpts + list(itertools.product(*grids))
    rss = evaluate(points)
    crit = np.array([float(weights @ r) for r in rss])
    best = np.array(points[int(np.argmin(crit))], dtype=float)
    if near is not None and any(
            not p.integer and (best[i] == g[0] != f[0] or best[i] == g[-1] != f[-1])
            for i, (p, g, f) in enumerate(zip(space, grids, full_grids, strict=True))):
        return fit_effect(effect, ctx, base, predictor, objective, weights)  # moved further

    continuous = [i for i, p in enumerate(space) if not p.integer]
    if continuous:
        def full(xc, at: np.ndarray | None = None) -> np.ndarray:
            x = (best if at is None else at).copy()
            x[continuous] = xc
            return x

        def refine(start: np.ndarray) -> tuple[np.ndarray, float]:
            # the continuous parameters between their grid neighbours, the integer ones
            # held at the start's values
            lo, hi = [], []
            for i in continuous:
                g = grids[i]
                k = int(np.argmin(np.abs(g - start[i])))
                lo.append(g[max(k - 1, 0)])
                hi.append(g[min(k + 1, g.size - 1)])

            def f(xc) -> float:
                return float(weights @ evaluate([full(np.atleast_1d(xc), start)])[0])

            if len(continuous) == 1:
                opt = minimize_scalar(lambda x: f([x]), bounds=(lo[0], hi[0]),
                                      method="bounded",
                                      options={"xatol": _xatol(space[continuous[0]])})
                x_opt = full(np.array([opt.x]), start)
            else:
                opt = minimize(f, start[continuous], method="Nelder-Mead",
                               bounds=list(zip(lo, hi, strict=True)),
                               options={"xatol": min(_xatol(space[i]) for i in continuous),
                                        "fatol": 1e-6, "maxfev": 60})
                x_opt = full(np.asarray(opt.x), start)
            f_opt, f_start = f(x_opt[continuous]), f(start[continuous])
            return (x_opt, f_opt) if f_opt < f_start else (start, f_start)

        starts = [best]
        integer = [i for i, p in enumerate(space) if p.integer]
        if strides and integer:
            # costly states, coarse grids: the continuous parameters are refined at the best
            # REFINED_COMBINATIONS integer combinations (a run's place, length and force
            # trade off along a ridge, on which the force grid alone picks the wrong one)
            seen: dict[tuple, np.ndarray] = {}
            for i in np.argsort(crit, kind="stable"):
                key = tuple(points[i][j] for j in integer)
                seen.setdefault(key, np.array(points[i], dtype=float))
                if len(seen) == REFINED_COMBINATIONS:
                    break
            starts = list(seen.values())
        best = min((refine(x) for x in starts), key=lambda r: r[1])[0]
    params = params_of(best)
    intervals: dict[str, tuple[float, float]] = {}
    at_bound: list[str] = []
    curvature, widening = None, 1.0
    if continuous:
        xc = best[continuous]
        lower = np.array([_to_x(space[i], space[i].lower) for i in continuous])
        upper = np.array([_to_x(space[i], space[i].upper) for i in continuous])

        def crit_batch(xs: list[np.ndarray]) -> np.ndarray:
            return np.array([float(weights @ r)
                             for r in evaluate([full(np.asarray(x)) for x in xs])])

        n_obs = float(np.sum(getattr(objective, "n_obs", np.inf)))
        curvature = curvature_covariance(crit_batch, xc, lower, upper)
        dof = n_obs - len(continuous)
        chi2 = float(weights @ evaluate([best])[0])
        if np.isfinite(n_obs) and dof > 0:
            widening = max(1.0, chi2 / dof)
        intervals = interval_map([space[i] for i in continuous], xc, widening * curvature)
        at_bound = [space[i].name for i, flag
                    in zip(continuous, at_bounds(xc, lower, upper), strict=True)
                    if flag or _at_physical_edge(space[i], float(best[i]))]
    return EffectFit(effect=effect.name, parameters=params,
                     state=effect.apply(ctx, base, params),
                     rss=evaluate([best])[0], n_parameters=len(space), evaluations=count[0],
                     intervals=intervals, at_bound=tuple(at_bound), curvature=curvature,
                     widening=widening)


def interval_map(space: list[Parameter], x: np.ndarray, cov: np.ndarray) -> dict:
    """``{name: (lower, upper)}``, SI: the ``LEVEL`` interval of each parameter of ``space``
    at search variables ``x`` (k,) with covariance ``cov`` (k, k), clipped to its searched
    range."""
    lower = np.array([_to_x(p, p.lower) for p in space])
    upper = np.array([_to_x(p, p.upper) for p in space])
    return {p.name: (_from_x(p, lo), _from_x(p, hi))
            for p, (lo, hi) in zip(space, parameter_intervals(x, cov, lower, upper),
                                   strict=True)}


def _at_physical_edge(p: Parameter, x: float) -> bool:
    # inside the physical range but within BOUND_TOL of the searched span from one of its
    # ends that lies inside the search (beyond it the fit is implausible instead)
    span = _to_x(p, p.upper) - _to_x(p, p.lower)
    for edge in p.physical:
        if p.lower < edge < p.upper and p.is_plausible(_from_x(p, x)) and \
                abs(x - _to_x(p, edge)) <= BOUND_TOL * span:
            return True
    return False


def at_bounds(x: np.ndarray, lower: np.ndarray, upper: np.ndarray,
              tol: float = BOUND_TOL) -> np.ndarray:
    """Whether each optimum ``x`` sits at an end of its searched range [lower, upper]
    (within ``tol`` of the span; all in search variables), shape (k,) of bool."""
    span = upper - lower
    return (x - lower <= tol * span) | (upper - x <= tol * span)


def curvature_covariance(crit: Callable[[list[np.ndarray]], np.ndarray], x0: np.ndarray,
                         lower: np.ndarray, upper: np.ndarray, *,
                         n_obs: float = np.inf) -> np.ndarray:
    """Covariance of the search variables at the minimum ``x0`` of a chi^2 criterion.

    chi^2 = -2 ln L + const, so near its minimum chi^2(x) ~ chi^2_0 + (x - x0)^T H (x - x0)
    / 2 and the covariance is 2 H^-1. H is a finite-difference Hessian in two rounds of
    batched evaluations: steps of 2 % of the searched span give a first curvature per
    variable; the second round steps by ``CURVATURE_STEP`` standard deviations of that
    first estimate (a chi^2 change of ~4: the scale of a 95 % interval, and large against
    the criterion's roughness of order 1 from the alignment's and the chain's tolerances,
    which makes the second differences of one-sigma steps unreliable; between 1e-4 and 10 %
    of the span), with the mixed terms from one extra point per pair. Stencils stay inside
    [lower, upper]: at an end the three points lie on its inner side. Directions the data
    do not constrain (curvature <= 0 or a standard deviation beyond the span) get the span
    as their standard deviation. When chi^2_0 per degree of freedom (n_obs - k) exceeds 1,
    the covariance is multiplied by it: a model that misses the data does not pin its
    parameters down as tightly as the noise alone would.

    Parameters
    ----------
    crit : callable
        ``crit(list of x (k,)) -> chi^2 (m,)``, evaluated in batches.
    x0 : ndarray, shape (k,)
        The minimum, in search variables (log10 of the parameter for log parameters).
    lower, upper : ndarray, shape (k,)
        The searched range of each variable.
    n_obs : float
        Observations behind the chi^2 (inf: no widening by the reduced chi^2).

    Returns
    -------
    ndarray, shape (k, k)
        Covariance of the search variables.
    """
    x0 = np.asarray(x0, dtype=float)
    k = x0.size
    span = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)

    def inside(i: int, h: np.ndarray) -> bool:
        return bool(x0[i] - h[i] >= lower[i] and x0[i] + h[i] <= upper[i])

    def stencils(h: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
        # per variable two points besides x0: x0 -+ h (central), or at an end x0 + s h and
        # x0 + 2 s h on its inner side; s is the side of the single step x0 + s h
        pts, signs = [x0.copy()], np.ones(k)
        for i in range(k):
            a, b = x0.copy(), x0.copy()
            if inside(i, h):
                a[i] -= h[i]
                b[i] += h[i]
            else:
                signs[i] = 1.0 if x0[i] + h[i] <= upper[i] else -1.0
                a[i] += signs[i] * h[i]
                b[i] += 2 * signs[i] * h[i]
            pts += [a, b]
        return signs, pts

    def curvatures(h: np.ndarray, f: np.ndarray) -> np.ndarray:
        c = np.empty(k)
        for i in range(k):
            fa, fb = f[1 + 2 * i], f[2 + 2 * i]
            c[i] = (fa - 2 * f[0] + fb if inside(i, h) else f[0] - 2 * fa + fb) / h[i] ** 2
        return c

    h = 0.02 * span
    _, pts = stencils(h)
    f = np.asarray(crit(pts), dtype=float)
    c = curvatures(h, f)
    sd = np.where(c > 0, np.sqrt(2.0 / np.where(c > 0, c, 1.0)), 0.1 * span)
    h = np.clip(CURVATURE_STEP * sd, 1e-4 * span, 0.1 * span)
    signs, pts = stencils(h)
    pairs = [(i, j) for i in range(k) for j in range(i + 1, k)]
    for i, j in pairs:
        x = x0.copy()
        x[i] += signs[i] * h[i]
        x[j] += signs[j] * h[j]
        pts.append(x)
    f = np.asarray(crit(pts), dtype=float)
    H = np.diag(curvatures(h, f))
    for m, (i, j) in enumerate(pairs):
        # forward mixed difference along the stencils' sides: f(x0 + s_i h_i + s_j h_j)
        # - f(x0 + s_i h_i) - f(x0 + s_j h_j) + f(x0), the single steps from the stencils
        fi = f[2 + 2 * i] if inside(i, h) else f[1 + 2 * i]
        fj = f[2 + 2 * j] if inside(j, h) else f[1 + 2 * j]
        H[i, j] = H[j, i] = (f[1 + 2 * k + m] - fi - fj + f[0]) / (signs[i] * signs[j]
                                                                   * h[i] * h[j])
    # in units of each variable's span: an unconstrained direction (flat, or curved the
    # wrong way from finite-difference noise) gets the searched span as its std
    Hn = 0.5 * (H + H.T) * np.outer(span, span)
    lam, vec = np.linalg.eigh(Hn)
    lam = np.maximum(lam, 2.0)
    cov = (vec @ np.diag(2.0 / lam) @ vec.T) * np.outer(span, span)
    dof = n_obs - k
    if np.isfinite(n_obs) and dof > 0:
        cov = cov * max(1.0, float(f[0]) / dof)
    return cov


def parameter_intervals(x0: np.ndarray, cov: np.ndarray, lower: np.ndarray,
                        upper: np.ndarray, z: float = Z_LEVEL) -> list[tuple[float, float]]:
    """``x0 -+ z sd`` per search variable (sd from ``cov``), clipped to [lower, upper]."""
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return [(float(max(lo, x - z * s)), float(min(hi, x + z * s)))
            for x, s, lo, hi in zip(x0, sd, lower, upper, strict=True)]


def field_spread(effect: Effect, ctx: Context, base: ModelState, predictor: Predictor,
                 objective, weights: np.ndarray, fit: EffectFit, *change_sets: np.ndarray
                 ) -> np.ndarray:
    """Covariance of a fit's continuous parameters over changes of the model's records:
    how far the optimum moves when the model is off by each of ``changes``.

    With the criterion quadratic about the optimum x0 (Hessian H = 2 ``fit.curvature``^-1),
    a model record shifted by a change d moves the optimum by -H^-1 (g_d - g_0), where g is
    the criterion's gradient at x0 with and without d: central differences over one
    standard deviation of each variable (one batch of 2k model runs; every change is then
    only a re-evaluation of the criterion). The second moment of those moves over the
    changes is returned (summed over independent sets of changes, which share the model
    runs): with changes drawn from the field model's accuracy
    (:func:`msens.diagnose.field_modes.field_draws`), the part of the parameters'
    uncertainty that comes from the field model.

    Parameters
    ----------
    effect, ctx, base, predictor, objective, weights
        As for :func:`fit_effect`.
    fit : EffectFit
        The effect's fit (with its ``curvature``).
    *change_sets : ndarray, shape (draws, sensors, nt)
        Changes of the model's records (the records' units); each set's second moment is
        taken over its own draws.

    Returns
    -------
    ndarray, shape (k, k)
        In search variables, the continuous parameters in the order of the effect's space.
    """
    space = effect.space(ctx, base)
    continuous = [i for i, p in enumerate(space) if not p.integer]
    internal(fit.curvature is not None and len(continuous) == fit.curvature.shape[0],
             "internal: field_spread needs the fit's curvature")
    x0 = np.array([_to_x(space[i], float(fit.parameters[space[i].name])) for i in continuous])
    lower = np.array([_to_x(space[i], space[i].lower) for i in continuous])
    upper = np.array([_to_x(space[i], space[i].upper) for i in continuous])
    span = upper - lower
    h = np.clip(CURVATURE_STEP * np.sqrt(np.maximum(np.diag(fit.curvature), 0.0)),
                1e-4 * span, 0.1 * span)
    points = []
    for i in range(len(continuous)):
        for sign in (-1.0, 1.0):
            x = x0.copy()
            x[i] = np.clip(x0[i] + sign * h[i], lower[i], upper[i])
            points.append(x)

    def params(x: np.ndarray) -> dict:
        out = dict(fit.parameters)
        for j, i in enumerate(continuous):
            out[space[i].name] = _from_x(space[i], float(x[j]))
        return out

    records = predictor.records([effect.apply(ctx, base, params(x)) for x in points])
    steps = np.array([points[2 * i + 1][i] - points[2 * i][i] for i in range(len(continuous))])

    def gradient(change) -> np.ndarray:
        f = np.array([float(weights @ objective.rss(r + change)) for r in records])
        return (f[1::2] - f[0::2]) / np.where(steps > 0, steps, 1.0)

    g0 = gradient(0.0)
    total = np.zeros_like(fit.curvature)
    for changes in change_sets:
        moves = np.array([-0.5 * fit.curvature @ (gradient(d) - g0) for d in changes])
        total += moves.T @ moves / len(moves)
    return total


def widened(effect: Effect, ctx: Context, base: ModelState, fit: EffectFit,
            extra: np.ndarray) -> dict:
    """The fit's intervals with the covariance ``extra`` (k, k; search variables, e.g.
    :func:`field_spread`) added to its own."""
    space = [p for p in effect.space(ctx, base) if not p.integer]
    x = np.array([_to_x(p, float(fit.parameters[p.name])) for p in space])
    return interval_map(space, x, fit.widening * fit.curvature + extra)


def linearisation_spread(effect: Effect, ctx: Context, base: ModelState, first: dict,
                         refit: dict) -> np.ndarray:
    """Covariance (k, k; search variables of the continuous parameters) of the move between
    two fits of one effect under the same data and two linearisations of the field
    model's uncertainty: ``first`` with the modes taken at the baseline's record, ``refit``
    with those of its own fitted record.

    Both likelihoods hold the field model's errors to first order about a record, and an
    effect that moves the pulse moves the shapes those errors take; the exact likelihood's
    optimum is not known better than the two linear ones agree, so their difference d
    enters as the outer product d d^T (one standard deviation of that size)."""
    space = [p for p in effect.space(ctx, base) if not p.integer]
    d = np.array([_to_x(p, float(refit[p.name])) - _to_x(p, float(first[p.name]))
                  for p in space])
    return np.outer(d, d)


def recentred(effect: Effect, ctx: Context, base: ModelState, intervals: dict,
              old: dict, new: dict) -> dict:
    """``intervals`` of a fit at ``old`` moved to ``new`` (a joint refit's values) by the
    same shift in each search variable, clipped to the searched range."""
    out = {}
    for p in effect.space(ctx, base):
        if p.name not in intervals:
            continue
        shift = _to_x(p, float(new[p.name])) - _to_x(p, float(old[p.name]))
        lo, hi = (_to_x(p, v) for v in intervals[p.name])
        out[p.name] = (_from_x(p, lo + shift), _from_x(p, hi + shift))
    return out


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

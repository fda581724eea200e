"""Which effect: fit every candidate of the library, score it and name one (steps 5-6 of
:mod:`msens.diagnose.workflow`)."""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping, Sequence

import numpy as np
from tqdm import tqdm

from msens.diagnose.diagnosis import Candidate
from msens.diagnose.effects import Context, Effect, ModelState, registry
from msens.diagnose.effects import get as get_effect
from msens.diagnose.fit import Z_LEVEL, EffectFit, _to_x, fit_effect
from msens.diagnose.predict import Predictor
from msens.errors import InputError
from msens.progress import heartbeat

_log = logging.getLogger(__name__)

#: Smallest BIC drop (score) for naming an effect; see :mod:`msens.diagnose.workflow`.
THRESHOLD = 10.0


def with_added(ctx: Context, state: ModelState,
                added: Sequence[tuple[str, Mapping[str, float]]]) -> ModelState:
    for name, params in added:
        state = get_effect(name).apply(ctx, state, params)
    return state


def candidate_effects(ctx: Context, names: Sequence[str] | None,
                       added: Sequence[tuple[str, Mapping]]) -> list[Effect]:
    lib = registry()
    if names is not None:
        unknown = [n for n in names if n not in lib]
        if unknown:
            raise InputError(f"unknown effect(s) {', '.join(unknown)}; known: {', '.join(lib)}")
    done = {n for n, _ in added}
    return [e for n, e in lib.items()
            if (names is None or n in names) and n not in done and e.applies(ctx)]


def fit_candidates(effects: Sequence[Effect], ctx: Context, base: ModelState,
                    predictor: Predictor, objective, weights: np.ndarray) -> list[EffectFit]:
    """:func:`fit_effect` of every candidate, with a progress bar (the slow step)."""
    _log.info("fitting %d candidate effects: %s", len(effects),
              ", ".join(e.name for e in effects))
    fits = []
    with tqdm(effects, desc="candidate effects", unit=" effect", leave=False,
              disable=not _log.isEnabledFor(logging.INFO)) as bar:
        for i, e in enumerate(bar):
            bar.set_postfix_str(e.name)
            # a line per candidate and a heartbeat while it fits (some take minutes)
            with heartbeat(_log, f"candidate {i + 1}/{len(effects)} {e.name}"):
                start = time.perf_counter()
                fits.append(fit_effect(e, ctx, base, predictor, objective, weights))
            _log.info("candidate %d/%d %s fitted in %.1f s", i + 1, len(effects), e.name,
                      time.perf_counter() - start)
    return fits


def log_decision(cands: list[Candidate], winner: Candidate | None, threshold: float) -> None:
    if winner is not None:
        _log.info("decision: %s (score %.1f > threshold %g)", winner.effect, winner.score,
                  threshold)
    elif cands:
        _log.info("decision: none (best %s scores %.1f <= threshold %g)", cands[0].effect,
                  cands[0].score, threshold)
    else:
        _log.info("decision: none (no candidate effect applies)")


def judge(effect: Effect, ctx: Context, base: ModelState, params: Mapping[str, float]
          ) -> tuple[bool, bool, tuple[str, ...]]:
    """(plausible, significant, notes) of an effect's fitted parameters.

    Plausible: every parameter inside its physical range. Significant: some parameter with
    a baseline value moved from it by at least its floor (an effect whose parameters have no
    baseline value, e.g. another law, is significant).
    """
    space = effect.space(ctx, base)
    ref = effect.baseline(ctx, base)
    notes = []
    plausible = True
    for p in space:
        v = float(params[p.name])
        if not p.is_plausible(v):
            plausible = False
            lo, hi = p.physical
            notes.append(f"implausible: {p.name} = {v:.4g} outside its physical range "
                         f"[{lo:.4g}, {hi:.4g}] ({p.reason})")
    moves = [(p, float(params[p.name]) - float(ref[p.name])) for p in space
             if ref.get(p.name) is not None]
    significant = not moves or any(abs(d) > 0 and abs(d) >= p.floor for p, d in moves)
    if not significant:
        notes.append("below the practical-significance floor: " + "; ".join(
            f"{p.name} changed by {d:+.3g} < {p.floor:.3g} ({p.floor_reason})"
            for p, d in moves))
    return plausible, significant, tuple(notes)


def bound_notes(effect: Effect, ctx: Context, base: ModelState, params: Mapping[str, float],
                at_bound: Sequence[str]) -> tuple[str, ...]:
    """Why a fit at an end of its searched range is not named, one note per parameter."""
    space = {p.name: p for p in effect.space(ctx, base)}
    out = []
    for name in at_bound:
        p = space[name]
        v = float(params[name])
        lo, hi = p.physical
        edges = [(abs(v - p.lower), "lower", "searched", p.lower, p.upper),
                 (abs(v - p.upper), "upper", "searched", p.lower, p.upper),
                 (abs(v - lo), "lower", "physical", lo, hi),
                 (abs(v - hi), "upper", "physical", lo, hi)]
        _, end, kind, a, b = min(edges, key=lambda e: e[0])
        out.append(f"at bound: {name} = {v:.4g} at the {end} end of its {kind} range "
                   f"[{a:.4g}, {b:.4g}]: the {'search' if kind == 'searched' else 'limit'}, "
                   "not the data, stopped it")
    return tuple(out)


def score_candidates(fits: list[EffectFit], rss0: np.ndarray, n_obs: np.ndarray, ctx: Context,
                     base: ModelState) -> tuple[list[Candidate], float]:
    # rss are chi^2 already (residuals over the fit-free noise), per sensor
    n = float(n_obs.sum())
    chi0 = float(rss0.sum())
    cands = []
    for f in fits:
        effect = get_effect(f.effect)
        chi = float(f.rss.sum())
        plausible, significant, notes = judge(effect, ctx, base, f.parameters)
        notes += bound_notes(effect, ctx, base, f.parameters, f.at_bound)
        cands.append(Candidate(
            effect=f.effect, parameters=f.parameters,
            baseline=effect.baseline(ctx, base), chi2=chi, misfit=chi / n,
            score=chi0 - chi - f.n_parameters * np.log(n), n_parameters=f.n_parameters,
            plausible=plausible, significant=significant, notes=notes,
            intervals=dict(f.intervals), at_bound=tuple(f.at_bound)))
    cands.sort(key=lambda c: -c.score)
    return cands, chi0 / n


def decide(cands: list[Candidate], fits: list[EffectFit], threshold: float
           ) -> tuple[Candidate | None, EffectFit | None]:
    """The best-scoring candidate that is plausible, significant and not at a bound of its
    search, and whose score beats by ``threshold`` both the baseline and every plausible
    change below its floor (when a negligible change explains the data better, nothing
    practical is missing), and that scores above every fit pinned at a bound (when an
    effect pushed to the end of its searched range fits better, the data want something
    the library does not hold, and a lesser effect is not the answer)."""
    negligible = max((c.score for c in cands if c.plausible and not c.significant),
                     default=0.0)
    pinned = max((c.score for c in cands if c.at_bound and c.significant), default=-np.inf)
    for c in cands:
        if c.nameable and c.score - max(negligible, 0.0) > threshold and c.score > pinned:
            return c, next(f for f in fits if f.effect == c.effect)
    return None, None


def floor_evidence(effect: Effect, ctx: Context, base: ModelState, params: Mapping[str, float],
                   intervals: Mapping[str, tuple[float, float]]) -> tuple[float, str]:
    """How strongly the named change is beyond its practical-significance floor, under the
    uncertainty of its reported intervals.

    For each parameter with a baseline value, a floor > 0, a reported interval and a fitted
    change beyond its floor: the chi^2 rise from the fit to the floor's edge (the
    negligible change of the same kind nearest the fit), in the quadratic approximation the
    interval stands for, ``(Z dx / h)^2``, with dx the distance from the fit to the edge
    and h the interval's half-width on the edge's side (in the search variable: log10 for
    scale parameters; ``Z`` the interval's normal quantile). On a physics MsS the intervals
    hold the field model's errors and the residual's discrepancy, so this is the evidence
    against a negligible change once the model's own uncertainty is counted; the raw
    chi^2 of the fit counts noise only.

    Returns
    -------
    (float, str)
        The largest rise over those parameters (inf when none has an interval: nothing to
        weigh) and a sentence on it.
    """
    ref = effect.baseline(ctx, base)
    rises = []
    for p in effect.space(ctx, base):
        b, iv = ref.get(p.name), intervals.get(p.name)
        v = float(params[p.name])
        if b is None or p.floor <= 0.0 or iv is None or abs(v - b) < p.floor:
            continue
        edge = b + p.floor if v > b else b - p.floor
        end = iv[0] if v > b else iv[1]
        if p.log and (edge <= 0.0 or end <= 0.0):
            continue  # the floor's edge or the interval reaches zero: no log distance
        x, h = _to_x(p, v), abs(_to_x(p, v) - _to_x(p, end))
        rise = np.inf if h == 0.0 else float((Z_LEVEL * (x - _to_x(p, edge)) / h) ** 2)
        reason = f" ({p.floor_reason})" if p.floor_reason else ""
        rises.append((rise, f"{p.name} = {v:.4g} (interval [{iv[0]:.4g}, {iv[1]:.4g}]) "
                            f"against the floor's edge {edge:.4g}{reason}"))
    return max(rises, key=lambda r: r[0], default=(np.inf, ""))


def demoted(c: Candidate, rise: float, why: str, threshold: float) -> Candidate:
    """``c`` as a negligible change: a named fit whose floor's edge lies within the model's
    uncertainty (:func:`floor_evidence` at most ``threshold``) is not significant, and, as
    every negligible change does, its score then blocks the lesser candidates."""
    note = (f"within the model's uncertainty of its floor: chi^2 rise {rise:.3g} <= "
            f"{threshold:g} from the fit to the floor's edge, {why}")
    return dataclasses.replace(c, significant=False, near_floor=True,
                               notes=(*c.notes, note))


def settle(cands: list[Candidate], winner: Candidate | None, ctx: Context, base: ModelState,
           threshold: float) -> tuple[list[Candidate], bool]:
    """(candidates, whether the decision stands): the winner, with its final parameters
    and intervals, must be beyond its practical-significance floor by the threshold's
    evidence once the model's uncertainty is counted (:func:`floor_evidence`); otherwise
    it is :func:`demoted` in the candidates and the caller decides again."""
    if winner is None:
        return cands, True
    rise, why = floor_evidence(get_effect(winner.effect), ctx, base, winner.parameters,
                               winner.intervals)
    if rise > threshold:
        return cands, True
    _log.info("%s not named: its fit is within the model's uncertainty of its floor "
              "(chi^2 rise %.3g <= %g to the floor's edge, %s)", winner.effect, rise,
              threshold, why)
    return [demoted(c, rise, why, threshold) if c.effect == winner.effect else c
            for c in cands], False

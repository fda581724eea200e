"""The discrepancy workflow: where do model and measurement disagree, and which missing
effect closes the gap?

Steps (issue 7):

1. *Baseline.* The study's model of the setup whose sensors match the data, with the contact
   and wall dissipation calibrated by paper Eq. 10 on the study's own amplitude ratios
   (``[calibration.dissipation]``; otherwise the study's gamma values). gamma_c is *not*
   re-fitted to the data under diagnosis: a free gamma_c would absorb the dissipative effects
   the workflow is meant to tell apart. Effects named in ``added`` (earlier passes) are
   applied on top.
2. *Calibration of the record.* One impact-to-trigger offset and per channel one gain
   (paper Eq. 11) and offset, profiled out of every comparison
   (:class:`~msens.diagnose.objective.WaveformObjective`; the starting offset comes from
   :func:`msens.compare.align_shot`).
3. *Where.* Feature residuals (TOF, AR, width, incident-peak time, pre-peak trough, speed
   between the sensors; from :func:`msens.compare.shot_records`) and the residual per time
   window (incident and reflected pulse of each sensor, and the rest) as chi^2 per sample.
4. *Noise.* Estimated before any fit (:mod:`msens.diagnose.noise`): the shots of the file
   are aligned and averaged, and each sample of the mean carries the variance of the
   shot-to-shot scatter (never below the pre-trigger noise) over the number of shots, or the
   pre-trigger noise for one shot. Residuals are measured against it (chi^2). Flooring the
   noise by the best candidate's residual would make every winner look like noise; it is
   not done.
5. *Which.* Every applicable effect of the library is fitted (batched grid + bounded
   refinement, :func:`~msens.diagnose.fit.fit_effect`) and scored by the drop of the Bayesian
   information criterion against the baseline,
   ``score = chi2_baseline - chi2_effect - k ln N``, with k the effect's parameter count and
   N the number of samples.
6. *Decision.* The best-scoring effect is named only when its score exceeds ``THRESHOLD`` =
   10 ("very strong" evidence on the Kass & Raftery (1995) scale of 2 ln B; with the BIC
   penalty already subtracted), its parameters lie inside their physical ranges (a fit
   outside is reported as implausible) and its change from the baseline reaches the
   effect's practical-significance floor (:class:`~msens.diagnose.effects.base.Parameter`).
   Otherwise the next candidate is considered, and ``"none"`` if none qualifies. A candidate
   must also beat by the threshold every plausible change below its floor: when a negligible
   change (say a striker 0.5 % faster) fits better than a significant one, nothing practical
   is missing.
7. *Verdict.* Whether the final model explains the data: its residual against the noise, for
   the record and for each window, by an F test (:mod:`msens.diagnose.verdict`);
   ``explained`` false says that the named effect (or the baseline) still misses, and where.
8. *Gap.* The named effect is added, the model rerun, and the misfit (chi^2 per sample)
   before and after reported. In later passes (``added`` not empty) the parameters of the
   earlier effects and the new one are first refined together, since each earlier fit
   absorbed part of the effects not yet named.

A feature-only mode (:func:`diagnose_reference`) takes a study's ``[reference]`` rows (e.g. the
paper's Table 2: TOF and AR per sensor, with their shot-to-shot std) as the measurement;
chi^2 is the sum of squared residuals over the published std and N the number of features.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from tqdm import tqdm

from msens.calibrate import DissipationFit
from msens.compare import model_record, setup_spec_channels, shot_records, smooth
from msens.config.schema import SetupSpec
from msens.config.study import Study
from msens.diagnose.effects import Context, Effect, ModelState, registry
from msens.diagnose.effects import get as get_effect
from msens.diagnose.fit import EffectFit, fit_effect, refit_jointly
from msens.diagnose.noise import shot_matrix
from msens.diagnose.objective import FeatureObjective, WaveformObjective, check_channels
from msens.diagnose.predict import (
    Predictor,
    baseline_state,
    feature_records,
    model_features_of,
    positions,
    setup_result,
)
from msens.diagnose.shots import fit_shots
from msens.diagnose.verdict import verdict
from msens.errors import InputError
from msens.io.waveform import Waveform
from msens.pipeline import calibrate_dissipation, output_times
from msens.signals.features import centre_distance

_log = logging.getLogger(__name__)

#: Smallest BIC drop (score) for naming an effect; see the module docstring.
THRESHOLD = 10.0
#: Half-width of the incident / reflected windows, in incident pulse widths (FWHM).
WINDOW_WIDTHS = 1.5


@dataclass(frozen=True)
class Candidate:
    """One fitted effect and its evidence.

    Attributes
    ----------
    effect : str
    parameters : dict
        Fitted values, SI.
    baseline : dict
        The parameters' baseline values (None where the baseline is another law).
    chi2 : float
        Weighted residual sum at the optimum.
    misfit : float
        chi2 per observation.
    score : float
        BIC drop against the baseline (> 0 favours the effect).
    n_parameters : int
    plausible : bool
        Every fitted parameter inside its physical range.
    significant : bool
        The change from the baseline reaches the effect's practical-significance floor.
    notes : tuple of str
        Why the candidate is implausible or below its floor (empty otherwise).
    """

    effect: str
    parameters: dict
    baseline: dict
    chi2: float
    misfit: float
    score: float
    n_parameters: int
    plausible: bool = True
    significant: bool = True
    notes: tuple[str, ...] = ()

    def to_json(self) -> dict:
        """The candidate's entry in ``diagnosis.json``."""
        return {"effect": self.effect, "misfit": self.misfit, "score": self.score,
                "parameters": self.parameters, "baseline": self.baseline,
                "n_parameters": self.n_parameters, "plausible": self.plausible,
                "significant": self.significant, "notes": list(self.notes)}


@dataclass(frozen=True)
class Diagnosis:
    """Result of one diagnosis pass.

    Attributes
    ----------
    mode : {"waveform", "features"}
    setup : str
    effect : str
        Named effect or ``"none"``.
    parameters : dict
        Its fitted parameters (empty for none).
    misfit_before, misfit_after : float
        chi^2 per observation of the baseline and of the model with the named effect.
    candidates : tuple of Candidate
        Sorted by score, best first.
    threshold : float
    n_obs : int
    sigma : tuple of float
        Noise std per sensor used in chi^2 (V or V for MsS voltage; 1 in feature mode).
    added : tuple of (str, dict)
        Effects already in the baseline (earlier passes).
    refit : tuple of (str, dict)
        When ``added`` is not empty and an effect is named: the added effects and the new one
        with their parameters refined together (:func:`~msens.diagnose.fit.refit_jointly`);
        ``misfit_after`` is that model's.
    gamma_contact, gamma_wall : float
        Baseline dissipation (Eq. 10 or the study's).
    disagreement : dict
        Where the baseline misses: features and windows (see :func:`diagnose`).
    simulations : int
    elapsed_s : float
    verdict : dict
        Whether the final model (the named effect, or the baseline for none) explains the
        data: ``explained`` and the residual/noise test per window
        (:func:`msens.diagnose.verdict.verdict`).
    noise : dict
        The noise estimate, independent of every fit (waveform mode; empty for features).
    before, after : ModelState
        The baseline and the model with the named effect (== before for none).
    overlay : list of dict
        Per sensor, for the figure: ``channel``, ``t_us`` (record time), ``data``,
        ``before``, ``after`` (V; the shots' mean), or for features mode the feature table.
    """

    mode: str
    setup: str
    effect: str
    parameters: dict
    misfit_before: float
    misfit_after: float
    candidates: tuple[Candidate, ...]
    threshold: float
    n_obs: int
    sigma: tuple[float, ...]
    added: tuple[tuple[str, dict], ...]
    refit: tuple[tuple[str, dict], ...]
    gamma_contact: float
    gamma_wall: float
    disagreement: dict
    simulations: int
    elapsed_s: float
    verdict: dict
    noise: dict
    before: ModelState = field(repr=False)
    after: ModelState = field(repr=False)
    overlay: list = field(repr=False, default_factory=list)

    @property
    def explained(self) -> bool:
        """Whether the final model's residual is consistent with the noise."""
        return bool(self.verdict["explained"])

    def summary(self) -> str:
        """One sentence: what is named and whether it explains the data."""
        where = self.verdict.get("unexplained_where")
        at = (f"; the residual is {where['residual_over_noise']:.2g} x the noise at the "
              f"{where['window']} window of {where['channel']}" if where else "")
        if self.effect == "none":
            if self.explained:
                return "nothing is missing: the model explains the data within the noise"
            return "no plausible library effect explains the data" + at
        if self.explained:
            return f"{self.effect} explains the data within the noise"
        return f"{self.effect} is supported but does not explain the data" + at

    def to_json(self) -> dict:
        """The content of ``diagnosis.json``."""
        return {
            "effect": self.effect,
            "parameters": self.parameters,
            "explained": self.explained,
            "summary": self.summary(),
            "misfit_before": self.misfit_before,
            "misfit_after": self.misfit_after,
            "verdict": self.verdict,
            "noise": self.noise,
            "candidates": [c.to_json() for c in self.candidates],
            "mode": self.mode,
            "setup": self.setup,
            "threshold_delta_bic": self.threshold,
            "misfit_definition": "chi^2 per observation: squared residuals over the noise "
                                 "variance estimated without any fit (waveform: per sample "
                                 "of the shots' mean, gain, offset and time offset profiled "
                                 "out; features: over the published std)",
            "score_definition": "BIC(baseline) - BIC(effect) = chi2_0 - chi2 - k ln N",
            "naming_rule": "the best-scoring candidate whose parameters are inside their "
                           "physical ranges, whose change reaches the effect's "
                           "practical-significance floor, and whose score exceeds the "
                           "threshold and the best plausible below-floor candidate's score "
                           "by the threshold",
            "n_observations": self.n_obs,
            "sigma": list(self.sigma),
            "baseline": {"gamma_contact": self.gamma_contact,
                         "gamma_wall": self.gamma_wall,
                         "added_effects": [{"effect": n, "parameters": p}
                                           for n, p in self.added]},
            "joint_refit": [{"effect": n, "parameters": p} for n, p in self.refit],
            "disagreement": self.disagreement,
            "simulations": self.simulations,
        }


# ------------------------------------------------------------------------ baseline

def match_setup_spec(study: Study, waveform: Waveform) -> SetupSpec:
    """The setup whose sensors are exactly the data's channels (kind and particle)."""
    wanted = {(c.kind, c.particle) for c in waveform.channels}
    names = []
    for s in study.setups:
        have = setup_spec_channels(s)
        if have == wanted:
            return s
        names.append(f"{s.name} ({', '.join(sorted(f'{k}@{p}' for k, p in have))})")
    data = ", ".join(sorted(f"{k}@{p}" for k, p in wanted))
    raise InputError(f"the study {study.name!r} does not match the data's sensors: data has "
                     f"{data}; study setups: {'; '.join(names)}")


def baseline_dissipation(study: Study, fit: DissipationFit | None = None) -> tuple[float, float]:
    """(gamma_c, gamma_w) of the baseline: ``fit``, else Eq. 10 if the study asks, else the
    study's values."""
    if fit is None:
        fit = calibrate_dissipation(study, output_times(study))
    if fit is not None:
        return fit.gamma_c, fit.gamma_w
    return study.chain.gamma_contact, study.chain.gamma_wall


def _with_added(ctx: Context, state: ModelState,
                added: Sequence[tuple[str, Mapping[str, float]]]) -> ModelState:
    for name, params in added:
        state = get_effect(name).apply(ctx, state, params)
    return state


def _candidate_effects(ctx: Context, names: Sequence[str] | None,
                       added: Sequence[tuple[str, Mapping]]) -> list[Effect]:
    lib = registry()
    if names is not None:
        unknown = [n for n in names if n not in lib]
        if unknown:
            raise InputError(f"unknown effect(s) {', '.join(unknown)}; known: {', '.join(lib)}")
    done = {n for n, _ in added}
    return [e for n, e in lib.items()
            if (names is None or n in names) and n not in done and e.applies(ctx)]


def _fit_candidates(effects: Sequence[Effect], ctx: Context, base: ModelState,
                    predictor: Predictor, objective, weights: np.ndarray) -> list[EffectFit]:
    """:func:`fit_effect` of every candidate, with a progress bar (the slow step)."""
    _log.info("fitting %d candidate effects: %s", len(effects),
              ", ".join(e.name for e in effects))
    fits = []
    with tqdm(effects, desc="candidate effects", unit=" effect", leave=False,
              disable=not _log.isEnabledFor(logging.INFO)) as bar:
        for e in bar:
            bar.set_postfix_str(e.name)
            fits.append(fit_effect(e, ctx, base, predictor, objective, weights))
    return fits


def _log_decision(cands: list[Candidate], winner: Candidate | None, threshold: float) -> None:
    if winner is not None:
        _log.info("decision: %s (score %.1f > threshold %g)", winner.effect, winner.score,
                  threshold)
    elif cands:
        _log.info("decision: none (best %s scores %.1f <= threshold %g)", cands[0].effect,
                  cands[0].score, threshold)
    else:
        _log.info("decision: none (no candidate effect applies)")


# ------------------------------------------------------------------------ scoring

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


def _score(fits: list[EffectFit], rss0: np.ndarray, n_obs: np.ndarray, ctx: Context,
           base: ModelState) -> tuple[list[Candidate], float]:
    # rss are chi^2 already (residuals over the fit-free noise), per sensor
    n = float(n_obs.sum())
    chi0 = float(rss0.sum())
    cands = []
    for f in fits:
        effect = get_effect(f.effect)
        chi = float(f.rss.sum())
        plausible, significant, notes = judge(effect, ctx, base, f.parameters)
        cands.append(Candidate(
            effect=f.effect, parameters=f.parameters,
            baseline=effect.baseline(ctx, base), chi2=chi, misfit=chi / n,
            score=chi0 - chi - f.n_parameters * np.log(n), n_parameters=f.n_parameters,
            plausible=plausible, significant=significant, notes=notes))
    cands.sort(key=lambda c: -c.score)
    return cands, chi0 / n


def _decide(cands: list[Candidate], fits: list[EffectFit], threshold: float
            ) -> tuple[Candidate | None, EffectFit | None]:
    """The best-scoring candidate that is plausible and significant and whose score beats
    by ``threshold`` both the baseline and every plausible change below its floor (when a
    negligible change explains the data better, nothing practical is missing)."""
    negligible = max((c.score for c in cands if c.plausible and not c.significant),
                     default=0.0)
    for c in cands:
        if c.plausible and c.significant and c.score - max(negligible, 0.0) > threshold:
            return c, next(f for f in fits if f.effect == c.effect)
    return None, None


# ------------------------------------------------------------------------ where

def _trough(force: np.ndarray, t: np.ndarray, t_inc: float, width: float,
            peak: float) -> float:
    """Deepest pre-peak excursion below zero within 2 widths before the incident peak,
    as a fraction of the incident peak (0 when there is none)."""
    m = (t >= t_inc - 2 * width) & (t <= t_inc) & np.isfinite(force)
    if not m.any() or not np.isfinite(peak) or peak == 0:
        return float("nan")
    return float(min(0.0, np.min(force[m])) / peak)


def _features(force: np.ndarray, t: np.ndarray) -> dict[str, float]:
    force = np.where(np.isfinite(force), force, 0.0)  # outside the record: at rest
    f = model_features_of(force, t)
    sm = smooth(force, float(t[1] - t[0]))
    return {"t_incident_us": float(f.t_incident) * 1e6, "tof_us": float(f.tof) * 1e6,
            "ar": float(f.ar), "width_us": float(f.width) * 1e6,
            "trough": _trough(sm, t, float(f.t_incident), float(f.width), float(f.f_incident))}


def _feature_residuals(result, waveform: Waveform) -> dict:
    """Measured (mean over shots) against baseline model features per channel, and speed."""
    t = result.history.t
    shots = shot_records(result, waveform)
    out: dict = {"channels": []}
    t_inc: dict[str, tuple[float, float, int]] = {}
    for sensor in result.sensors:
        name = f"{sensor.sensor.kind.value}@{sensor.sensor.particle}"
        recs = [r for shot in shots for r in shot
                if (r.channel.kind, r.channel.particle)
                == (sensor.sensor.kind.value, sensor.sensor.particle)]
        meas = [_features(r.force, t) for r in recs]
        model = _features(model_record(sensor, t), t)
        row = {"channel": name}
        for k in model:
            vals = np.array([m[k] for m in meas])
            row[k] = {"measured": float(np.mean(vals)), "model": model[k],
                      "residual": float(np.mean(vals) - model[k]),
                      "std": float(np.std(vals, ddof=1)) if vals.size > 1 else 0.0}
        out["channels"].append(row)
        t_inc[name] = (row["t_incident_us"]["measured"], model["t_incident_us"],
                       sensor.sensor.particle)
    if len(t_inc) >= 2:
        (a, b) = sorted(t_inc.values(), key=lambda x: x[2])[::len(t_inc) - 1]
        d = centre_distance(result.chain.length, a[2], b[2])
        meas_v = d / ((b[0] - a[0]) * 1e-6)
        model_v = d / ((b[1] - a[1]) * 1e-6)
        out["speed_m_per_s"] = {"measured": meas_v, "model": model_v,
                                "residual": meas_v - model_v}
    return out


def _windows(objective: WaveformObjective, records_before: np.ndarray,
             records_after: np.ndarray, result) -> list[dict]:
    """chi^2 per sample (residual over the fit-free noise) in the incident and reflected
    window of each sensor, and elsewhere, before and after."""
    feats = model_features_of(feature_records(records_before, objective.physics, objective.t),
                              objective.t)
    rows = []
    per = [objective.aligned(r) for r in (records_before, records_after)]
    for j, sensor in enumerate(result.sensors):
        name = f"{sensor.sensor.kind.value}@{sensor.sensor.particle}"
        w = WINDOW_WIDTHS * float(feats.width[j])
        spans = {"incident": (float(feats.t_incident[j]) - w, float(feats.t_incident[j]) + w),
                 "reflected": (float(feats.t_reflected[j]) - w,
                               float(feats.t_reflected[j]) + w)}
        # windows are in model time of the baseline alignment, the same samples after
        masks = []
        for _, tm, _ in per[0]:
            inside = {k: (tm >= lo) & (tm <= hi) for k, (lo, hi) in spans.items()}
            inside["elsewhere"] = ~(inside["incident"] | inside["reflected"])
            masks.append(inside)
        for window in ("incident", "reflected", "elsewhere"):
            vals, count = [], 0
            for aligned in per:
                num = 0.0
                count = 0
                for shot, (_, _, m), mk in zip(objective.shots, aligned, masks, strict=True):
                    sel = mk[window]
                    r = (shot.y[j] - m[j])[sel]
                    num += float(np.sum(shot.w[j][sel] * r**2))
                    count += r.size
                vals.append(num / count if count else float("nan"))
            if count:
                rows.append({"channel": name, "window": window, "n_samples": count,
                             "chi2_per_sample_before": vals[0],
                             "chi2_per_sample_after": vals[1]})
    return rows


def _where(windows: list[dict]) -> str:
    worst = max(windows, key=lambda r: r["chi2_per_sample_before"])
    return f"{worst['window']} pulse at {worst['channel']}" if worst["window"] != "elsewhere" \
        else f"outside the pulses at {worst['channel']}"


# ------------------------------------------------------------------------ workflows

def diagnose(waveform: Waveform, study: Study, *, fit: DissipationFit | None = None,
             added: Sequence[tuple[str, Mapping[str, float]]] = (),
             effects: Sequence[str] | None = None, threshold: float = THRESHOLD) -> Diagnosis:
    """Find the missing effect behind the misfit of a measured waveform.

    Parameters
    ----------
    waveform : Waveform
        Measured channels (one or more shots); they select the study's setup.
    study : Study
    fit : DissipationFit, optional
        An Eq. 10 calibration already made (skips it; it costs ~130 chain runs).
    added : sequence of (effect name, parameters)
        Effects already in the baseline (from earlier passes).
    effects : sequence of str, optional
        Candidate effect names (default: every applicable effect of the library).
    threshold : float
        Smallest BIC drop that names an effect.

    Returns
    -------
    Diagnosis

    Raises
    ------
    InputError
        No setup of the study matches the data's sensors; a channel has no usable pulse.
    """
    start = time.perf_counter()
    setup = match_setup_spec(study, waveform)
    check_channels(waveform)
    shot_matrix(waveform, [(s.kind.value, s.particle) for s in setup.sensors])  # fail early
    ctx = Context(study, setup)
    gc, gw = baseline_dissipation(study, fit)
    _log.info("diagnosis of setup %s: baseline model (gamma_c = %.3g kg/s, gamma_w = %.3g "
              "kg/s%s)", setup.name, gc, gw,
              "".join(f", + {n}" for n, _ in added))
    predictor = Predictor(output_times(study))
    plain = baseline_state(ctx, gc, gw)
    base = _with_added(ctx, plain, added)
    base_result = setup_result(ctx, base, predictor)
    shifts, per_shot = None, None
    if len({c.repeat for c in waveform.channels}) > 1:
        # each shot's own speed and delay: align the shots on their impact, and average
        # every model over the shots' spread of speeds as the data are
        per_shot = fit_shots(waveform, base, base_result, predictor)
        shifts = np.round((per_shot.delays[0] - per_shot.delays) / waveform.dt).astype(int)
        plain = dataclasses.replace(plain, velocity_spread=per_shot.spread)
        base = _with_added(ctx, plain, added)
        _log.info("%d shots: striker speed spread %.2g %%", len(per_shot.speeds),
                  100 * per_shot.spread)
    objective = WaveformObjective(waveform, base_result, shifts)
    records0 = predictor.records([base])[0]
    rss0 = objective.rss(records0)
    weights = np.ones(len(rss0))  # rss is chi^2: already over the noise
    fits = _fit_candidates(_candidate_effects(ctx, effects, added), ctx, base, predictor,
                           objective, weights)
    cands, misfit0 = _score(fits, rss0, objective.n_obs, ctx, base)
    winner, wfit = _decide(cands, fits, threshold)
    _log_decision(cands, winner, threshold)
    after = wfit.state if wfit is not None else base
    refit: tuple[tuple[str, dict], ...] = ()
    if wfit is not None and added:
        named = [(get_effect(n), dict(p)) for n, p in added] + \
            [(get_effect(wfit.effect), dict(wfit.parameters))]
        params, after, _ = refit_jointly(named, ctx, plain, predictor, objective, weights)
        refit = tuple((e.name, p) for (e, _), p in zip(named, params, strict=True))
        winner = dataclasses.replace(winner, parameters=params[-1])
    records1 = predictor.records([after])[0]  # rerun with the effect added
    rss1 = objective.rss(records1)
    n = float(objective.n_obs.sum())
    windows = _windows(objective, records0, records1, base_result)
    ens = objective.ensemble
    names = [f"{s.kind.value}@{s.particle}" for s in setup.sensors]
    disagreement = {"where": _where(windows), "windows": windows,
                    "features": _feature_residuals(base_result, waveform)}
    return Diagnosis(
        mode="waveform", setup=setup.name, effect=winner.effect if winner else "none",
        parameters=dict(winner.parameters) if winner else {},
        misfit_before=misfit0, misfit_after=float(rss1.sum()) / n,
        candidates=tuple(cands), threshold=threshold, n_obs=int(n),
        sigma=tuple(float(np.sqrt(np.mean(1.0 / w))) for w in objective.shots[0].w),
        added=tuple((k, dict(v)) for k, v in added),
        refit=refit, gamma_contact=gc, gamma_wall=gw, disagreement=disagreement,
        simulations=predictor.simulations, elapsed_s=time.perf_counter() - start,
        verdict=verdict(float(rss1.sum()), n, windows, ens.dof),
        noise={**ens.to_json(names), **(per_shot.to_json() if per_shot else {})},
        before=base, after=after, overlay=_overlay(objective, records0, records1, base_result))


def _overlay(objective: WaveformObjective, records0: np.ndarray, records1: np.ndarray,
             result) -> list[dict]:
    shot = objective.shots[0]
    (_, _, m0), (_, _, m1) = objective.aligned(records0)[0], objective.aligned(records1)[0]
    return [{"channel": f"{s.sensor.kind.value}@{s.sensor.particle}",
             "t_us": shot.tau * 1e6, "data": shot.y[j], "before": m0[j], "after": m1[j]}
            for j, s in enumerate(result.sensors)]


def diagnose_passes(waveform: Waveform, study: Study, *, passes: int = 2,
                    fit: DissipationFit | None = None, **kw) -> list[Diagnosis]:
    """Repeated diagnosis: each pass adds the previous winner to the baseline; stops at
    ``"none"`` or after ``passes`` passes."""
    if fit is None and study.dissipation_fit is not None:
        fit = calibrate_dissipation(study, output_times(study))
    out: list[Diagnosis] = []
    added: list[tuple[str, dict]] = []
    for _ in range(passes):
        d = diagnose(waveform, study, fit=fit, added=tuple(added), **kw)
        out.append(d)
        # "explained" is a consistency test, weaker than the evidence a second effect can
        # still have: the passes go on until nothing is named
        if d.effect == "none":
            break
        added = list(d.refit) if d.refit else [*added, (d.effect, d.parameters)]
    return out


def diagnose_reference(study: Study, setup_name: str, *, fit: DissipationFit | None = None,
                       added: Sequence[tuple[str, Mapping[str, float]]] = (),
                       effects: Sequence[str] | None = None,
                       threshold: float = THRESHOLD) -> Diagnosis:
    """Feature-only diagnosis against the study's ``[reference]`` rows of one setup.

    Parameters
    ----------
    study : Study
        With ``[reference]`` rows (e.g. the paper's Table 2) for ``setup_name``.
    setup_name : str
    fit, added, effects, threshold
        As in :func:`diagnose`.

    Returns
    -------
    Diagnosis
        ``mode = "features"``; ``disagreement`` lists each feature's normalised residual.
    """
    start = time.perf_counter()
    names = [s.name for s in study.setups]
    if setup_name not in names:
        raise InputError(f"setup must be one of {', '.join(names)}, got {setup_name!r}")
    setup = study.setup(setup_name)
    ctx = Context(study, setup)
    rows = {r.position: r for r in study.reference if r.setup == setup_name}
    if not rows:
        raise InputError(f"the study {study.name!r} has no [reference] rows for setup "
                         f"{setup_name!r}")
    gc, gw = baseline_dissipation(study, fit)
    _log.info("feature diagnosis of setup %s: baseline model (gamma_c = %.3g kg/s, gamma_w = "
              "%.3g kg/s%s)", setup.name, gc, gw, "".join(f", + {n}" for n, _ in added))
    predictor = Predictor(output_times(study))
    base = _with_added(ctx, baseline_state(ctx, gc, gw), added)
    where = positions([s.particle for s in setup.sensors])
    objective = FeatureObjective(setup, rows, where, predictor.t)
    records0 = predictor.records([base])[0]
    rss0 = objective.rss(records0)
    weights = np.ones(len(where))
    fits = _fit_candidates(_candidate_effects(ctx, effects, added), ctx, base, predictor,
                           objective, weights)
    cands, misfit0 = _score(fits, rss0, objective.n_obs, ctx, base)
    winner, wfit = _decide(cands, fits, threshold)
    _log_decision(cands, winner, threshold)
    after = wfit.state if wfit is not None else base
    records1 = predictor.records([after])[0]
    n = float(objective.n_obs.sum())
    table = _feature_table(objective, records0, records1, setup, where)
    worst = max(table, key=lambda r: abs(r["residual_before"]))
    # each feature is one window; the published std is taken as known (dof infinite)
    rows = [{"channel": r["channel"], "window": r["feature"], "n_samples": 1,
             "chi2_per_sample_before": r["residual_before"] ** 2,
             "chi2_per_sample_after": r["residual_after"] ** 2} for r in table]
    return Diagnosis(
        mode="features", setup=setup.name, effect=winner.effect if winner else "none",
        parameters=dict(winner.parameters) if winner else {},
        misfit_before=misfit0, misfit_after=float(objective.rss(records1).sum()) / n,
        candidates=tuple(cands), threshold=threshold, n_obs=int(n),
        sigma=tuple(float(s) for s in objective.sigma),
        added=tuple((k, dict(v)) for k, v in added),
        refit=(), gamma_contact=gc, gamma_wall=gw,
        disagreement={"where": f"{worst['feature']} at {worst['channel']}",
                      "features": table},
        simulations=predictor.simulations, elapsed_s=time.perf_counter() - start,
        verdict=verdict(float(objective.rss(records1).sum()), n, rows, float("inf")),
        noise={"source": "the published shot-to-shot std of each feature"},
        before=base, after=after, overlay=table)


def _feature_table(objective: FeatureObjective, records0: np.ndarray, records1: np.ndarray,
                   setup: SetupSpec, where: list[str]) -> list[dict]:
    f0, f1 = (model_features_of(feature_records(r, objective.physics, objective.t),
                                objective.t) for r in (records0, records1))
    r0, r1 = objective.residuals(records0), objective.residuals(records1)
    out = []
    for j, (s, pos, row) in enumerate(zip(setup.sensors, where, objective.rows, strict=True)):
        name = f"{s.kind.value}@{s.particle} ({pos})"
        out.append({"channel": name, "feature": "tof_us", "measured": row.tof_us,
                    "std": row.tof_std_us, "model_before": float(f0.tof[j]) * 1e6,
                    "model_after": float(f1.tof[j]) * 1e6, "residual_before": float(r0[j, 0]),
                    "residual_after": float(r1[j, 0])})
        out.append({"channel": name, "feature": "ar", "measured": row.ar, "std": row.ar_std,
                    "model_before": float(f0.ar[j]), "model_after": float(f1.ar[j]),
                    "residual_before": float(r0[j, 1]), "residual_after": float(r1[j, 1])})
    return out

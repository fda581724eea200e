"""The discrepancy workflow: where do model and measurement disagree, and which missing
effect closes the gap?

Steps:

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
   On a physics MsS each coil's inductance (with eddy currents its impedance) is then
   profiled as a nonlinear nuisance of the baseline (:mod:`msens.diagnose.inductance`: the
   read-out's resonance moves by about its width for a few per cent of error), and the
   likelihood's field-model modes are taken at the profiled baseline.
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
   On a physics MsS (first pass) the named effect is then fitted again under the
   likelihood of its own fitted record (the field model's modes taken there, not at the
   baseline), and its intervals widened by the spread of that fit over joint draws of the
   field model's errors and of the discrepancy its residual shows beyond the likelihood's
   variance (:func:`_named_refit`, :mod:`msens.diagnose.discrepancy`).
   The named effect must then be beyond its floor by the threshold's evidence under those
   final intervals (:func:`~msens.diagnose.candidates.floor_evidence`): the raw chi^2
   counts the noise only, and a fit 8 % from the baseline with a 5 % floor can be decisive
   against the noise and yet within the field model's errors of the floor. Otherwise it is
   demoted to a negligible change and the decision is made again
   (:func:`~msens.diagnose.candidates.settle`).
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

import numpy as np

from msens.calibrate import DissipationFit
from msens.compare import model_processing, setup_spec_channels
from msens.config.schema import SetupSpec
from msens.config.study import Study
from msens.diagnose import discrepancy, inductance
from msens.diagnose.candidates import (
    THRESHOLD,
    candidate_effects,
    decide,
    fit_candidates,
    log_decision,
    score_candidates,
    settle,
    with_added,
)
from msens.diagnose.diagnosis import Candidate, Diagnosis
from msens.diagnose.effects import Context
from msens.diagnose.effects import get as get_effect
from msens.diagnose.effects.base import ModelState
from msens.diagnose.field_modes import field_draws, record_modes
from msens.diagnose.fit import (
    EffectFit,
    field_spread,
    fit_effect,
    linearisation_spread,
    recentred,
    refit_jointly,
    widened,
)
from msens.diagnose.likelihood import variance_split
from msens.diagnose.noise import shot_matrix
from msens.diagnose.objective import FeatureObjective, WaveformObjective, check_channels
from msens.diagnose.predict import (
    Predictor,
    baseline_state,
    positions,
    same_run,
    setup_result,
)
from msens.diagnose.shots import ShotFits, fit_shots
from msens.diagnose.verdict import verdict
from msens.diagnose.where import feature_residuals, feature_table, window_residuals, worst_window
from msens.errors import InputError
from msens.io.waveform import Waveform
from msens.parallel import one_blas_thread
from msens.pipeline import calibrate_dissipation, output_times
from msens.progress import heartbeat
from msens.results import SetupResult
from msens.synth import GAIN_CONVENTION, GAIN_KEY, gain_unit

__all__ = [
    "THRESHOLD",
    "Candidate",
    "Diagnosis",
    "WaveformBaseline",
    "baseline_dissipation",
    "diagnose",
    "diagnose_passes",
    "diagnose_reference",
    "match_setup_spec",
    "waveform_baseline",
]

_log = logging.getLogger(__name__)


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


@dataclasses.dataclass(frozen=True)
class WaveformBaseline:
    """The study's model of a measured file and the likelihood it is judged by: what
    ``diagnose`` starts from and ``calibrate`` samples with.

    Attributes
    ----------
    ctx : Context
        The study and the setup whose sensors are the data's channels.
    gamma_contact, gamma_wall : float
        The baseline's dissipation, kg/s (Eq. 10 fit, or the study's values).
    predictor : Predictor
    plain : ModelState
        The baseline without ``added`` effects (with the shots' speed spread).
    base : ModelState
        The baseline with ``added`` effects.
    result : SetupResult
        The baseline's run (without the speed spread).
    per_shot : ShotFits or None
        Each shot's own striker speed and delay (two or more shots).
    objective : WaveformObjective
        The data's ensemble and its likelihood (noise and model uncertainty; the model
        variance fixed from ``records``).
    records : ndarray, shape (sensors, nt)
        The baseline's records (forces in N; a physics MsS its DAQ voltage in V).
    """

    ctx: Context
    gamma_contact: float
    gamma_wall: float
    predictor: Predictor
    plain: ModelState
    base: ModelState
    result: SetupResult
    per_shot: ShotFits | None
    objective: WaveformObjective
    records: np.ndarray


def waveform_baseline(waveform: Waveform, study: Study, *, fit: DissipationFit | None = None,
                      added: Sequence[tuple[str, Mapping[str, float]]] = ()
                      ) -> WaveformBaseline:
    """Baseline model and likelihood of a measured file (steps 1, 2 and 4 of the module
    docstring).

    Parameters
    ----------
    waveform : Waveform
        Measured channels (one or more shots); they select the study's setup.
    study : Study
    fit : DissipationFit, optional
        An Eq. 10 calibration already made.
    added : sequence of (effect name, parameters)
        Effects already in the baseline.

    Returns
    -------
    WaveformBaseline

    Raises
    ------
    InputError
        No setup of the study matches the data's sensors; a channel has no usable pulse.
    """
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
    base = with_added(ctx, plain, added)
    base_result = setup_result(ctx, base, predictor)
    per_shot = None
    if len({c.repeat for c in waveform.channels}) > 1:
        # each shot's own speed and delay: align the shots on their impact, and average
        # every model over the shots' spread of speeds as the data are
        per_shot = fit_shots(waveform, base, base_result, predictor)
        plain = dataclasses.replace(plain, velocity_spread=per_shot.spread)
        base = with_added(ctx, plain, added)
        _log.info("%d shots: striker speed spread %.2g %%", len(per_shot.speeds),
                  100 * per_shot.spread)
    records0 = predictor.records([base])[0]
    objective = objective_at(waveform, base_result, per_shot, predictor, base, records0)
    return WaveformBaseline(ctx=ctx, gamma_contact=gc, gamma_wall=gw, predictor=predictor,
                            plain=plain, base=base, result=base_result, per_shot=per_shot,
                            objective=objective, records=records0)


def objective_at(waveform: Waveform, result: SetupResult, per_shot: ShotFits | None,
                 predictor: Predictor, state: ModelState, records: np.ndarray
                 ) -> WaveformObjective:
    """The likelihood of a measured file with its model uncertainty taken at ``state``.

    Parameters
    ----------
    waveform : Waveform
    result : SetupResult
        The baseline's run (its only use: the starting time offset).
    per_shot : ShotFits or None
        The shots' own delays (two or more shots).
    predictor : Predictor
    state : ModelState
        The model whose field-model modes and diagonal variance the likelihood holds.
    records : ndarray, shape (sensors, nt)
        ``state``'s records.

    Returns
    -------
    WaveformObjective
    """
    shifts = None if per_shot is None else \
        np.round((per_shot.delays[0] - per_shot.delays) / waveform.dt).astype(int)
    objective = WaveformObjective(waveform, result, shifts)
    # the likelihood's variance: the noise and the model's own uncertainty (physics MsS)
    _log.info("field-model modes of the records (each contact, the circuit, each bead's "
              "pull; ~60 chain runs)")
    with heartbeat(_log, "field-model modes"):
        modes = record_modes(state, predictor)
    objective.add_model_uncertainty(records, modes)
    return objective


# ------------------------------------------------------------------------ workflows

@one_blas_thread()
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
    b = waveform_baseline(waveform, study, fit=fit, added=added)
    if any(m is not None for m in b.objective.field_modes):
        b = _with_inductance(waveform, b)
    ctx, predictor, plain, base = b.ctx, b.predictor, b.plain, b.base
    setup, gc, gw, per_shot = ctx.setup, b.gamma_contact, b.gamma_wall, b.per_shot
    base_result, objective, records0 = b.result, b.objective, b.records
    rss0 = objective.rss(records0)
    weights = np.ones(len(rss0))  # rss is chi^2: already over the noise
    fits = fit_candidates(candidate_effects(ctx, effects, added), ctx, base, predictor,
                           objective, weights)
    cands, misfit0 = score_candidates(fits, rss0, objective.n_obs, ctx, base)
    discrepancies: list = []
    while True:
        winner, wfit = decide(cands, fits, threshold)
        objective, discrepancies = b.objective, []
        if wfit is not None and not added and any(m is not None
                                                  for m in objective.field_modes):
            winner, wfit, objective, discrepancies = _named_refit(waveform, b, winner, wfit,
                                                                  weights)
        cands, settled = settle(cands, winner, ctx, base, threshold)
        if settled:
            break
    log_decision(cands, winner, threshold)
    after = wfit.state if wfit is not None else base
    refit: tuple[tuple[str, dict], ...] = ()
    if wfit is not None and added:
        named = [(get_effect(n), dict(p)) for n, p in added] + \
            [(get_effect(wfit.effect), dict(wfit.parameters))]
        params, after, _ = refit_jointly(named, ctx, plain, predictor, objective, weights)
        refit = tuple((e.name, p) for (e, _), p in zip(named, params, strict=True))
        winner = dataclasses.replace(
            winner, parameters=params[-1],
            intervals=recentred(get_effect(wfit.effect), ctx, base, winner.intervals,
                                winner.parameters, params[-1]))
    records1 = predictor.records([after])[0]  # rerun with the effect added
    rss1 = objective.rss(records1)
    n = float(objective.n_obs.sum())
    windows = window_residuals(objective, records0, records1, base_result)
    ens = objective.ensemble
    names = [f"{s.kind.value}@{s.particle}" for s in setup.sensors]
    disagreement = {"where": worst_window(windows), "windows": windows,
                    "features": feature_residuals(base_result, waveform),
                    "model_processing": model_processing()}
    return Diagnosis(
        mode="waveform", setup=setup.name, effect=winner.effect if winner else "none",
        parameters=dict(winner.parameters) if winner else {},
        intervals=dict(winner.intervals) if winner else {},
        misfit_before=misfit0, misfit_after=float(rss1.sum()) / n,
        candidates=tuple(cands), threshold=threshold, n_obs=int(n),
        sigma=tuple(float(np.sqrt(np.mean(1.0 / w))) for w in objective.shots[0].w),
        added=tuple((k, dict(v)) for k, v in added),
        refit=refit, gamma_contact=gc, gamma_wall=gw, disagreement=disagreement,
        simulations=predictor.simulations, elapsed_s=time.perf_counter() - start,
        verdict=verdict(float(rss1.sum()), n, windows, ens.dof),
        noise={**ens.to_json(names), **(per_shot.to_json() if per_shot else {}),
               "model_uncertainty": _model_uncertainty_json(objective, names),
               **({"discrepancy": _discrepancy_json(discrepancies, names)}
                  if discrepancies else {}),
               **({"coil_inductance": _inductance_json(after, names)}
                  if any(f is not None for f in inductance.factors(after)) else {})},
        before=base, after=after, overlay=_overlay(objective, records0, records1, base_result),
        calibration=_calibration(objective, records1, base_result, names))


def _with_inductance(waveform: Waveform, b: WaveformBaseline) -> WaveformBaseline:
    """The baseline with each coil's inductance profiled (:mod:`msens.diagnose.inductance`)
    and the likelihood's model uncertainty taken there; unchanged when every factor stays
    1 or ends at the end of its search (not an error within the field model's accuracy)."""
    with heartbeat(_log, "the coils' inductance profiled"):
        base = inductance.profile(b.base, b.predictor,
                                  b.objective.without_modes(inductance.MODES))
    found = inductance.factors(base)
    _log.info("the coils' inductance profiled: factors %s of the field model's",
              ", ".join(f"{f:.4f}" for f in found if f is not None))
    if all(f in (None, 1.0) for f in found):
        return b
    records = b.predictor.records([base])[0]
    objective = objective_at(waveform, b.result, b.per_shot, b.predictor, base, records)
    return dataclasses.replace(b, plain=inductance.with_factors(b.plain, found),
                               base=base, objective=objective, records=records)


def _named_refit(waveform: Waveform, b: WaveformBaseline, winner: Candidate,
                 wfit: EffectFit, weights: np.ndarray
                 ) -> tuple[Candidate, EffectFit, WaveformObjective]:
    """The named effect refitted with the field-model modes taken at its own fit, and its
    intervals widened by joint draws of the field model's errors.

    The candidates are compared under one likelihood, the baseline's; but the modes are
    shapes of the baseline's record, and an effect that moves the pulse (a stiffer wall,
    stronger magnets) moves the shapes the field model's errors take with it. So the
    named effect is fitted again with the modes (and the diagonal model variance) of its
    own fitted record, near its first fit (:func:`~msens.diagnose.fit.fit_effect`'s
    ``near``: the first fit's integer parameters, a few grid points on either side of its
    continuous ones), and that likelihood judges the final model. Its intervals then add
    to the curvature's the spread of the optimum over :data:`~msens.diagnose.field_modes.
    BOOTSTRAP_DRAWS` joint draws of every field-model quantity (:func:`~msens.diagnose.
    field_modes.field_draws`, :func:`~msens.diagnose.fit.field_spread`): the pull's effect
    is not linear near lightly loaded contacts, its errors and the sensitivities' combine,
    and the modes hold only their linear parts and a few draws. They also add the spread
    over draws of the discrepancy the refit's residual shows beyond the likelihood's
    variance (:mod:`msens.diagnose.discrepancy`; this replaces the reduced chi^2's
    widening), and the move between the first fit and the refit
    (:func:`~msens.diagnose.fit.linearisation_spread`: the two linearisations of the field
    model's uncertainty bracket the exact likelihood's optimum). A refit that ends at a
    bound of its search keeps the first fit.

    Returns
    -------
    (winner, fit, objective, discrepancies)
        ``discrepancies``: per channel, the discrepancy the refit leaves
        (:mod:`msens.diagnose.discrepancy`; empty without a refit or a curvature).
    """
    ctx, predictor = b.ctx, b.predictor
    effect = get_effect(wfit.effect)
    if same_run(wfit.state, b.base) and any(
            f is not None and f != 1.0 for f in inductance.factors(b.base)):
        b, wfit = _readout_inductance(b, effect, wfit, weights)
        winner = dataclasses.replace(winner, parameters=dict(wfit.parameters),
                                     intervals=dict(wfit.intervals))
    _log.info("refit of %s with the model uncertainty of its own fitted record", effect.name)
    obj = objective_at(waveform, b.result, b.per_shot, predictor, wfit.state,
                       predictor.records([wfit.state])[0])
    with heartbeat(_log, f"refit of {effect.name}"):
        fit = fit_effect(effect, ctx, b.base, predictor, obj, weights,
                         near=dict(wfit.parameters))
    if fit.at_bound:
        _log.info("the refit of %s ends at a bound (%s): the first fit is kept",
                  effect.name, ", ".join(fit.at_bound))
        return winner, wfit, b.objective, []
    intervals = dict(fit.intervals)
    if fit.curvature is None:
        return (dataclasses.replace(winner, parameters=dict(fit.parameters),
                                    intervals=intervals), fit, obj, [])
    with heartbeat(_log, f"{effect.name}: draws of the field model's errors and the "
                         "residual's discrepancy"):
        changes = field_draws(fit.state, predictor)
        draws, estimates = discrepancy.model_changes(obj, predictor.records([fit.state])[0])
        sets = [c for c in (changes, draws) if c is not None and np.any(c)]
        _log.info("%s: its intervals over %d draws of the field model's errors and %d of "
                  "the residual's discrepancy (%s of its power)", effect.name,
                  0 if changes is None else len(changes), len(draws),
                  ", ".join(f"{100 * e.share:.0f} %" for e in estimates))
        extra = (field_spread(effect, ctx, b.base, predictor, obj, weights, fit, *sets)
                 if sets else np.zeros_like(fit.curvature))
    extra = extra + linearisation_spread(effect, ctx, b.base, wfit.parameters, fit.parameters)
    # the discrepancy's draws hold the misfit beyond the likelihood's variance, which the
    # curvature's widening by the reduced chi^2 would count again
    intervals = widened(effect, ctx, b.base, dataclasses.replace(fit, widening=1.0), extra)
    return (dataclasses.replace(winner, parameters=dict(fit.parameters), intervals=intervals),
            fit, obj, estimates)


def _readout_inductance(b: WaveformBaseline, effect, wfit: EffectFit, weights: np.ndarray
                        ) -> tuple[WaveformBaseline, EffectFit]:
    """An effect of the read-out alone (the cable's capacitance, the DAQ's filter) trades
    off against the coils' inductance: both move the read-out's resonance, so the baseline's
    profiled inductance takes up part of such an effect and biases its fit. The effect is
    fitted again on the baseline with the field model's inductance, and of the two the one
    with the lower chi^2 plus the inductance factors' prior (the likelihood without the
    linear inductance modes, :mod:`msens.diagnose.inductance`) is kept, with its baseline."""
    free = b.objective.without_modes(inductance.MODES)
    nominal = inductance.with_factors(b.base, tuple(
        None if f is None else 1.0 for f in inductance.factors(b.base)))
    with heartbeat(_log, f"{effect.name} on the field model's inductance"):
        other = fit_effect(effect, b.ctx, nominal, b.predictor, free, weights,
                           near=dict(wfit.parameters))
    crit = [inductance.criterion(free, r, s)
            for r, s in zip(b.predictor.records([wfit.state, other.state]),
                            (wfit.state, other.state), strict=True)]
    _log.info("%s of the read-out: criterion %.1f with the profiled inductance, %.1f with "
              "the field model's", effect.name, *crit)
    if other.at_bound or crit[1] >= crit[0]:
        return b, wfit
    plain = inductance.with_factors(b.plain, inductance.factors(nominal))
    return dataclasses.replace(b, base=nominal, plain=plain), other


def _inductance_json(state: ModelState, names: list[str]) -> dict:
    """Each coil's profiled inductance factor in the final model
    (:mod:`msens.diagnose.inductance`)."""
    return {"definition": "each coil's inductance (with eddy currents its impedance beyond "
                          "the copper) over the field model's, profiled as a nuisance with "
                          f"a Gaussian prior of {inductance.FIELD_ACCURACY:.0%} and searched "
                          f"within +-{inductance.SPAN * inductance.FIELD_ACCURACY:.0%} of 1 "
                          "(an optimum at the end of the search is set back to 1)",
            "factors": {n: f for n, f in zip(names, inductance.factors(state), strict=True)
                        if f is not None}}


def _discrepancy_json(estimates: list, names: list[str]) -> dict:
    """The named fit's residual split into what the likelihood expects and the discrepancy
    beyond it (:mod:`msens.diagnose.discrepancy`)."""
    return {"definition": "the named effect's final residual: the part of its power above "
                          "the level the likelihood's variance gives white residuals "
                          "(noise and diagonal model variance), and that part's rms; its "
                          "draws widen the named parameters' intervals",
            "channels": [{"channel": n, **e.to_json()}
                         for n, e in zip(names, estimates, strict=True)]}


def _model_uncertainty_json(objective: WaveformObjective, names: list[str]) -> dict:
    """The model's own uncertainty in the likelihood: its sizes per channel and its share
    of the variance the residuals are measured against."""
    shot = objective.shots[0]
    per = []
    for j, (n, u) in enumerate(zip(names, objective.model_uncertainty, strict=True)):
        split = (variance_split(shot.noise_var[j], shot.model_var[j])
                 if shot.model_var is not None else variance_split(1.0 / shot.w[j], 0.0))
        modes = (objective.field_modes[j] if j < len(objective.field_modes) else None)
        per.append({"channel": n, **u.to_json(), **split,
                    "field_model_modes": modes.to_json() if modes is not None else None})
    return {"definition": "variance per sample added to the noise's: (a m)^2 + (r t dm/dt)^2 "
                          "of the baseline model's record m (a: relative_amplitude, r: "
                          "relative_timing, t: time since impact); shares: of the summed "
                          "variance over the record. Field-model modes (physics MsS): the "
                          "record's change for a 1-std error of each field-model quantity "
                          "(contact sensitivities, R, L, winding C, magnets' pull), whose "
                          "amplitudes every fit profiles with a unit Gaussian prior",
            **objective.variance_split(), "channels": per}


def _calibration(objective: WaveformObjective, records: np.ndarray, result,
                 names: list[str]) -> dict:
    """The gain, offset and delay profiled out of the fit of ``records`` (the final model),
    in the one gain convention of msens (measured = gain x model)."""
    a = objective.aligned(records)[0][0]
    return {"convention": f"{GAIN_CONVENTION} (as synth's truth_gain_* and compare's "
                          f"{GAIN_KEY})",
            "delay_s": float(a.delay),
            "channels": [{"channel": n, GAIN_KEY: float(g), f"{GAIN_KEY}_unit": gain_unit(s),
                          "offset_V": float(b)}
                         for n, g, b, s in zip(names, a.gains, a.offsets, result.sensors,
                                               strict=True)]}


def _overlay(objective: WaveformObjective, records0: np.ndarray, records1: np.ndarray,
             result) -> list[dict]:
    shot = objective.shots[0]
    # on the time since striker impact (record time + each model's fitted trigger delay),
    # the time axis of every other figure
    (_, t0, m0), (_, t1, m1) = objective.aligned(records0)[0], objective.aligned(records1)[0]
    return [{"channel": f"{s.sensor.kind.value}@{s.sensor.particle}",
             "t_us": t0 * 1e6, "t_after_us": t1 * 1e6, "data": shot.y[j], "before": m0[j],
             "after": m1[j]}
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
    base = with_added(ctx, baseline_state(ctx, gc, gw), added)
    where = positions([s.particle for s in setup.sensors])
    objective = FeatureObjective(setup, rows, where, predictor.t)
    records0 = predictor.records([base])[0]
    rss0 = objective.rss(records0)
    weights = np.ones(len(where))
    fits = fit_candidates(candidate_effects(ctx, effects, added), ctx, base, predictor,
                           objective, weights)
    cands, misfit0 = score_candidates(fits, rss0, objective.n_obs, ctx, base)
    while True:
        winner, wfit = decide(cands, fits, threshold)
        cands, settled = settle(cands, winner, ctx, base, threshold)
        if settled:
            break
    log_decision(cands, winner, threshold)
    after = wfit.state if wfit is not None else base
    records1 = predictor.records([after])[0]
    n = float(objective.n_obs.sum())
    table = feature_table(objective, records0, records1, setup, where)
    worst = max(table, key=lambda r: abs(r["residual_before"]))
    # each feature is one window; the published std is taken as known (dof infinite)
    rows = [{"channel": r["channel"], "window": r["feature"], "n_samples": 1,
             "chi2_per_sample_before": r["residual_before"] ** 2,
             "chi2_per_sample_after": r["residual_after"] ** 2} for r in table]
    return Diagnosis(
        mode="features", setup=setup.name, effect=winner.effect if winner else "none",
        parameters=dict(winner.parameters) if winner else {},
        intervals=dict(winner.intervals) if winner else {},
        misfit_before=misfit0, misfit_after=float(objective.rss(records1).sum()) / n,
        candidates=tuple(cands), threshold=threshold, n_obs=int(n),
        sigma=tuple(float(s) for s in objective.sigma),
        added=tuple((k, dict(v)) for k, v in added),
        refit=(), gamma_contact=gc, gamma_wall=gw,
        disagreement={"where": f"{worst['feature']} at {worst['channel']}",
                      "features": table, "model_processing": model_processing()},
        simulations=predictor.simulations, elapsed_s=time.perf_counter() - start,
        verdict=verdict(float(objective.rss(records1).sum()), n, rows, float("inf")),
        noise={"source": "the published shot-to-shot std of each feature"},
        before=base, after=after, overlay=table)

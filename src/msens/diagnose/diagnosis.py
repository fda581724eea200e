"""The result of a diagnosis: each fitted candidate effect and the diagnosis of one pass."""

from __future__ import annotations

from dataclasses import dataclass, field

from msens.diagnose.effects import ModelState


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
        Why the candidate is implausible, below its floor or at a bound (empty otherwise).
    intervals : dict
        Per continuous parameter, its 95 % interval (lower, upper), SI, from the curvature
        of the fit (:func:`msens.diagnose.fit.curvature_covariance`).
    at_bound : tuple of str
        Parameters whose fit is at an end of their searched range: the candidate is not
        named (the search, not the data, stopped it).
    near_floor : bool
        Beyond its floor, but not by the threshold's evidence under its final intervals
        (:func:`msens.diagnose.candidates.floor_evidence`): not significant, a negligible
        change.
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
    intervals: dict = field(default_factory=dict)
    at_bound: tuple[str, ...] = ()
    near_floor: bool = False

    @property
    def nameable(self) -> bool:
        """Plausible, significant and not at a bound of its search."""
        return self.plausible and self.significant and not self.at_bound

    def to_json(self) -> dict:
        """The candidate's entry in ``diagnosis.json``."""
        return {"effect": self.effect, "misfit": self.misfit, "score": self.score,
                "parameters": self.parameters, "baseline": self.baseline,
                "intervals": intervals_json(self.parameters, self.intervals, self.at_bound),
                "at_bound": bool(self.at_bound),
                "n_parameters": self.n_parameters, "plausible": self.plausible,
                "significant": self.significant, "near_floor": self.near_floor,
                "notes": list(self.notes)}


#: What the reported intervals are.
INTERVAL_DEFINITION = ("95 % interval of each continuous parameter from the curvature of "
                       "the fit's chi^2 at its optimum (covariance 2 H^-1 of a finite-"
                       "difference Hessian in the search variables, log10 for scale "
                       "parameters; widened by the reduced chi^2 when it exceeds 1; the "
                       "likelihood's variance holds the noise and the model's own "
                       "uncertainty); for a named effect on a physics MsS, refitted with "
                       "the field-model modes of its own fitted record and widened by the "
                       "spread of the optimum over joint draws of the field model's "
                       "errors and of the discrepancy its residual shows (in place of the "
                       "reduced chi^2's widening), and by the move from the first fit (the "
                       "field model's uncertainty linearised at the baseline) to the refit; "
                       "clipped to the searched range; integer "
                       "parameters "
                       "have none. at_bound: the optimum is within 0.5 % of the searched "
                       "span from one of its ends, or from an end of its physical range "
                       "inside it")


def intervals_json(parameters: dict, intervals: dict, at_bound: tuple[str, ...]) -> dict:
    """``{name: {"value", "lower", "upper", "at_bound"}}`` of the fitted parameters
    (``lower``/``upper`` None for integer parameters)."""
    out = {}
    for k, v in parameters.items():
        lo, hi = intervals.get(k, (None, None))
        out[k] = {"value": v, "lower": lo, "upper": hi, "at_bound": k in at_bound}
    return out


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
        Per sensor, for the figure: ``channel``, ``t_us`` (µs since striker impact: the
        record time plus the baseline's fitted trigger delay), ``t_after_us`` (the same with
        the corrected model's delay), ``data``, ``before``, ``after`` (V; the shots' mean),
        or for features mode the feature table.
    calibration : dict
        Waveform mode: the record calibration profiled out of the final model's fit, per
        channel: ``gain_measured_per_model`` (measured = gain x model, synth's and
        compare's convention) with its unit, DC offset (V) and the impact-to-trigger delay
        (s). Empty in feature mode.
    intervals : dict
        The named parameters' 95 % intervals (lower, upper), SI (after a joint refit, the
        single fit's interval moved to the refined value); empty: those of the named
        candidate.
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
    calibration: dict = field(default_factory=dict)
    intervals: dict = field(default_factory=dict)

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
            closest = self.closest_at_bound()
            near = ""
            if closest is not None:
                pinned = ", ".join(f"{k} = {closest.parameters[k]:.4g}"
                                   for k in closest.at_bound)
                near = (f"; the closest, {closest.effect}, has its fit at the bound of its "
                        f"searched range ({pinned})")
            if self.explained:
                return ("nothing is missing: the model explains the data within the noise"
                        + near)
            return "no plausible library effect explains the data" + at + near
        if self.explained:
            return f"{self.effect} explains the data within the noise"
        return f"{self.effect} is supported but does not explain the data" + at

    def closest_at_bound(self) -> Candidate | None:
        """With no effect named: the best-scoring candidate that would have been named but
        for a fit at a bound of its search (None otherwise)."""
        if self.effect != "none":
            return None
        return next((c for c in self.candidates if c.significant and c.at_bound
                     and c.score > self.threshold), None)

    def named_candidate(self) -> Candidate | None:
        """The candidate of the named effect (None for none)."""
        return next((c for c in self.candidates if c.effect == self.effect), None)

    def to_json(self) -> dict:
        """The content of ``diagnosis.json``."""
        named = self.named_candidate()
        closest = self.closest_at_bound()
        return {
            "effect": self.effect,
            "parameters": self.parameters,
            "parameter_intervals": intervals_json(
                self.parameters, self.intervals or (named.intervals if named else {}), ()),
            "interval_definition": INTERVAL_DEFINITION,
            "closest_at_bound": None if closest is None else {
                "effect": closest.effect, "score": closest.score,
                "parameters": intervals_json(closest.parameters, closest.intervals,
                                             closest.at_bound)},
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
                           "physical ranges and not at a bound of their searched ranges, "
                           "that scores above every fit at a bound, "
                           "whose change reaches the effect's "
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
            **({"record_calibration": self.calibration} if self.calibration else {}),
            "simulations": self.simulations,
        }

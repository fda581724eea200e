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
        Per sensor, for the figure: ``channel``, ``t_us`` (µs since striker impact: the
        record time plus the baseline's fitted trigger delay), ``t_after_us`` (the same with
        the corrected model's delay), ``data``, ``before``, ``after`` (V; the shots' mean),
        or for features mode the feature table.
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

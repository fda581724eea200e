"""Is the data explained? The residual of a model against a noise level that no fit touched.

A residual is consistent with the noise when its chi^2 per sample (residual squares over the
noise variance of each sample, :mod:`msens.diagnose.noise`) stays below the ``1 - alpha``
quantile of the F distribution F(n, dof): n residual samples against a noise variance that was
itself estimated with ``dof`` degrees of freedom (the pre-trigger samples, or the shots'
scatter). With a published std (feature mode) the noise is taken as known (dof infinite: the
chi^2 quantile over n). The whole record and every window (incident and reflected pulse of each
sensor, the rest) are tested, with ``alpha`` shared among them (Bonferroni): the data are
explained only when every one of them passes. The gain, offset and time shift fitted per
channel take a handful of the thousands of degrees of freedom and are neglected.
"""

from __future__ import annotations

import numpy as np
from scipy import stats

#: False-alarm probability of the whole test (an explained data set called unexplained).
ALPHA = 1e-3


def consistency_limit(n: float, dof: float, alpha: float) -> float:
    """Largest chi^2 per sample of ``n`` residuals consistent with the noise.

    Parameters
    ----------
    n : float
        Residual samples (> 0).
    dof : float
        Degrees of freedom of the noise-variance estimate (inf: known).
    alpha : float
        Probability that noise alone exceeds the limit.

    Returns
    -------
    float
        The ``1 - alpha`` quantile of F(n, dof) (of chi^2(n) / n for a known variance).
    """
    if not np.isfinite(dof):
        return float(stats.chi2.ppf(1.0 - alpha, n) / n)
    return float(stats.f.ppf(1.0 - alpha, n, dof))


def verdict(chi2: float, n: float, windows: list[dict], dof: float,
            alpha: float = ALPHA) -> dict:
    """Whether a residual is consistent with the noise, overall and window by window.

    Parameters
    ----------
    chi2, n : float
        chi^2 and samples of the whole residual.
    windows : list of dict
        Each with ``channel``, ``window``, ``n_samples`` and ``chi2_per_sample_after`` (the
        model under test). Returned with ``limit``, ``residual_over_noise`` (RMS residual
        over RMS noise) and ``consistent`` added.
    dof : float
        Degrees of freedom of the noise estimate.
    alpha : float

    Returns
    -------
    dict
        ``explained``, ``chi2_per_sample``, ``limit``, ``residual_over_noise``, ``alpha``,
        ``dof``, ``test``, ``windows`` and, when not explained, ``unexplained_where`` (the
        window furthest above its limit).
    """
    tests = 1 + len(windows)
    a = alpha / tests
    limit = consistency_limit(n, dof, a)
    rows = []
    for w in windows:
        x = float(w["chi2_per_sample_after"])
        lim = consistency_limit(max(float(w["n_samples"]), 1.0), dof, a)
        rows.append({**w, "limit": lim, "residual_over_noise": float(np.sqrt(max(x, 0.0))),
                     "consistent": bool(x <= lim)})
    overall = chi2 / n
    explained = bool(overall <= limit and all(r["consistent"] for r in rows))
    out = {"explained": explained, "chi2_per_sample": overall, "limit": limit,
           "residual_over_noise": float(np.sqrt(max(overall, 0.0))), "alpha": alpha,
           "dof": dof,
           "test": f"chi^2 per sample <= 1 - alpha/{tests} quantile of F(n, dof) for the "
                   f"record and each of its {len(windows)} windows (alpha = {alpha:g})",
           "windows": rows}
    if not explained:
        worst = max(rows, key=lambda r: r["chi2_per_sample_after"] / r["limit"]) if rows \
            else None
        if worst is not None and not worst["consistent"]:
            out["unexplained_where"] = {
                "channel": worst["channel"], "window": worst["window"],
                "residual_over_noise": worst["residual_over_noise"]}
        else:
            out["unexplained_where"] = {"channel": "all", "window": "whole record",
                                        "residual_over_noise": out["residual_over_noise"]}
    return out

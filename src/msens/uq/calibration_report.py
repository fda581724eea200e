"""What a calibration reports: ``calibration.json``, a text table and three figures.

- :func:`to_json` — per calibrated input its prior (distribution, reason, source), posterior
  mean, std, median, 5/95 % quantiles and 90 % credible interval, the best sample and its
  convergence (split R-hat, autocorrelation time, effective sample size); the sampler's
  settings and acceptance; the likelihood (what it measures against, chi^2 at the best
  sample); the inputs held at nominal; the posterior predictive (every setup's feature
  bands, each ``[reference]`` row inside its band or not; the waveform band, thinned).
- :func:`format_table` — the posterior and the convergence verdict, for the terminal.
- :func:`pairs_figure` — the posterior's marginals and pairwise scatter, prior range marked.
- :func:`predictive_figure` — the measurement with the calibrated model's 5-95 % band.
- :func:`trace_figure` — every walker's path per input, burn-in shaded.
"""

from __future__ import annotations

import numpy as np

from msens.uq.mcmc import RHAT_LIMIT
from msens.uq.report import feature_label
from msens.vocabulary import TIME_LABEL, channel_name

#: Quantiles of the posterior summaries.
QUANTILES = (0.05, 0.5, 0.95)
#: Waveform samples kept in the JSON per channel (every k-th).
WAVEFORM_POINTS = 2500


def _finite(x) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def _band(y: np.ndarray) -> list[float | None]:
    y = y[np.isfinite(y)]
    return [_finite(v) for v in np.quantile(y, QUANTILES)] if y.size else [None] * 3


def to_json(cal, inputs, *, provenance: dict) -> dict:
    """The content of ``calibration.json``.

    Parameters
    ----------
    cal : Calibration
    inputs : InputSet
        The study's uncertain inputs (the held ones are listed).
    provenance : dict
    """
    c = cal.coords
    best = c.values(cal.chains.best()[None])[0]
    posterior = []
    for j, p in enumerate(c.inputs):
        x = cal.samples[:, j]
        q = np.quantile(x, QUANTILES)
        posterior.append({
            **{k: v for k, v in p.to_json().items()
               if k in ("name", "unit", "description", "distribution", "parameters",
                        "support", "nominal", "reason", "source")},
            "posterior_mean": float(np.mean(x)), "posterior_std": float(np.std(x, ddof=1)),
            "posterior_5_50_95": [float(v) for v in q],
            "credible_interval_90": [float(q[0]), float(q[2])],
            "best_sample": float(best[j]),
            "prior_std": float(c.scale[j]),
            "shrinkage": float(1.0 - np.std(x, ddof=1) / c.scale[j]),
            "rhat": _finite(cal.rhat[j]), "autocorr_time_steps": _finite(cal.tau[j]),
            "effective_samples": _finite(cal.ess[j])})
    held = [p.name for p in inputs.propagated if p.name not in c.names] + \
        [p.name for p in inputs.held]
    walkers, steps = cal.chains.z.shape[1], cal.chains.z.shape[0]
    out = {
        "mode": cal.mode, "setup": cal.setup, "measurement": cal.measurement,
        "inputs": posterior,
        "held_at_nominal": held,
        "correlation": np.corrcoef(cal.samples.T).tolist() if len(c.names) > 1 else [[1.0]],
        "convergence": {
            "converged": cal.converged, "rhat_limit": RHAT_LIMIT,
            "rhat_definition": "split R-hat over the walkers' kept halves (BDA3 11.4)",
            "acceptance_fraction": cal.chains.acceptance,
            "walkers": walkers, "steps": steps, "burn_in_steps": cal.chains.burn,
            "kept_samples": int(cal.samples.shape[0]),
            "sampler": "emcee EnsembleSampler, 80 % DEMove + 20 % DESnookerMove, vectorised",
            "start": "best of the nominal point and prior draws, refined by Nelder-Mead; "
                     "walkers drawn from the Laplace approximation there"},
        "likelihood": {
            "shared_with": "msens diagnose (msens.diagnose.likelihood)",
            "measured_against": ("each sample's noise variance (pre-trigger noise, shot "
                                 "scatter) plus the model's own uncertainty; gain, DC offset "
                                 "and impact-to-trigger offset profiled out"
                                 if cal.mode == "waveform" else
                                 "each published feature's shot-to-shot std"),
            "chi2_best": cal.chi2_best, "n_obs": cal.n_obs,
            "chi2_per_observation": cal.chi2_best / cal.n_obs if cal.n_obs else None,
            **cal.variance},
        "predictive": {
            "draws": int(next(iter(cal.predictive.values())).size) if cal.predictive else 0,
            "features": {k: {"label": feature_label(k)[0], "unit": feature_label(k)[1],
                             "band_5_50_95": _band(v)} for k, v in cal.predictive.items()},
            "reference": cal.reference},
        "cost": {"model_runs": cal.runs, "seconds": cal.seconds},
        "provenance": provenance,
    }
    if cal.band is not None:
        b = cal.band
        step = max(1, int(np.ceil(b["t_us"].size / WAVEFORM_POINTS)))
        out["predictive"]["waveform"] = {
            "channels": b["channels"], "delay_us": b["delay_us"],
            "t_us": b["t_us"][::step].tolist(),
            "data": b["data"][:, ::step].tolist(),
            "model_5_50_95": b["model"][:, :, ::step].tolist()}
    return out


def format_table(report: dict) -> str:
    """The posterior and the convergence verdict as text."""
    lines = [f"calibration of setup {report['setup']} on {report['measurement']} "
             f"({report['mode']})",
             f"{'input':<34} {'unit':>5} {'nominal':>11} {'posterior 5-50-95 %':>36} "
             f"{'R-hat':>6} {'ESS':>6}"]
    for p in report["inputs"]:
        q = p["posterior_5_50_95"]
        lines.append(f"{p['name']:<34} {p['unit']:>5} {p['nominal']:>11.4g} "
                     f"{q[0]:>11.4g} {q[1]:>11.4g} {q[2]:>11.4g}  "
                     f"{p['rhat'] if p['rhat'] is not None else float('nan'):>6.3f} "
                     f"{p['effective_samples'] or 0:>6.0f}")
    cv = report["convergence"]
    lines.append(f"{'converged' if cv['converged'] else 'NOT converged'}: R-hat limit "
                 f"{cv['rhat_limit']}, acceptance {cv['acceptance_fraction']:.2f}, "
                 f"{cv['walkers']} walkers x {cv['steps']} steps")
    lk = report["likelihood"]
    if lk.get("chi2_per_observation") is not None:
        lines.append(f"chi^2 per observation at the best sample: "
                     f"{lk['chi2_per_observation']:.3g} ({lk['n_obs']:.0f} observations)")
    for r in report["predictive"]["reference"]:
        tag = "calibrated on" if r["calibrated_on"] else "predicted"
        for f in ("tof_us", "ar"):
            e = r[f]
            q, qm = e["model_5_50_95"], e["measurement_5_95"]
            lines.append(f"  {r['setup']}/{r['position']} {f}: measured {e['measured']:.4g} "
                         f"+- {e['measured_std']:.2g}; model {q[1]:.4g} [{q[0]:.4g}, "
                         f"{q[2]:.4g}], a measurement's 90 % band [{qm[0]:.4g}, {qm[1]:.4g}] "
                         f"({'inside' if e['inside_90'] else 'OUTSIDE'}; {tag})")
    return "\n".join(lines)


def _short(name: str) -> str:
    return name.replace("sensor.magnet.", "magnet ").replace("striker.", "striker ") \
        .replace("chain.", "").replace("electronics.", "")


def pairs_figure(cal):
    """Marginal histograms on the diagonal, pairwise scatter below, the nominal value dashed
    and the 90 % credible interval dotted (axes span the samples and the nominal value)."""
    import matplotlib.pyplot as plt

    c = cal.coords
    k = len(c.names)
    fig, axes = plt.subplots(k, k, figsize=(2.4 * k + 1.2, 2.4 * k + 0.8), squeeze=False)
    x = cal.samples
    for i in range(k):
        for j in range(k):
            ax = axes[i, j]
            if j > i:
                ax.set_visible(False)
                continue
            lo_j, hi_j = np.quantile(x[:, j], (0.001, 0.999))
            lo_j, hi_j = min(lo_j, c.center[j]), max(hi_j, c.center[j])  # nominal in view
            if i == j:
                ax.hist(x[:, j], bins=40, color="C0", alpha=0.7, density=True)
                q = np.quantile(x[:, j], (0.05, 0.95))
                for v in q:
                    ax.axvline(v, color="C0", ls=":", lw=1)
                ax.axvline(c.center[j], color="k", ls="--", lw=1)
                ax.set_yticks([])
            else:
                ax.plot(x[:, j], x[:, i], ".", ms=1, alpha=0.15, color="C0", rasterized=True)
                ax.axvline(c.center[j], color="k", ls="--", lw=0.8)
                ax.axhline(c.center[i], color="k", ls="--", lw=0.8)
            pad = 0.1 * (hi_j - lo_j) or abs(lo_j) * 1e-3 or 1e-12
            ax.set_xlim(lo_j - pad, hi_j + pad)
            if i == k - 1:
                ax.set_xlabel(f"{_short(c.names[j])} ({c.inputs[j].kind.unit})", fontsize=8)
            if j == 0 and i > 0:
                ax.set_ylabel(f"{_short(c.names[i])} ({c.inputs[i].kind.unit})", fontsize=8)
            ax.tick_params(labelsize=7)
    fig.suptitle(f"Posterior of {k} input(s): setup {cal.setup} on {cal.measurement}\n"
                 f"dashed: nominal; dotted: 90 % credible interval", fontsize=9)
    fig.tight_layout()
    return fig


def predictive_figure(cal):
    """Waveform mode: each measured channel with the calibrated model's 5-95 % band; feature
    mode: each reference feature, measured +- std, against the model's 90 % band."""
    import matplotlib.pyplot as plt

    if cal.band is not None:
        b = cal.band
        n = len(b["channels"])
        fig, axes = plt.subplots(n, 1, figsize=(7.0, 2.6 * n + 0.6), squeeze=False,
                                 sharex=True)
        for j, ax in enumerate(axes[:, 0]):
            ax.plot(b["t_us"], b["data"][j] * 1e3, color="0.4", lw=0.7, label="measured")
            ax.fill_between(b["t_us"], b["model"][0, j] * 1e3, b["model"][2, j] * 1e3,
                            color="C1", alpha=0.4, lw=0, label="calibrated model, 5-95 %")
            ax.plot(b["t_us"], b["model"][1, j] * 1e3, color="C1", lw=0.9,
                    label="calibrated model, median")
            ax.set_ylabel("voltage (mV)")
            ax.set_title(channel_name(b["channels"][j]), fontsize=9)
            ax.grid(alpha=0.3)
        axes[0, 0].legend(fontsize=8, loc="upper right")
        axes[-1, 0].set_xlabel(TIME_LABEL)
        fig.suptitle("Posterior predictive over the measurement (gain, offset and trigger "
                     "delay as fitted)", fontsize=10)
        fig.tight_layout()
        return fig
    refs = cal.reference
    fig, axes = plt.subplots(1, 2, figsize=(9.0, 0.45 * max(len(refs), 2) + 1.6),
                             squeeze=False)
    labels = [f"{r['setup']} {r['position']}" + (" *" if r["calibrated_on"] else "")
              for r in refs]
    y = np.arange(len(refs))
    for ax, (f, what, unit) in zip(axes[0], (("tof_us", "time of flight", "µs"),
                                              ("ar", "amplitude ratio", "1")), strict=True):
        q = np.array([r[f]["model_5_50_95"] for r in refs], dtype=float)
        qm = np.array([r[f]["measurement_5_95"] for r in refs], dtype=float)
        ax.barh(y, qm[:, 1] - qm[:, 0], left=qm[:, 0], height=0.5, color="C1", alpha=0.2,
                label="a measurement, 5-95 %")
        ax.barh(y, q[:, 2] - q[:, 0], left=q[:, 0], height=0.5, color="C1", alpha=0.6,
                label="calibrated model, 5-95 %")
        ax.plot(q[:, 1], y, "|", color="C1", ms=12, label="model median")
        ax.errorbar([r[f]["measured"] for r in refs], y,
                    xerr=[r[f]["measured_std"] for r in refs], fmt="o", color="k", ms=4,
                    capsize=3, label="measured +- std")
        ax.set_yticks(y, labels, fontsize=8)
        ax.set_xlabel(f"{what} ({unit})")
        ax.grid(alpha=0.3, axis="x")
    axes[0, 0].invert_yaxis()
    axes[0, 1].invert_yaxis()
    axes[0, 1].legend(fontsize=7, loc="best")
    fig.suptitle(f"Posterior predictive of the reference rows (* calibrated on: "
                 f"{cal.setup})", fontsize=10)
    fig.tight_layout()
    return fig


def trace_figure(cal):
    """Every walker's path for each calibrated input; the burn-in (discarded) shaded."""
    import matplotlib.pyplot as plt

    c = cal.coords
    k = len(c.names)
    z = cal.chains.z
    theta = c.center + c.scale * z  # (steps, walkers, k)
    fig, axes = plt.subplots(k, 1, figsize=(7.0, 1.8 * k + 0.8), squeeze=False, sharex=True)
    steps = np.arange(z.shape[0])
    for j, ax in enumerate(axes[:, 0]):
        ax.plot(steps, theta[:, :, j], lw=0.4, alpha=0.5, color="C0")
        ax.axvspan(0, cal.chains.burn, color="0.85", zorder=0, label="burn-in (discarded)")
        ax.set_ylabel(f"{_short(c.names[j])}\n({c.inputs[j].kind.unit})", fontsize=8)
        r = cal.rhat[j]
        ax.set_title(f"{c.names[j]}: split R-hat {r:.3f}", fontsize=8)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("sampler step")
    fig.suptitle(f"Walker traces ({z.shape[1]} walkers)", fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["QUANTILES", "format_table", "pairs_figure", "predictive_figure", "to_json",
           "trace_figure"]

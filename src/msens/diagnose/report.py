"""Write a diagnosis: ``diagnosis.json`` and ``diagnosis.png``.

The figure shows where the baseline disagrees (chi^2 per sample in each sensor's incident and
reflected window and elsewhere, before and after the named effect, with the largest value that
noise alone reaches; or, in feature mode, each feature's residual in units of its std), whether
the data are explained, and, for waveforms, the shots' mean of every channel over the baseline
and the corrected model.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from msens.diagnose.diagnosis import Diagnosis
from msens.io.output import OutputDir

FILES = ("diagnosis.json", "diagnosis.png")


def report(passes: Sequence[Diagnosis]) -> dict:
    """``diagnosis.json``: the first pass in full, and a summary of every pass."""
    out = passes[0].to_json()
    out["passes"] = [{"effect": d.effect, "parameters": d.parameters,
                      "explained": d.explained, "summary": d.summary(),
                      "misfit_before": d.misfit_before, "misfit_after": d.misfit_after,
                      "best_score": d.candidates[0].score if d.candidates else None,
                      "joint_refit": [{"effect": n, "parameters": p} for n, p in d.refit]}
                     for d in passes]
    return out


def _label(d: Diagnosis) -> str:
    if d.effect == "none":
        return "no effect named"
    pars = ", ".join(f"{k} = {v:.4g}" for k, v in d.parameters.items())
    return f"{d.effect} ({pars})"


def _bars(ax, d: Diagnosis, before: list[float], after: list[float]) -> np.ndarray:
    """Baseline and corrected bars side by side; the baseline alone when no effect was
    named (the "after" model is then the baseline)."""
    x = np.arange(len(before))
    if d.effect == "none":
        ax.bar(x, before, 0.5, label="baseline (no effect named)")
    else:
        ax.bar(x - 0.2, before, 0.4, label="baseline")
        ax.bar(x + 0.2, after, 0.4, label=f"with {d.effect}")
    return x


#: Axis names of the features a reference diagnosis compares.
_FEATURES = {"tof_us": "TOF", "ar": "AR"}


def figure(d: Diagnosis) -> Figure:
    """Where the disagreement sits, and before/after overlays (baseline only when no
    effect was named)."""
    if d.mode == "features":
        fig, ax = plt.subplots(figsize=(7, 3.6))
        table = d.disagreement["features"]
        x = _bars(ax, d, [r["residual_before"] for r in table],
                  [r["residual_after"] for r in table])
        ax.set_xticks(x, [f"{_FEATURES.get(r['feature'], r['feature'])}\n{r['channel']}"
                          for r in table], fontsize=7)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_ylabel("(model − measured) / std (–)")
        ax.legend(fontsize=8)
        ax.set_title(f"setup {d.setup}: {_label(d)}\n{d.summary()}", fontsize=8)
        fig.tight_layout()
        return fig
    channels = d.overlay
    fig, axes = plt.subplots(1 + len(channels), 1, figsize=(8, 2.6 * (1 + len(channels))),
                             squeeze=False)
    ax = axes[0, 0]
    rows = d.disagreement["windows"]
    x = _bars(ax, d, [r["chi2_per_sample_before"] for r in rows],
              [r["chi2_per_sample_after"] for r in rows])
    ax.set_xticks(x, [f"{r['window']}\n{r['channel']}" for r in rows], fontsize=7)
    ax.set_yscale("log")
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    # the largest chi^2 per sample that noise alone reaches (the verdict's test)
    limits = [w["limit"] for w in d.verdict["windows"]]
    ax.scatter(x, limits, marker="_", s=300, color="k", zorder=3, label="noise limit")
    ax.set_ylabel("χ² per sample (–)")
    ax.legend(fontsize=8)
    ax.set_title(f"setup {d.setup}: disagreement mostly at the {d.disagreement['where']}\n"
                 f"{_label(d)}; misfit {d.misfit_before:.3g} -> {d.misfit_after:.3g}\n"
                 f"{d.summary()}", fontsize=8)
    for ax, ch in zip(axes[1:, 0], channels, strict=True):
        ax.plot(ch["t_us"], ch["data"], color="0.6", lw=0.7, label="measured (mean of the shots)")
        ax.plot(ch["t_us"], ch["before"], "b--", lw=1.0, label="baseline")
        if d.effect != "none":  # otherwise "after" is the baseline drawn again
            ax.plot(ch["t_us"], ch["after"], "r-", lw=1.0, label=f"with {d.effect}")
        ax.set_ylabel(f"{ch['channel']} (V)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("record time (µs)")
    fig.tight_layout()
    return fig


def write(passes: Sequence[Diagnosis], out: str | Path | OutputDir, *,
          provenance: dict | None = None, fig_format: str = "png") -> list[Path]:
    """Write ``diagnosis.json`` and ``diagnosis.<fig_format>`` (png, pdf or svg; atomically,
    never over a user's file); ``provenance`` (msens version, study hash) is recorded in
    the JSON."""
    from msens.io.output import DPI

    d = out if isinstance(out, OutputDir) else OutputDir(out)
    written = [d.write_json("diagnosis.json",
                            {**report(passes), **({"provenance": provenance}
                                                  if provenance else {})})]
    fig = figure(passes[0])
    written.append(d.savefig("diagnosis.png", fig, fmt=fig_format, dpi=DPI))
    plt.close(fig)
    return written

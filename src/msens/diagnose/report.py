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
from matplotlib.ticker import FuncFormatter

from msens.diagnose.diagnosis import Diagnosis
from msens.io.output import OutputDir
from msens.vocabulary import TIME_LABEL, channel_name, setup_name

FILES = ("diagnosis.json", "diagnosis.png")


def report(passes: Sequence[Diagnosis]) -> dict:
    """``diagnosis.json``: the first pass in full, and a summary of every pass."""
    out = passes[0].to_json()
    out["passes"] = [{"effect": d.effect, "parameters": d.parameters,
                      "parameter_intervals": d.to_json()["parameter_intervals"],
                      "explained": d.explained, "summary": d.summary(),
                      "misfit_before": d.misfit_before, "misfit_after": d.misfit_after,
                      "best_score": d.candidates[0].score if d.candidates else None,
                      "joint_refit": [{"effect": n, "parameters": p} for n, p in d.refit]}
                     for d in passes]
    return out


#: Parameter-name suffixes (SI units written out in the names) -> (unit shown, scale).
_UNITS = (("_kg_per_s_m05", "kg/(s m^0.5)", 1.0), ("_n_s_per_m", "N s/m", 1.0),
          ("_kg_per_s", "kg/s", 1.0), ("_m_per_s", "m/s", 1.0), ("_factor", "× nominal", 1.0),
          ("_pa", "GPa", 1e-9), ("_kg", "g", 1e3), ("_f", "pF", 1e12), ("_s", "µs", 1e6),
          ("_n", "N", 1.0), ("_m", "mm", 1e3))


def _parameter_text(key: str, value: float) -> tuple[str, str]:
    """One fitted parameter for a reader, as (name, value with unit):
    ``striker_velocity_m_per_s`` 0.371 -> ("striker velocity", "0.371 m/s"),
    ``lowpass_tau_s`` 2e-6 -> ("lowpass tau", "2 µs")."""
    for suffix, unit, scale in _UNITS:
        if key.lower().endswith(suffix):
            return key[: -len(suffix)].replace("_", " "), f"{value * scale:.3g} {unit}"
    return key.replace("_", " "), f"{value:.3g}"


def effect_text(d: Diagnosis) -> str:
    """The named effect in words with its fitted parameters, e.g. "striker impact speed
    0.371 m/s", "static compression of a run of contacts (first contact 12, contact count 3,
    precompression force 2.1 N)"; "no effect" when none was named."""
    if d.effect == "none":
        return "no effect"
    what = _effect_name(d)
    pars = [_parameter_text(k, v) for k, v in d.parameters.items()]
    if len(pars) == 1:
        return f"{what} {pars[0][1]}"
    return f"{what} ({', '.join(f'{n} {v}' for n, v in pars)})" if pars else what


def _effect_name(d: Diagnosis) -> str:
    """The named effect without its values, for legends."""
    from msens.diagnose.effects import registry

    effect = registry().get(d.effect)
    # an effect not in the library (e.g. read from an older file): its name in words
    return effect.description.split(" (")[0] if effect else d.effect.replace("_", " ")


def _where_text(where: dict | None) -> str:
    if not where:
        return ""
    return (f"the residual is {where['residual_over_noise']:.2g} × the noise in the "
            f"{where['window']} window of the {channel_name(where['channel'])}")


def title(d: Diagnosis, width: int = 100) -> str:
    """The figure's verdict, in words, consistent with ``diagnosis.json``'s ``explained``:
    what is named (or that nothing is), whether the model then explains the measurement
    within the noise, and where it does not; lines wrapped at ``width`` characters."""
    import textwrap

    setup = setup_name(d.setup)
    where = _where_text(d.verdict.get("unexplained_where"))
    if d.effect == "none":
        text = (f"{setup}: the model explains the measurement within the noise; no effect "
                "is missing" if d.explained
                else f"{setup}: no effect of the library explains the misfit; {where}")
    elif d.explained:
        text = f"{setup}: the fitted {effect_text(d)} explains the measurement within the noise"
    else:
        text = (f"{setup}: the fitted {effect_text(d)} improves the fit but does not explain "
                f"the measurement; {where}")
    return textwrap.fill(text, width)


def _bars(ax, d: Diagnosis, before: list[float], after: list[float]) -> np.ndarray:
    """Baseline and corrected bars side by side; the baseline alone when no effect was
    named (the "after" model is then the baseline)."""
    x = np.arange(len(before))
    if d.effect == "none":
        ax.bar(x, before, 0.5, label="baseline model (no effect named)")
    else:
        ax.bar(x - 0.2, before, 0.4, label="baseline model")
        ax.bar(x + 0.2, after, 0.4, label=f"with fitted {_effect_name(d)}")
    return x


#: Axis names of the features a reference diagnosis compares.
_FEATURES = {"tof_us": "time of flight", "ar": "amplitude ratio"}


def figure(d: Diagnosis) -> Figure:
    """Where the model disagrees with the measurement, before and after the named effect,
    and (waveform mode) the measured records over both models, on the time since striker
    impact like every other figure.

    Returns
    -------
    Figure
    """
    if d.mode == "features":
        fig, ax = plt.subplots(figsize=(7, 3.8))
        table = d.disagreement["features"]
        x = _bars(ax, d, [r["residual_before"] for r in table],
                  [r["residual_after"] for r in table])
        ax.set_xticks(x, [f"{_FEATURES.get(r['feature'], r['feature'])}\n"
                          f"{channel_name(r['channel']).replace(' at ', ' at' + chr(10))}"
                          for r in table], fontsize=7)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_ylabel("(model − measured) / std (–)")
        ax.legend(fontsize=8)
        fig.suptitle(title(d), fontsize=9)
        fig.tight_layout()
        return fig
    channels = d.overlay
    fig, axes = plt.subplots(1 + len(channels), 1, figsize=(8, 2.6 * (1 + len(channels)) + 0.4),
                             squeeze=False)
    ax = axes[0, 0]
    rows = d.disagreement["windows"]
    x = _bars(ax, d, [r["chi2_per_sample_before"] for r in rows],
              [r["chi2_per_sample_after"] for r in rows])
    ax.set_xticks(x, [f"{r['window']} window\n{channel_name(r['channel'])}" for r in rows],
                  fontsize=7)
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(FuncFormatter(
        lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else ""))
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    # the largest chi^2 per sample that noise alone reaches (the verdict's test)
    limits = [w["limit"] for w in d.verdict["windows"]]
    ax.scatter(x, limits, marker="_", s=300, color="k", zorder=3,
               label="largest value noise alone reaches")
    ax.set_ylabel("χ² per sample (–)")
    ax.set_title("misfit per pulse window, in units of the noise", loc="left", fontsize=8)
    ax.legend(fontsize=7)
    for ax, ch in zip(axes[1:, 0], channels, strict=True):
        t_after = ch.get("t_after_us", ch["t_us"])
        ax.plot(ch["t_us"], ch["data"], color="0.6", lw=0.7, label="measured (mean of the shots)")
        ax.plot(ch["t_us"], ch["before"], "C0--", lw=1.0, label="baseline model")
        if d.effect != "none":  # otherwise "after" is the baseline drawn again
            ax.plot(t_after, ch["after"], "C3-", lw=1.0,
                    label=f"with fitted {_effect_name(d)}")
        ax.set_ylabel("voltage (V)")
        ax.set_title(channel_name(ch["channel"]), loc="left", fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    if channels:
        axes[-1, 0].set_xlabel(TIME_LABEL)
    fig.suptitle(title(d), fontsize=9)
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

"""Sweep outputs: designs.csv, the Pareto plot and the recommended design.

designs.csv: one row per design in sweep order; SI column names; every float written with 10
significant digits (``%.10g``) so that reruns, resumed runs and Dask runs give identical
bytes; ``contact_maps`` says whether the row's figures read the nonlinear contact maps (a
screening sweep's verified designs: true); failed designs keep their parameters, ``status =
failed`` and the ``reason``.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Collection, Sequence
from pathlib import Path

import numpy as np

from msens.design.cache import atomic_write_bytes
from msens.design.sweep import Design, Recommend

METRICS = ("outer_radius_m", "resistance_ohm", "inductance_H", "winding_capacitance_F",
           "resonance_Hz", "quality_factor", "bandwidth_Hz", "noise_rms_V",
           "sensitivity_villari_Wb_per_N", "dLambda_dapproach_Wb_per_m", "peak_emf_V",
           "peak_voltage_V", "snr", "precompression_N", "precompression_max_N",
           "wave_speed_change")
#: Axis labels of the metrics a recommendation can rank on.
LABELS = {"snr": "SNR (peak DAQ voltage / noise rms)", "peak_emf_V": "peak EMF (V)",
          "peak_voltage_V": "peak DAQ voltage (V)", "bandwidth_Hz": "bandwidth (Hz)",
          "sensitivity_villari_Wb_per_N":
              r"$\Sigma_c\,\partial\Lambda/\partial F_c$, Villari (Wb/N)",
          "dLambda_dapproach_Wb_per_m":
              r"$\Sigma_c\,\partial\Lambda/\partial \delta_c$, contact approach (Wb/m)",
          "resonance_Hz": "resonance (Hz)"}


def _fmt(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else format(v, ".10g")
    return str(v)


def column_name(parameter: str) -> str:
    """``coil.turns`` -> ``coil_turns``."""
    return parameter.replace(".", "_")


def csv_text(designs: Sequence[Design], rows: Sequence[dict]) -> str:
    """The designs.csv text."""
    params = [k for k, _ in designs[0].values] if designs else []
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["design", "status", *map(column_name, params), *METRICS, "contact_maps",
                "reason"])
    for d, r in zip(designs, rows, strict=True):
        w.writerow([d.index, r["status"], *(_fmt(v) for _, v in d.values),
                    *(_fmt(r.get(m)) for m in METRICS), _fmt(r.get("contact_maps")),
                    r.get("reason", "")])
    return buf.getvalue()


def pareto_mask(x: np.ndarray, y: np.ndarray, x_better: str) -> np.ndarray:
    """Designs not dominated in (maximise y, minimise or maximise x)."""
    sx = -x if x_better == "max" else x
    keep = np.ones(x.size, dtype=bool)
    for i in range(x.size):
        dom = (sx <= sx[i]) & (y >= y[i]) & ((sx < sx[i]) | (y > y[i]))
        keep[i] = not np.any(dom)
    return keep


def _limits(rule: Recommend) -> list[tuple[str, str, float]]:
    limits = []
    if rule.min_bandwidth_hz is not None:
        limits.append(("bandwidth_Hz", ">=", rule.min_bandwidth_hz))
    if rule.max_precompression_n is not None:
        limits.append(("precompression_max_N", "<=", rule.max_precompression_n))
    if rule.min_snr is not None:
        limits.append(("snr", ">=", rule.min_snr))
    if rule.min_resonance_hz is not None:
        limits.append(("resonance_Hz", ">=", rule.min_resonance_hz))
    return limits


def ranked(rows: Sequence[dict], rule: Recommend) -> list[int]:
    """Indices of the designs that meet ``rule``'s limits, best first (largest
    |objective|; ties keep sweep order)."""
    limits = _limits(rule)
    feasible = [i for i, r in enumerate(rows) if r["status"] == "ok" and all(
        (r[k] >= v) if op == ">=" else (r[k] <= v) for k, op, v in limits)]
    return sorted(feasible, key=lambda i: -abs(rows[i][rule.objective]))  # stable: ties in order


def above_verified(rows: Sequence[dict], verified: Collection[int],
                   rule: Recommend) -> list[int]:
    """Designs meeting the limits, not among ``verified`` (positions), whose screened
    |objective| exceeds the best verified design's (every one, if no verified design meets
    the limits), best first: the designs that could still beat the recommendation."""
    order = ranked(rows, rule)
    best = next((i for i in order if i in verified), None)
    target = -math.inf if best is None else abs(rows[best][rule.objective])
    return [i for i in order if i not in verified and abs(rows[i][rule.objective]) > target]


def recommend(designs: Sequence[Design], rows: Sequence[dict], rule: Recommend,
              among: Sequence[int] | None = None) -> dict:
    """The best design by ``rule`` and why (``{"design": None, ...}`` if none qualifies).

    ``among``: positions in ``designs`` the recommendation may choose from (default all),
    e.g. the designs a sweep verified with the contact maps."""
    limits = _limits(rule)
    allowed = set(range(len(rows)) if among is None else among)
    ok = [i for i in allowed if rows[i]["status"] == "ok"]
    order = [i for i in ranked(rows, rule) if i in allowed]
    out = {"objective": rule.objective,
           "limits": [f"{k} {op} {v:g}" for k, op, v in limits],
           "designs_ok": len(ok), "designs_failed": len(allowed) - len(ok),
           "designs_feasible": len(order)}
    if not order:
        return {**out, "design": None,
                "reasons": ["no design meets every limit" if ok else "every design failed"]}
    best = order[0]
    r = rows[best]
    reasons = [f"largest |{rule.objective}| = {abs(r[rule.objective]):.4g} among "
               f"{len(order)} designs meeting the limits"]
    if len(order) > 1:
        second = order[1]
        reasons.append(f"runner-up design {designs[second].index}: "
                       f"{abs(rows[second][rule.objective]):.4g}")
    for k, op, v in limits:
        reasons.append(f"{k} = {r[k]:.4g} ({op} {v:g})")
    edges = range_edges(designs, best)
    reasons.extend(f"the optimum sits on the {side} of the swept range of {column_name(k)} "
                   f"({v:g}): the best design may lie beyond it" for k, v, side in edges)
    reasons.append(f"peak EMF {r['peak_emf_V']:.4g} V, peak DAQ voltage "
                   f"{r['peak_voltage_V']:.4g} V, SNR {r['snr']:.4g}, bandwidth "
                   f"{r['bandwidth_Hz']:.4g} Hz, resonance {r['resonance_Hz']:.4g} Hz, "
                   f"precompression {r['precompression_N']:.4g} N (wave speed "
                   f"{100 * r['wave_speed_change']:+.3g} %)")
    return {**out, "design": designs[best].index,
            "at_range_edge": [column_name(k) for k, _, _ in edges],
            "parameters": {column_name(k): v for k, v in designs[best].values},
            "metrics": {m: r[m] for m in METRICS}, "reasons": reasons}


def verification(rec: dict, designs: Sequence[Design], rows: Sequence[dict],
                 screening: dict[int, dict], rule: Recommend) -> dict:
    """``rec`` (made among the verified designs) with what verification changed.

    Adds ``verification``: per verified design its objective, peak EMF and peak DAQ voltage
    screened (linear contact sources) and verified (its own contact maps), and the reasons
    gain a line on the screening's error and a warning when a design left unverified
    screens above the recommended design's verified objective (verify more designs)."""
    keys = (rule.objective, "peak_emf_V", "peak_voltage_V")
    entries = []
    for i, before in screening.items():
        after = rows[i]
        e = {"design": designs[i].index, "status": after["status"]}
        if before["status"] == "ok" and after["status"] == "ok":
            e.update({f"screening_{k}": before[k] for k in keys})
            e.update({f"verified_{k}": after[k] for k in keys})
            e["objective_change"] = abs(after[rule.objective]) / abs(before[rule.objective]) - 1
        entries.append(e)
    reasons = list(rec["reasons"])
    changes = [abs(e["objective_change"]) for e in entries if "objective_change" in e]
    off = (f"the screening's {rule.objective} off by up to {100 * max(changes):.2g} %"
           if changes else "none of them evaluated")
    reasons.insert(0, f"recommended among the {len(screening)} best screened designs, "
                      f"evaluated again with their own contact maps ({off})")
    if rec.get("design") is not None:
        above = above_verified(rows, screening, rule)
        if above:
            reasons.insert(1, f"{len(above)} unverified design(s) screen above the "
                              f"recommended design's verified {rule.objective} (first: "
                              f"design {designs[above[0]].index}): verify more designs")
    return {**rec, "verified_designs": [designs[i].index for i in screening],
            "verification": entries, "reasons": reasons}


def range_edges(designs: Sequence[Design], best: int) -> list[tuple[str, float, str]]:
    """Numeric parameters (3 or more swept values) whose best value is the sweep's min or max.

    Returns
    -------
    list of (parameter, value, "lower end" | "upper end")
    """
    out = []
    for j, (key, v) in enumerate(designs[best].values):
        values = {d.values[j][1] for d in designs}
        if isinstance(v, str) or len(values) < 3:
            continue
        if v == min(values):
            out.append((key, float(v), "lower end"))
        elif v == max(values):
            out.append((key, float(v), "upper end"))
    return out


#: Objectives plotted in decibels: amplitude ratios (20 log10).
DECIBELS = {"snr": "SNR: peak DAQ voltage over noise rms (dB)"}
#: Most groups a swept parameter may have to colour the designs by (see :func:`groups`).
MAX_GROUPS = 8


def plotted_objective(values: np.ndarray, objective: str) -> tuple[np.ndarray, str]:
    """|objective| as plotted, and its axis label: 20 log10 for the ratios of
    :data:`DECIBELS`, else as is."""
    v = np.abs(np.asarray(values, dtype=float))
    if objective in DECIBELS:
        with np.errstate(divide="ignore"):
            return 20.0 * np.log10(v), DECIBELS[objective]
    return v, LABELS.get(objective, objective)


_UNITS = (("_m", "mm", 1e3), ("_T", "T", 1.0), ("_N", "N", 1.0))


def parameter_name(key: str) -> str:
    """A swept parameter for a legend, without its SI suffix: ``coil.length_m`` ->
    "coil length"."""
    for suffix, _, _ in _UNITS:
        if key.endswith(suffix):
            key = key[: -len(suffix)]
            break
    return key.replace(".", " ").replace("_", " ")


def parameter_text(key: str, value) -> str:
    """A swept value for a legend: ``coil.turns`` 400 -> "coil turns = 400",
    ``coil.length_m`` 0.007 -> "coil length = 7 mm"."""
    name = parameter_name(key)
    if isinstance(value, str):
        return f"{name} = {value}"
    for suffix, unit, scale in _UNITS:
        if key.endswith(suffix):
            return f"{name} = {value * scale:g} {unit}"
    return f"{name} = {value:g}"


def groups(designs: Sequence[Design], y: np.ndarray) -> tuple[str, list] | None:
    """The swept parameter that best explains the spread of ``y`` (one value per design):
    the one of 2 .. :data:`MAX_GROUPS` values whose groups hold the largest share of the
    variance of ``y`` (between-group over total sum of squares). None for a sweep of one
    parameter value or a constant ``y``.

    Returns
    -------
    (parameter, values) or None
        ``values``: the parameter's value per design, in ``designs``' order.
    """
    finite = np.isfinite(y)
    total = float(np.sum((y[finite] - y[finite].mean()) ** 2)) if finite.any() else 0.0
    if not designs or total <= 0:
        return None
    best, share = None, -1.0
    for j, (key, _) in enumerate(designs[0].values):
        vals = [d.values[j][1] for d in designs]
        distinct = list(dict.fromkeys(vals))
        if not 2 <= len(distinct) <= MAX_GROUPS:
            continue
        between = 0.0
        for v in distinct:
            g = y[[i for i, x in enumerate(vals) if x == v and finite[i]]]
            if g.size:
                between += g.size * (g.mean() - y[finite].mean()) ** 2
        if between / total > share:
            best, share = (key, vals), between / total
    return best


def pareto_figure(designs: Sequence[Design], rows: Sequence[dict], best: int | None,
                  objective: str = "snr", verified: Sequence[int] | None = None):
    """The objective against precompression and against bandwidth, Pareto fronts marked
    (and the designs verified with the contact maps, positions ``verified``, ringed).

    The designs are coloured by the swept parameter that explains most of the objective's
    spread (:func:`groups`), named in the legend; a signal-to-noise ratio is plotted in dB.
    The recommended design (``best``, a design index) is an open star drawn over its own
    point, which stays visible.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [i for i, r in enumerate(rows) if r["status"] == "ok"]
    s, y_label = plotted_objective([rows[i][objective] for i in ok], objective)
    # trade-offs worth showing: those that vary (a coil sweep leaves the precompression alone)
    axes_keys = [a for a in (("precompression_N", "min", "magnetic precompression (N)", 1.0),
                             ("bandwidth_Hz", "max", "bandwidth (kHz)", 1e-3),
                             ("resonance_Hz", "max", "read-out resonance (kHz)", 1e-3))
                 if len({rows[i][a[0]] for i in ok}) > 1][:2] or \
        [("bandwidth_Hz", "max", "bandwidth (kHz)", 1e-3)]
    split = groups([designs[i] for i in ok], s)
    fig, axes = plt.subplots(1, len(axes_keys), figsize=(5 * len(axes_keys), 4.6),
                             layout="constrained", squeeze=False)
    for ax, (key, better, label, unit) in zip(axes[0], axes_keys, strict=True):
        x = np.array([rows[i][key] for i in ok]) * unit
        if x.size:
            front = pareto_mask(x, s, better)
            if split is None:
                ax.scatter(x, s, s=9, c="0.6", lw=0, label="design", zorder=2)
            else:
                param, vals = split
                for k, v in enumerate(dict.fromkeys(vals)):
                    g = np.array([u == v for u in vals])
                    ax.scatter(x[g], s[g], s=9, color=f"C{(k + 1) % 10}", lw=0, alpha=0.8,
                               label=parameter_text(param, v), zorder=2)
            o = np.argsort(x[front])
            ax.plot(x[front][o], s[front][o], "-", c="k", lw=0.9, zorder=3)
            ax.plot(x[front][o], s[front][o], "o", mfc="none", mec="k", ms=5, zorder=4,
                    label="Pareto front")
            ring = [k for k, i in enumerate(ok) if verified is not None and i in verified]
            if ring:
                ax.scatter(x[ring], s[ring], s=110, facecolors="none", edgecolors="C3",
                           lw=1.0, zorder=4, label="verified with contact maps")
            if best is not None and best in [designs[i].index for i in ok]:
                k = [designs[i].index for i in ok].index(best)
                ax.plot(x[k], s[k], "*", mfc="none", mec="C3", mew=1.4, ms=17, zorder=5,
                        label=f"recommended (design {best})")
        ax.set_xlabel(label)
        ax.set_ylabel(y_label)
        ax.grid(alpha=0.3)
    handles, names = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, names, loc="outside right upper", fontsize=8, frameon=False,
                   title=f"designs by {parameter_name(split[0])}" if split else None,
                   title_fontsize=8)
    title = f"{len(ok)} designs ({len(rows) - len(ok)} failed)"
    if verified:
        title += (f"; linear contact sources, the best {len(verified)} verified with their "
                  "own contact maps")
    fig.suptitle(title, fontsize=10)
    return fig


def pareto_plot(designs: Sequence[Design], rows: Sequence[dict], path: Path,
                best: int | None, objective: str = "snr",
                verified: Sequence[int] | None = None) -> None:
    """Write :func:`pareto_figure` in the format of ``path``'s suffix (png, pdf or svg) at
    :data:`msens.io.output.DPI`, the same bytes on every rerun."""
    import matplotlib.pyplot as plt

    from msens.io.output import DPI

    fig = pareto_figure(designs, rows, best, objective, verified)
    buf = io.BytesIO()
    fmt = Path(path).suffix.lstrip(".") or "png"
    # no version or date stamp: reruns write identical bytes
    stamp = {"png": {"Software": None}, "pdf": {"Creator": None, "Producer": None,
                                                "CreationDate": None},
             "svg": {"Creator": None, "Date": None}}.get(fmt, {})
    with plt.rc_context({"svg.hashsalt": "msens"}):  # SVG element ids: fixed, not random
        fig.savefig(buf, format=fmt, dpi=DPI, metadata=stamp)
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue())


__all__ = ["DECIBELS", "LABELS", "METRICS", "column_name", "csv_text", "groups",
           "parameter_name", "parameter_text", "pareto_figure", "pareto_mask", "pareto_plot",
           "plotted_objective", "range_edges", "ranked", "recommend", "verification"]

"""Sweep outputs: designs.csv, the Pareto plot and the recommended design.

designs.csv: one row per design in sweep order; SI column names; every float written with 10
significant digits (``%.10g``) so that reruns, resumed runs and Dask runs give identical
bytes; failed designs keep their parameters, ``status = failed`` and the ``reason``.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
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
          "sensitivity_villari_Wb_per_N": "Σ ∂Λ/∂F_c, Villari (Wb/N)",
          "dLambda_dapproach_Wb_per_m": "Σ ∂Λ/∂δ_c, contact approach (Wb/m)",
          "resonance_Hz": "resonance (Hz)"}


def _fmt(v) -> str:
    if v is None:
        return ""
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
    w.writerow(["design", "status", *map(column_name, params), *METRICS, "reason"])
    for d, r in zip(designs, rows, strict=True):
        w.writerow([d.index, r["status"], *(_fmt(v) for _, v in d.values),
                    *(_fmt(r.get(m)) for m in METRICS), r.get("reason", "")])
    return buf.getvalue()


def pareto_mask(x: np.ndarray, y: np.ndarray, x_better: str) -> np.ndarray:
    """Designs not dominated in (maximise y, minimise or maximise x)."""
    sx = -x if x_better == "max" else x
    keep = np.ones(x.size, dtype=bool)
    for i in range(x.size):
        dom = (sx <= sx[i]) & (y >= y[i]) & ((sx < sx[i]) | (y > y[i]))
        keep[i] = not np.any(dom)
    return keep


def recommend(designs: Sequence[Design], rows: Sequence[dict], rule: Recommend) -> dict:
    """The best design by ``rule`` and why (``{"design": None, ...}`` if none qualifies)."""
    limits = []
    if rule.min_bandwidth_hz is not None:
        limits.append(("bandwidth_Hz", ">=", rule.min_bandwidth_hz))
    if rule.max_precompression_n is not None:
        limits.append(("precompression_max_N", "<=", rule.max_precompression_n))
    if rule.min_snr is not None:
        limits.append(("snr", ">=", rule.min_snr))
    if rule.min_resonance_hz is not None:
        limits.append(("resonance_Hz", ">=", rule.min_resonance_hz))
    ok = [i for i, r in enumerate(rows) if r["status"] == "ok"]
    feasible = [i for i in ok if all(
        (rows[i][k] >= v) if op == ">=" else (rows[i][k] <= v) for k, op, v in limits)]
    out = {"objective": rule.objective,
           "limits": [f"{k} {op} {v:g}" for k, op, v in limits],
           "designs_ok": len(ok), "designs_failed": len(rows) - len(ok),
           "designs_feasible": len(feasible)}
    if not feasible:
        return {**out, "design": None,
                "reasons": ["no design meets every limit" if ok else "every design failed"]}
    score = [abs(rows[i][rule.objective]) for i in feasible]
    order = np.argsort(score, kind="stable")[::-1]
    best = feasible[int(order[0])]
    r = rows[best]
    reasons = [f"largest |{rule.objective}| = {abs(r[rule.objective]):.4g} among "
               f"{len(feasible)} designs meeting the limits"]
    if len(order) > 1:
        second = feasible[int(order[1])]
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


def pareto_plot(designs: Sequence[Design], rows: Sequence[dict], path: Path,
                best: int | None, objective: str = "snr") -> None:
    """The objective against precompression and against bandwidth, Pareto fronts marked.

    Written in the format of ``path``'s suffix (png, pdf or svg) at :data:`msens.io.output.DPI`.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from msens.io.output import DPI

    ok = [i for i, r in enumerate(rows) if r["status"] == "ok"]
    s = np.array([abs(rows[i][objective]) for i in ok])
    # trade-offs worth showing: those that vary (a coil sweep leaves the precompression alone)
    axes_keys = [a for a in (("precompression_N", "min", "magnetic precompression (N)", 1.0),
                             ("bandwidth_Hz", "max", "bandwidth (kHz)", 1e-3),
                             ("resonance_Hz", "max", "read-out resonance (kHz)", 1e-3))
                 if len({rows[i][a[0]] for i in ok}) > 1][:2] or \
        [("bandwidth_Hz", "max", "bandwidth (kHz)", 1e-3)]
    fig, axes = plt.subplots(1, len(axes_keys), figsize=(5 * len(axes_keys), 4.2),
                             constrained_layout=True, squeeze=False)
    for ax, (key, better, label, unit) in zip(axes[0], axes_keys, strict=True):
        x = np.array([rows[i][key] for i in ok]) * unit
        if x.size:
            front = pareto_mask(x, s, better)
            ax.scatter(x[~front], s[~front], s=8, c="0.6", label="design")
            o = np.argsort(x[front])
            ax.plot(x[front][o], s[front][o], "o-", c="C0", ms=4, label="Pareto front")
            if best is not None and best in [designs[i].index for i in ok]:
                k = [designs[i].index for i in ok].index(best)
                ax.plot(x[k], s[k], "*", c="C3", ms=14, label=f"recommended ({best})")
        ax.set_xlabel(label)
        ax.set_ylabel(LABELS.get(objective, objective))
        ax.legend(fontsize=8)
    fig.suptitle(f"{len(ok)} designs ({len(rows) - len(ok)} failed)")
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


__all__ = ["LABELS", "METRICS", "column_name", "csv_text", "pareto_mask", "pareto_plot",
           "range_edges", "recommend"]

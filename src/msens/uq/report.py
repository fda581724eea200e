"""What a forward propagation reports: ``uq.json``, a text table and two figures.

- :func:`to_json` — the inputs (distribution, reason, source, route; the held ones with why),
  per output its unit, 5-50-95 % band, nominal value and Sobol indices with confidence
  intervals, per sensor the waveform band, and the cost (model runs, field solves, time).
- :func:`format_table` — the bands and the input that matters most, for the terminal.
- :func:`waveform_figure` — each sensor's record with its 5-95 % band and median.
- :func:`sobol_figure` — first-order and total indices with their confidence intervals for
  the outputs a user asks most about (peak DAQ voltage, TOF, AR of each sensor).
"""

from __future__ import annotations

import numpy as np

from msens.uq.propagate import CONFIDENCE, QUANTILES, Propagation
from msens.vocabulary import TIME_LABEL, channel_name

#: Units and labels of the features, by their name's last part.
FEATURES = {
    "tof_us": ("µs", "time of flight"),
    "ar": ("1", "amplitude ratio"),
    "incident_peak_N": ("N", "incident peak force"),
    "peak_voltage_V": ("V", "peak DAQ voltage"),
    "peak_voltage_time_us": ("µs", "time of the peak DAQ voltage"),
    "peak_emf_V": ("V", "peak EMF"),
    "peak_emf_time_us": ("µs", "time of the peak EMF"),
    "speed_incident_m_per_s": ("m/s", "incident pulse speed"),
    "speed_reflected_m_per_s": ("m/s", "reflected pulse speed"),
}
#: Waveform samples kept in ``uq.json`` per sensor (every k-th, k chosen to stay below).
WAVEFORM_POINTS = 2500


def feature_label(name: str) -> tuple[str, str]:
    """(label, unit) of an output ``setup/sensor/feature`` or ``setup/feature``."""
    parts = name.split("/")
    unit, what = FEATURES.get(parts[-1], ("?", parts[-1]))
    where = channel_name(parts[1]) if len(parts) == 3 else parts[0]
    return f"{what}, {where}", unit


def to_json(result: Propagation, nominal: dict[str, float], *, provenance: dict,
            study) -> dict:
    """The content of ``uq.json``.

    Parameters
    ----------
    result : Propagation
    nominal : dict
        Each output at the nominal input values (the ``msens run`` prediction).
    provenance : dict
    study : Study
        The propagated study (its name and published reference rows).
    """
    names = [p.name for p in result.inputs.propagated]
    outputs = {}
    for k, y in result.features.items():
        label, unit = feature_label(k)
        ix = result.indices[k]
        outputs[k] = {
            "label": label, "unit": unit, "nominal": nominal.get(k),
            "quantiles": dict(zip([f"p{round(q * 100):02d}" for q in QUANTILES],
                                  result.band(k).tolist(), strict=True)),
            "mean": float(np.nanmean(y)) if np.isfinite(y).any() else None,
            "std": float(np.nanstd(y)) if np.isfinite(y).any() else None,
            "missing_runs": int(np.sum(~np.isfinite(y))),
            "sobol": {n: {"S1": float(ix.first[j]), "S1_conf": float(ix.first_conf[j]),
                          "ST": float(ix.total[j]), "ST_conf": float(ix.total_conf[j])}
                      for j, n in enumerate(names)},
            **({"sobol_note": ix.note} if ix.note else {}),
        }
    step = max(1, int(np.ceil(result.t.size / WAVEFORM_POINTS)))
    waveforms = {}
    for k in result.waveforms:
        band = result.waveform_band(k)
        waveforms[k] = {"unit": "V" if _is_voltage(k, result) else "N", "every_nth": step,
                        "time_s": result.t[::step].tolist(),
                        **{f"p{round(q * 100):02d}": band[i, ::step].tolist()
                           for i, q in enumerate(QUANTILES)}}
    return {
        "schema": "msens.uq/1", "study": study.name, "inputs_file": result.inputs.source,
        "provenance": provenance,
        "method": {"sampling": "Saltelli scheme on a scrambled Sobol' sequence "
                               "(SALib.sample.sobol, first-order and total indices)",
                   "indices": f"SALib.analyze.sobol, {CONFIDENCE:.0%} bootstrap intervals",
                   "base_samples": result.base_samples, "seed": result.seed,
                   "bands": "5-50-95 % quantiles over every run (waveforms: over the "
                            "scheme's A and B rows)"},
        "cost": {"model_runs": int(result.values.shape[0]), "chain_runs": result.runs,
                 "field_solves": field_solves(result.inputs), "seconds": result.seconds,
                 "workers": result.workers},
        "inputs": [p.to_json() for p in result.inputs.inputs],
        "held_at_nominal": {p.name: p.held_reason for p in result.inputs.held},
        "outputs": outputs, "reference_coverage": reference_coverage(study, result),
        "waveforms": waveforms,
    }


def field_solves(inputs) -> int:
    """Field models the propagation's surrogates are built on besides the study's own (each
    solved once, then read from the artifact store): the reversibility surrogate's nodes
    (:data:`msens.magnetics.reversibility.NODES`) with ``field.reversibility`` propagated,
    else 0 (the other field inputs read tables of the study's field models)."""
    from msens.magnetics.reversibility import NODES
    from msens.uq.inputs import FIELD_SURROGATE

    surrogate = [p for p in inputs.propagated if p.route == FIELD_SURROGATE]
    if not surrogate:
        return 0
    return len(NODES) - sum(1 for c in NODES if c == surrogate[0].nominal)


def reference_coverage(study, result: Propagation) -> list[dict]:
    """Each published experiment number of the study (``[[reference.row]]``: TOF and AR with
    their std over shots) beside the prediction's 5-95 % band: is it inside?"""
    out = []
    for ref in study.reference:
        setup = next((s for s in study.setups if s.name == ref.setup), None)
        if setup is None:
            continue
        particles = sorted(s.particle for s in setup.sensors)
        pick = {"top": particles[0], "bottom": particles[-1]}.get(ref.position)
        sensor = next((s for s in setup.sensors if s.particle == pick), None)
        if sensor is None:
            continue
        for feature, value, std in (("tof_us", ref.tof_us, ref.tof_std_us),
                                    ("ar", ref.ar, ref.ar_std)):
            name = f"{setup.name}/{sensor.kind.value}@{sensor.particle}/{feature}"
            if name not in result.features:
                continue
            lo, _, hi = result.band(name)
            out.append({"setup": ref.setup, "position": ref.position, "output": name,
                        "experiment": value, "experiment_std": std, "band_5_95": [lo, hi],
                        "inside": bool(lo <= value <= hi)})
    return out


def _is_voltage(name: str, result: Propagation) -> bool:
    # a physics MsS's waveform is its DAQ voltage: it has a peak_voltage_V feature
    return f"{name}/peak_voltage_V" in result.features


def format_table(report: dict) -> str:
    """Plain-text summary of ``uq.json``: bands and the most influential input."""
    held = report["held_at_nominal"]
    lines = [f"study {report['study']}: {report['cost']['model_runs']} model runs "
             f"(N = {report['method']['base_samples']}, seed {report['method']['seed']}), "
             f"{report['cost']['field_solves']} field solves, "
             f"{report['cost']['seconds']:.0f} s on {report['cost']['workers']}"]
    head = f"{'output':<44} {'nominal':>10} {'5 %':>10} {'50 %':>10} {'95 %':>10}  top input (ST)"
    lines += [head, "-" * len(head)]
    for k, o in report["outputs"].items():
        q = o["quantiles"]
        top = max(o["sobol"].items(), key=lambda kv: kv[1]["ST"]
                  if np.isfinite(kv[1]["ST"]) else -1)
        nom = o["nominal"] if o["nominal"] is not None else float("nan")
        lines.append(f"{k:<44} {nom:>10.4g} {_num(q['p05']):>10} {_num(q['p50']):>10} "
                     f"{_num(q['p95']):>10}  {top[0]} ({top[1]['ST']:.2f})"
                     + (f" [{o['sobol_note']}]" if "sobol_note" in o else ""))
    for r in report.get("reference_coverage", []):
        lo, hi = r["band_5_95"]
        lines.append(f"experiment {r['output']}: {r['experiment']:.4g} (std "
                     f"{r['experiment_std']:.2g}) {'inside' if r['inside'] else 'OUTSIDE'} "
                     f"the 5-95 % band {lo:.4g}..{hi:.4g}")
    if held:
        lines.append("held at nominal (the bands are conditional on their values): "
                     + "; ".join(held))
    return "\n".join(lines)


def _num(v) -> str:
    return "nan" if v is None else f"{v:.4g}"


def waveform_figure(result: Propagation, t_max: float | None = None):
    """Each sensor's record with its 5-95 % band and median (one panel per sensor)."""
    import matplotlib.pyplot as plt

    names = list(result.waveforms)
    fig, axes = plt.subplots(len(names), 1, figsize=(7.0, 2.6 * len(names) + 0.6),
                             squeeze=False, sharex=True)
    t_us = result.t * 1e6
    keep = t_us <= (t_max * 1e6 if t_max else t_us[-1])
    for ax, k in zip(axes[:, 0], names, strict=True):
        band = result.waveform_band(k)
        volts = _is_voltage(k, result)
        scale, unit = (1e3, "mV") if volts else (1.0, "N")
        ax.fill_between(t_us[keep], band[0, keep] * scale, band[2, keep] * scale,
                        color="C0", alpha=0.3, lw=0, label="5-95 % band")
        ax.plot(t_us[keep], band[1, keep] * scale, color="C0", lw=1.0, label="median")
        what = "DAQ voltage" if volts else "force"
        ax.set_ylabel(f"{what} ({unit})")
        ax.set_title(channel_name(k.split("/")[1]), fontsize=9)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="upper right")
    axes[-1, 0].set_xlabel(TIME_LABEL)
    fig.suptitle(f"Prediction band over {len(result.inputs.propagated)} uncertain inputs "
                 f"({result.waveforms[names[0]].shape[0]} runs)", fontsize=10)
    fig.tight_layout()
    return fig


#: Features shown in the Sobol figure, in order.
SOBOL_FEATURES = ("peak_voltage_V", "tof_us", "ar")


def sobol_figure(result: Propagation):
    """First-order and total Sobol indices with their confidence intervals (bars) for the
    peak DAQ voltage, TOF and AR of each sensor (or the features there are)."""
    import matplotlib.pyplot as plt

    shown = [k for f in SOBOL_FEATURES for k in result.features
             if k.endswith("/" + f) and not result.indices[k].note]
    if not shown:
        shown = [k for k in result.features if not result.indices[k].note][:6]
    names = [p.name for p in result.inputs.propagated]
    cols = 2 if len(shown) > 1 else 1
    rows = int(np.ceil(len(shown) / cols))
    # a bar pair per input, and room for each panel's title and axis label (with one or
    # two inputs the bars alone left no room: tight_layout gave up with a warning)
    height = max(0.28 * len(names) * rows + 1.6, 1.9 * rows + 0.6)
    fig, axes = plt.subplots(rows, cols, figsize=(6.0 * cols, height), squeeze=False,
                             sharey=True)
    y = np.arange(len(names))
    for ax, k in zip(axes.flat, shown, strict=False):
        ix = result.indices[k]
        ax.barh(y - 0.2, ix.first, 0.4, xerr=ix.first_conf, color="C0", capsize=2,
                label="first order S1")
        ax.barh(y + 0.2, ix.total, 0.4, xerr=ix.total_conf, color="C1", capsize=2,
                label="total ST")
        label, unit = feature_label(k)
        ax.set_title(f"{label} ({unit})", fontsize=9)
        ax.set_xlim(-0.1, 1.1)
        ax.axvline(0.0, color="k", lw=0.5)
        ax.grid(alpha=0.3, axis="x")
        ax.set_xlabel(f"Sobol index (1; bars: {CONFIDENCE:.0%} interval)")
        ax.tick_params(axis="y", labelsize=7)
    for ax in axes.flat[len(shown):]:
        ax.set_visible(False)
    units = {p.name: p.kind.unit for p in result.inputs.propagated}
    axes[0, 0].set_yticks(y, [f"{n} ({units[n]})" for n in names])
    axes[0, 0].invert_yaxis()
    # one legend for all panels, above them: inside a panel it would hide a bar
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.suptitle(f"Which input to measure: Sobol indices (N = {result.base_samples}, "
                 f"{result.values.shape[0]} runs)", fontsize=10)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.97))
    fig.legend(handles, labels, fontsize=8, ncol=2, loc="upper right",
               bbox_to_anchor=(0.99, 0.995), frameon=False)
    return fig


__all__ = ["FEATURES", "SOBOL_FEATURES", "feature_label", "format_table", "reference_coverage",
           "sobol_figure", "to_json", "waveform_figure"]

"""Where model and measurement disagree: features per channel, residual per time window
(step 3 of :mod:`msens.diagnose.workflow`), and the feature table of the reference mode."""

from __future__ import annotations

import numpy as np

from msens.compare import model_record, shot_records
from msens.config.schema import SetupSpec
from msens.diagnose.objective import FeatureObjective, WaveformObjective
from msens.diagnose.predict import feature_records, model_features_of
from msens.io.waveform import Waveform
from msens.signals.features import centre_distance, smooth

#: Half-width of the incident / reflected windows, in incident pulse widths (FWHM).
WINDOW_WIDTHS = 1.5


def trough(force: np.ndarray, t: np.ndarray, t_inc: float, width: float,
            peak: float) -> float:
    """Deepest pre-peak excursion below zero within 2 widths before the incident peak,
    as a fraction of the incident peak (0 when there is none)."""
    m = (t >= t_inc - 2 * width) & (t <= t_inc) & np.isfinite(force)
    if not m.any() or not np.isfinite(peak) or peak == 0:
        return float("nan")
    return float(min(0.0, np.min(force[m])) / peak)


def record_features(force: np.ndarray, t: np.ndarray) -> dict[str, float]:
    force = np.where(np.isfinite(force), force, 0.0)  # outside the record: at rest
    f = model_features_of(force, t)
    sm = smooth(force, float(t[1] - t[0]))
    return {"t_incident_us": float(f.t_incident) * 1e6, "tof_us": float(f.tof) * 1e6,
            "ar": float(f.ar), "width_us": float(f.width) * 1e6,
            "trough": trough(sm, t, float(f.t_incident), float(f.width), float(f.f_incident))}


def feature_residuals(result, waveform: Waveform) -> dict:
    """Measured (mean over shots) against baseline model features per channel, and speed."""
    t = result.history.t
    shots = shot_records(result, waveform)
    out: dict = {"channels": []}
    t_inc: dict[str, tuple[float, float, int]] = {}
    for sensor in result.sensors:
        name = f"{sensor.sensor.kind.value}@{sensor.sensor.particle}"
        recs = [r for shot in shots for r in shot
                if (r.channel.kind, r.channel.particle)
                == (sensor.sensor.kind.value, sensor.sensor.particle)]
        meas = [record_features(r.force, t) for r in recs]
        model = record_features(model_record(sensor, t), t)
        row = {"channel": name}
        for k in model:
            vals = np.array([m[k] for m in meas])
            row[k] = {"measured": float(np.mean(vals)), "model": model[k],
                      "residual": float(np.mean(vals) - model[k]),
                      "std": float(np.std(vals, ddof=1)) if vals.size > 1 else 0.0}
        out["channels"].append(row)
        t_inc[name] = (row["t_incident_us"]["measured"], model["t_incident_us"],
                       sensor.sensor.particle)
    if len(t_inc) >= 2:
        (a, b) = sorted(t_inc.values(), key=lambda x: x[2])[::len(t_inc) - 1]
        d = centre_distance(result.chain.length, a[2], b[2])
        meas_v = d / ((b[0] - a[0]) * 1e-6)
        model_v = d / ((b[1] - a[1]) * 1e-6)
        out["speed_m_per_s"] = {"measured": meas_v, "model": model_v,
                                "residual": meas_v - model_v}
    return out


def window_residuals(objective: WaveformObjective, records_before: np.ndarray,
             records_after: np.ndarray, result) -> list[dict]:
    """chi^2 per sample (residual over the likelihood's variance: the fit-free noise plus the
    model's own uncertainty) in the incident and reflected window of each sensor, and
    elsewhere, before and after; for the model after, the chi^2 over the noise alone and
    the model uncertainty's share of the window's variance."""
    feats = model_features_of(feature_records(records_before, objective.physics, objective.t),
                              objective.t)
    rows = []
    per = [objective.aligned(r) for r in (records_before, records_after)]
    for j, sensor in enumerate(result.sensors):
        name = f"{sensor.sensor.kind.value}@{sensor.sensor.particle}"
        w = WINDOW_WIDTHS * float(feats.width[j])
        spans = {"incident": (float(feats.t_incident[j]) - w, float(feats.t_incident[j]) + w),
                 "reflected": (float(feats.t_reflected[j]) - w,
                               float(feats.t_reflected[j]) + w)}
        # windows are in model time of the baseline alignment, the same samples after
        masks = []
        for _, tm, _ in per[0]:
            inside = {k: (tm >= lo) & (tm <= hi) for k, (lo, hi) in spans.items()}
            inside["elsewhere"] = ~(inside["incident"] | inside["reflected"])
            masks.append(inside)
        for window in ("incident", "reflected", "elsewhere"):
            vals, count = [], 0
            noise_only, noise_sum, model_sum = 0.0, 0.0, 0.0
            for k, aligned in enumerate(per):
                num = 0.0
                count = 0
                for shot, (_, _, m), mk in zip(objective.shots, aligned, masks, strict=True):
                    sel = mk[window]
                    r = (shot.y[j] - m[j])[sel]
                    num += float(np.sum(shot.w[j][sel] * r**2))
                    count += r.size
                    if k == 1:  # the model under test: the residual over the noise alone
                        nv = (1.0 / shot.w[j] if shot.noise_var is None
                              else shot.noise_var[j])[sel]
                        noise_only += float(np.sum(r**2 / nv))
                        noise_sum += float(np.sum(nv))
                        if shot.model_var is not None:
                            model_sum += float(np.sum(shot.model_var[j][sel]))
                vals.append(num / count if count else float("nan"))
            if count:
                total = noise_sum + model_sum
                rows.append({"channel": name, "window": window, "n_samples": count,
                             "chi2_per_sample_before": vals[0],
                             "chi2_per_sample_after": vals[1],
                             "chi2_per_sample_after_noise_only": noise_only / count,
                             "model_uncertainty_share": model_sum / total if total > 0
                             else 0.0})
    return rows


def worst_window(windows: list[dict]) -> str:
    worst = max(windows, key=lambda r: r["chi2_per_sample_before"])
    return f"{worst['window']} pulse at {worst['channel']}" if worst["window"] != "elsewhere" \
        else f"outside the pulses at {worst['channel']}"


def feature_table(objective: FeatureObjective, records0: np.ndarray, records1: np.ndarray,
                   setup: SetupSpec, where: list[str]) -> list[dict]:
    f0, f1 = (model_features_of(feature_records(r, objective.physics, objective.t),
                                objective.t) for r in (records0, records1))
    r0, r1 = objective.residuals(records0), objective.residuals(records1)
    out = []
    for j, (s, pos, row) in enumerate(zip(setup.sensors, where, objective.rows, strict=True)):
        name = f"{s.kind.value}@{s.particle} ({pos})"
        out.append({"channel": name, "feature": "tof_us", "measured": row.tof_us,
                    "std": row.tof_std_us, "model_before": float(f0.tof[j]) * 1e6,
                    "model_after": float(f1.tof[j]) * 1e6, "residual_before": float(r0[j, 0]),
                    "residual_after": float(r1[j, 0])})
        out.append({"channel": name, "feature": "ar", "measured": row.ar, "std": row.ar_std,
                    "model_before": float(f0.ar[j]), "model_after": float(f1.ar[j]),
                    "residual_before": float(r0[j, 1]), "residual_after": float(r1[j, 1])})
    return out

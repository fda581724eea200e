"""Predicted against measured waveforms: alignment, Eq. 11 calibration and agreement metrics.

For every shot the measured channels are baseline-corrected (pre-trigger mean), MsS voltages
are integrated with drift correction (the coil sees dF/dt, paper Eq. 5), one time offset per
shot is found by cross-correlating the top channel with the model (a single offset keeps the
wave speed between channels intact), and each channel's conversion factor K = F_model / V_peak
(paper Eq. 11) turns volts into newtons. Metrics per channel are then averaged over shots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msens.errors import InputError
from msens.features import PulseFeatures, centre_distance, pulse_features, wave_speed
from msens.io.waveform import Channel, Waveform
from msens.pipeline import SensorResult, SetupResult, StudyResult
from msens.processing import integrate_drift_corrected, lowpass, xcorr_delay
from msens.sensors import SensorKind
from msens.study import SetupSpec

#: Peaks and times are read from records low-passed at this frequency, Hz — the model's too,
#: so the filter biases neither side. Solitary pulses here last ~20 µs (content < 100 kHz);
#: the filter removes the noise that would otherwise bias a peak's maximum upward.
FEATURE_CUTOFF_HZ = 250e3


def smooth(record: np.ndarray, dt: float) -> np.ndarray:
    """Zero-phase low-pass used before feature extraction (see FEATURE_CUTOFF_HZ)."""
    return lowpass(record, dt, min(FEATURE_CUTOFF_HZ, 0.4 / dt), order=4)


def smoothed_features(force: np.ndarray, t: np.ndarray) -> PulseFeatures:
    """Features of records (..., nt) after the smoothing measurements get (:func:`smooth`)."""
    dt = float(t[1] - t[0])
    force = np.asarray(force, dtype=float)
    flat = force.reshape(-1, force.shape[-1])
    smoothed = np.array([smooth(f, dt) for f in flat]).reshape(force.shape)
    return pulse_features(smoothed, t)


@dataclass(frozen=True)
class ShotRecord:
    """One measured channel of one shot on the model's time axis.

    Attributes
    ----------
    channel : Channel
    t : ndarray, shape (nt,)
        Model time (since impact), s.
    raw : ndarray, shape (nt,)
        Force-like measured record: V (bead, rod) or V s (integrated MsS voltage); NaN where
        the record does not cover the model time.
    gain : float
        Eq. 11 factor K, N/V or N/(V s).
    delay_s : float
        Impact-to-trigger delay found for the shot, s.
    features : PulseFeatures
        Features of ``gain * raw``.
    """

    channel: Channel
    t: np.ndarray
    raw: np.ndarray
    gain: float
    delay_s: float
    features: PulseFeatures

    @property
    def force(self) -> np.ndarray:
        """Measured record in newtons, shape (nt,)."""
        return self.gain * self.raw


def match_setup(result: StudyResult, waveform: Waveform) -> SetupResult:
    """The study setup whose sensors are exactly the data's channels (kind and particle)."""
    wanted = {(c.kind, c.particle) for c in waveform.channels}
    names = []
    for s in result.setups:
        have = {(x.sensor.kind.value, x.sensor.particle) for x in s.sensors}
        names.append(f"{s.setup.name} ({', '.join(sorted(f'{k}@{p}' for k, p in have))})")
        if wanted == have:
            return s
    data = ", ".join(sorted(f"{k}@{p}" for k, p in wanted))
    raise InputError(f"the study does not match the data's sensors: data has {data}; "
                     f"study setups: {'; '.join(names)}")


def setup_spec_channels(setup: SetupSpec) -> set[tuple[str, int]]:
    """(kind, particle) of a setup's sensors."""
    return {(s.kind.value, s.particle) for s in setup.sensors}


def _model_force(sensor: SensorResult) -> np.ndarray:
    """The model record a calibrated measurement is compared with, N."""
    return sensor.force


def _force_like(waveform: Waveform, channel: Channel, kind: str) -> np.ndarray:
    """Baseline-free (and for the MsS integrated) record on the waveform's time axis."""
    tau = waveform.time
    v = np.asarray(waveform.channel(channel), dtype=float)
    pre = tau < 0.0
    if pre.sum() < 5:
        pre = np.arange(tau.size) < max(5, tau.size // 50)
    v = v - v[pre].mean()
    if kind != SensorKind.MSS.value:
        return v
    # The coil voltage is ~dF/dt: integrate; the drift fit uses the pre-trigger samples and
    # the quiet tail, if the record has one.
    level = 0.05 * np.max(np.abs(v))
    active = np.flatnonzero(np.abs(v) > level)
    start = tau[active[0]] - 5e-6 if active.size else tau[0]
    return integrate_drift_corrected(tau, v, (start, tau[-1] + 1.0), order=0)


def _shots(waveform: Waveform) -> list[list[Channel]]:
    repeats = sorted({c.repeat for c in waveform.channels})
    return [[c for c in waveform.channels if c.repeat == r] for r in repeats]


def align_shot(setup: SetupResult, waveform: Waveform, channels: list[Channel]) -> float:
    """Impact-to-trigger delay of one shot, s, from its top channel (smallest particle)."""
    top = min(channels, key=lambda c: c.particle)
    sensor = _sensor(setup, top)
    tau = waveform.time
    measured = _force_like(waveform, top, top.kind)
    model_on_tau = np.interp(tau, setup.history.t, _model_force(sensor), left=0.0, right=0.0)
    # measured(tau) ~ model(tau + D): it leads the model by D, so the lag found is -D
    lag = xcorr_delay(model_on_tau, measured, waveform.dt)
    return -lag


def _sensor(setup: SetupResult, channel: Channel) -> SensorResult:
    for s in setup.sensors:
        if s.sensor.kind.value == channel.kind and s.sensor.particle == channel.particle:
            return s
    raise InputError(f"channel {channel.name} has no sensor in setup {setup.setup.name!r}")


def shot_records(setup: SetupResult, waveform: Waveform) -> list[list[ShotRecord]]:
    """Aligned and calibrated records, per shot and channel."""
    t = setup.history.t
    model_peak = {id(s): float(smoothed_features(_model_force(s), t).f_incident)
                  for s in setup.sensors}
    out = []
    for channels in _shots(waveform):
        delay = align_shot(setup, waveform, channels)
        records = []
        for ch in channels:
            sensor = _sensor(setup, ch)
            raw = np.interp(t, waveform.time + delay, _force_like(waveform, ch, ch.kind),
                            left=np.nan, right=np.nan)
            filled = smooth(np.where(np.isfinite(raw), raw, 0.0), float(t[1] - t[0]))
            f_raw = pulse_features(filled, t)
            if not np.isfinite(f_raw.f_incident) or f_raw.f_incident == 0:
                raise InputError(f"channel {ch.name}: no incident pulse found")
            gain = model_peak[id(sensor)] / float(f_raw.f_incident)
            feats = pulse_features(gain * filled, t)
            records.append(ShotRecord(channel=ch, t=t, raw=raw, gain=gain, delay_s=delay,
                                      features=feats))
        out.append(records)
    return out


def _metrics(record: ShotRecord, sensor: SensorResult, m: PulseFeatures) -> dict[str, float]:
    model = _model_force(sensor)
    ok = np.isfinite(record.raw)
    diff = record.force[ok] - model[ok]
    scale = float(np.max(np.abs(model[ok])))
    corr = float(np.corrcoef(record.force[ok], model[ok])[0, 1])
    f = record.features
    return {
        "gain": record.gain,
        "tof_us": float(f.tof) * 1e6,
        "ar": float(f.ar),
        "width_us": float(f.width) * 1e6,
        "incident_peak_N": float(f.f_incident),
        "reflected_peak_N": float(f.f_reflected),
        "incident_time_error_us": float(f.t_incident - m.t_incident) * 1e6,
        "reflected_time_error_us": float(f.t_reflected - m.t_reflected) * 1e6,
        "nrmse": float(np.sqrt(np.mean(diff**2)) / scale),
        "correlation": corr,
    }


def _stats(values: list[dict[str, float]]) -> dict[str, dict[str, float]]:
    keys = values[0].keys()
    out = {}
    for k in keys:
        arr = np.array([v[k] for v in values], dtype=float)
        out[k] = {"mean": float(np.mean(arr)),
                  "std": float(np.std(arr, ddof=1)) if arr.size > 1 else 0.0}
    return out


def compare(result: StudyResult, waveform: Waveform) -> dict:
    """Metrics of the measured waveform against the matching setup of ``result``.

    Returns
    -------
    dict
        ``{"setup", "shots", "channels": [{"channel", "kind", "particle", "model": {...},
        "measured": {metric: {"mean", "std"}}}], "speed": {...}}`` — the content of
        ``compare.json``. Gains are N/V (bead, rod) or N/(V s) (MsS).
    """
    setup = match_setup(result, waveform)
    shots = shot_records(setup, waveform)
    channels = []
    for sensor in setup.sensors:
        m = smoothed_features(_model_force(sensor), setup.history.t)
        per_shot = [
            _metrics(r, sensor, m) for recs in shots for r in recs
            if r.channel.kind == sensor.sensor.kind.value
            and r.channel.particle == sensor.sensor.particle
        ]
        channels.append({
            "channel": f"{sensor.sensor.kind.value}@{sensor.sensor.particle}",
            "kind": sensor.sensor.kind.value,
            "particle": sensor.sensor.particle,
            "model": {"tof_us": float(m.tof) * 1e6, "ar": float(m.ar),
                      "width_us": float(m.width) * 1e6,
                      "incident_peak_N": float(m.f_incident)},
            "measured": _stats(per_shot),
        })
    out = {"setup": setup.setup.name, "shots": len(shots), "channels": channels}
    parts = sorted(s.sensor.particle for s in setup.sensors)
    if len(parts) >= 2:
        d = centre_distance(setup.chain.length, parts[0], parts[-1])
        speeds = []
        for recs in shots:
            by_p = {r.channel.particle: r for r in recs}
            if parts[0] in by_p and parts[-1] in by_p:
                speeds.append(float(wave_speed(d, by_p[parts[0]].features.t_incident,
                                               by_p[parts[-1]].features.t_incident)))
        out["speed"] = {"model_m_per_s": setup.speed_incident,
                        "measured_m_per_s": {"mean": float(np.mean(speeds)),
                                             "std": float(np.std(speeds, ddof=1))
                                             if len(speeds) > 1 else 0.0}}
    return out

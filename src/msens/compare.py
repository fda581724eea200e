"""Predicted against measured waveforms: alignment, Eq. 11 calibration and agreement metrics.

One time offset per shot is found by cross-correlating the top channel with the model (a
single offset keeps the wave speed between channels intact); each channel then gets its
conversion factor K and is compared with the model record of the same kind. Metrics per
channel are averaged over shots.

Bead, rod and four-contact MsS channels: the measured record is baseline-corrected
(pre-trigger mean), an MsS voltage is integrated with drift correction (the coil sees dF/dt,
paper Eq. 5), and K = F_model / V_peak (paper Eq. 11, N/V or N/(V s)) turns it into newtons.

Physics MsS channels: the model predicts the DAQ voltage itself, and it is not zero before
the pulse reaches the coil (contacts well above it are sensitive too), so a pre-trigger
baseline is not a zero level. Model and measurement are compared as voltages and go
through the same steps instead: the shot is aligned by cross-correlating voltages; the
measured voltage on the model's time grid is fitted by ``v_model / K + offset``
(least squares over the whole record: K is dimensionless, V/V, the full-record analogue of
Eq. 11's peak ratio, and the offset needs no quiet window); both voltages are then
integrated, the measured one (offset removed, times K) starting from the model's integral
at the record's first sample, so the two records differ only by what the data differ from
the model. Features (TOF, AR, peaks in V s) and agreement metrics are those of the
integrated voltages.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid

from msens.config.schema import SetupSpec
from msens.config.study import Study
from msens.errors import InputError
from msens.io.waveform import Channel, Waveform
from msens.readout.sensors import SensorKind
from msens.results import SensorResult, SetupResult, StudyResult
from msens.signals.alignment import xcorr_delay
from msens.signals.features import (
    FEATURE_CUTOFF_HZ,
    PulseFeatures,
    centre_distance,
    integrated,
    model_features,
    pulse_features,
    smooth,
    wave_speed,
)
from msens.signals.processing import integrate_drift_corrected
from msens.synth import GAIN_CONVENTION, GAIN_KEY, UNITS, UNITS_KEY, is_physics_mss
from msens.synth import gain_unit as measured_gain_unit
from msens.tables import processing_line as processing_line


def lowpassed_features(records: np.ndarray, t: np.ndarray) -> PulseFeatures:
    """The model's features as compare reads them: :func:`msens.signals.features.model_features`
    (the pipeline of ``msens run``) after the low-pass the measured records get."""
    return model_features(records, t, lowpass_records=True)


#: What ``compare`` does to the model's records that ``msens run`` does not (the
#: ``model_processing`` of ``compare.json`` and the last line of its table).
MODEL_PROCESSING = ("model features as msens run reads them, after the "
                    f"{FEATURE_CUTOFF_HZ / 1e3:g} kHz zero-phase low-pass the measured records "
                    "get")


#: A physics MsS record holds a pulse when its voltage correlates with the model's at least
#: this well after alignment; white noise alone gives about 1/sqrt(samples), ~0.01.
MIN_PULSE_CORRELATION = 0.2


@dataclass(frozen=True)
class ShotRecord:
    """One measured channel of one shot on the model's time axis.

    Attributes
    ----------
    channel : Channel
    t : ndarray, shape (nt,)
        Model time (since impact), s.
    raw : ndarray, shape (nt,)
        Force-like measured record: V (bead, rod), V s (integrated four-contact MsS
        voltage) or V s (integrated physics MsS voltage, offset removed, at the data's
        scale); NaN where the record does not cover the model time.
    gain : float
        Conversion factor K: N/V (bead, rod), N/(V s) (four-contact MsS, paper Eq. 11) or
        V/V (physics MsS, model voltage over measured voltage).
    delay_s : float
        Impact-to-trigger delay found for the shot, s.
    features : PulseFeatures
        Features of ``gain * raw``.
    model : ndarray or None, shape (nt,)
        The model record ``gain * raw`` is compared with (:func:`model_record`), in its unit;
        None stands for the sensor's force.
    offset : float
        Fitted DC offset of a physics MsS record, V (data scale); 0 for the others, whose
        baseline is the pre-trigger mean.
    """

    channel: Channel
    t: np.ndarray
    raw: np.ndarray
    gain: float
    delay_s: float
    features: PulseFeatures
    model: np.ndarray | None = None
    offset: float = 0.0

    @property
    def force(self) -> np.ndarray:
        """Calibrated measured record, shape (nt,): N, or V s for a physics MsS."""
        return self.gain * self.raw


def _names(pairs: set[tuple[str, int]]) -> str:
    return ", ".join(f"{k}@{p}" for k, p in sorted(pairs, key=lambda x: (x[1], x[0])))


def _match(study_name: str, setups: list[tuple[str, set[tuple[str, int]]]],
           waveform: Waveform) -> int:
    """Index of the setup whose sensors are exactly the data's channels, else InputError
    naming the channels without a sensor and what each setup has."""
    wanted = {(c.kind, c.particle) for c in waveform.channels}
    for i, (_, have) in enumerate(setups):
        if wanted == have:
            return i
    known = set().union(*(have for _, have in setups))
    orphans = wanted - known
    lead = (f"channel(s) {_names(orphans)} of the data have no sensor in study "
            f"{study_name!r}" if orphans
            else f"no setup of study {study_name!r} has exactly the data's sensors")
    listing = "; ".join(f"{name} ({_names(have)})" for name, have in setups)
    raise InputError(f"the study does not match the data's sensors: {lead}; data has "
                     f"{_names(wanted)}; study setups: {listing}")


def match_setup(result: StudyResult, waveform: Waveform) -> SetupResult:
    """The study setup whose sensors are exactly the data's channels (kind and particle)."""
    setups = [(s.setup.name, setup_spec_channels(s.setup)) for s in result.setups]
    return result.setups[_match(result.study.name, setups, waveform)]


def match_setup_spec(study: Study, waveform: Waveform) -> SetupSpec:
    """:func:`match_setup` on the study file alone, before anything is simulated."""
    setups = [(s.name, setup_spec_channels(s)) for s in study.setups]
    return study.setups[_match(study.name, setups, waveform)]


def setup_spec_channels(setup: SetupSpec) -> set[tuple[str, int]]:
    """(kind, particle) of a setup's sensors."""
    return {(s.kind.value, s.particle) for s in setup.sensors}


def check_units(waveform: Waveform) -> None:
    """Reject data whose metadata give another unit than volts (design.md §8)."""
    unit = waveform.metadata.get(UNITS_KEY)
    if unit is not None and unit != UNITS:
        raise InputError(f"the data's metadata say {UNITS_KEY}: {unit}; msens reads every "
                         f"channel in volts ({UNITS_KEY}: {UNITS}): convert the data to V")


def model_record(sensor: SensorResult, t: np.ndarray) -> np.ndarray:
    """The model record a calibrated measurement is compared with, shape (nt,).

    The sensor's force (N) for bead, rod and four-contact MsS; for a physics MsS the running
    integral of its DAQ voltage from impact (``t`` = 0), V s: the record ``msens run`` reads
    its features from (there in newtons, :attr:`msens.readout.mss.MssRecord.daq_force`).
    """
    if is_physics_mss(sensor):
        return integrated(sensor.voltage_shape, t)
    return sensor.force


def check_signal(setup: SetupResult, waveform: Waveform, source: str) -> None:
    """Refuse a waveform whose first shot is the model's upside down or on a scaled time
    axis (:func:`msens.signals.signalcheck.check_against_model`), naming the channel."""
    from msens.signals.signalcheck import check_against_model

    for j, ch in enumerate(waveform.channels):
        if ch.repeat != 1:
            continue
        sensor = _sensor(setup, ch)
        # the quantity the instrument records: a voltage shape (dF/dt for a four-contact
        # MsS, the DAQ voltage for a physics MsS) or the force itself (bead, rod)
        model = sensor.voltage_shape if sensor.voltage_shape is not None else sensor.force
        check_against_model(ch.name, source, waveform.time, waveform.data[:, j],
                            setup.history.t, model)


def _model_force(setup: SetupResult, sensor: SensorResult) -> np.ndarray:
    return model_record(sensor, setup.history.t)


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
    """Impact-to-trigger delay of one shot, s, from its top channel (smallest particle).

    A physics MsS channel is aligned by its voltage (mean removed, both low-passed) against
    the model's DAQ voltage; the others by their force-like record against the model force.
    """
    top = min(channels, key=lambda c: c.particle)
    sensor = _sensor(setup, top)
    tau = waveform.time
    if is_physics_mss(sensor):
        v = np.asarray(waveform.channel(top), dtype=float)
        measured = smooth(v - v.mean(), waveform.dt)
        model_on_tau = smooth(np.interp(tau, setup.history.t, sensor.voltage_shape,
                                        left=0.0, right=0.0), waveform.dt)
    else:
        measured = _force_like(waveform, top, top.kind)
        model_on_tau = np.interp(tau, setup.history.t, _model_force(setup, sensor),
                                 left=0.0, right=0.0)
    # measured(tau) ~ model(tau + D): it leads the model by D, so the lag found is -D
    lag = xcorr_delay(model_on_tau, measured, waveform.dt)
    return -lag


def _sensor(setup: SetupResult, channel: Channel) -> SensorResult:
    for s in setup.sensors:
        if s.sensor.kind.value == channel.kind and s.sensor.particle == channel.particle:
            return s
    raise InputError(f"channel {channel.name} has no sensor in setup {setup.setup.name!r}")


def _physics_record(setup: SetupResult, sensor: SensorResult, waveform: Waveform,
                    ch: Channel, delay: float) -> ShotRecord:
    """A physics MsS channel processed like the model (see the module docstring)."""
    t = setup.history.t
    v = np.interp(t, waveform.time + delay, np.asarray(waveform.channel(ch), dtype=float),
                  left=np.nan, right=np.nan)
    ok = np.flatnonzero(np.isfinite(v))
    model_v = sensor.voltage_shape
    if ok.size < 10:
        raise InputError(f"channel {ch.name}: the record covers {ok.size} samples of the "
                         f"model's time span (0 .. {t[-1] * 1e6:.0f} us after impact)")
    seg = slice(ok[0], ok[-1] + 1)  # the covered samples are contiguous
    design = np.column_stack((model_v[seg], np.ones(ok.size)))
    (slope, offset), *_ = np.linalg.lstsq(design, v[seg], rcond=None)
    corr = float(np.corrcoef(v[seg], model_v[seg])[0, 1]) if np.std(v[seg]) > 0 else 0.0
    if not (slope > 0 and corr >= MIN_PULSE_CORRELATION):
        raise InputError(
            f"channel {ch.name}: no pulse found: after alignment the record correlates "
            f"with the model's coil voltage at {corr:.2f} (a pulse gives > "
            f"{MIN_PULSE_CORRELATION}) with fitted gain {slope:.3g} V/V")
    gain = 1.0 / float(slope)
    model = model_record(sensor, t)
    raw = np.full(t.size, np.nan)
    # both integrals start at the record's first sample from the model's value there
    raw[seg] = model[ok[0]] / gain + cumulative_trapezoid(v[seg] - offset, t[seg], initial=0.0)
    held = np.concatenate((np.full(ok[0], raw[ok[0]]), raw[seg],
                           np.full(t.size - ok[-1] - 1, raw[ok[-1]])))
    feats = pulse_features(gain * smooth(held, float(t[1] - t[0])), t)
    return ShotRecord(channel=ch, t=t, raw=raw, gain=gain, delay_s=delay, features=feats,
                      model=model, offset=float(offset))


def shot_records(setup: SetupResult, waveform: Waveform) -> list[list[ShotRecord]]:
    """Aligned and calibrated records, per shot and channel."""
    t = setup.history.t
    model_peak = {id(s): float(lowpassed_features(_model_force(setup, s), t).f_incident)
                  for s in setup.sensors}
    out = []
    for channels in _shots(waveform):
        delay = align_shot(setup, waveform, channels)
        records = []
        for ch in channels:
            sensor = _sensor(setup, ch)
            if is_physics_mss(sensor):
                records.append(_physics_record(setup, sensor, waveform, ch, delay))
                continue
            raw = np.interp(t, waveform.time + delay, _force_like(waveform, ch, ch.kind),
                            left=np.nan, right=np.nan)
            filled = smooth(np.where(np.isfinite(raw), raw, 0.0), float(t[1] - t[0]))
            f_raw = pulse_features(filled, t)
            if not np.isfinite(f_raw.f_incident) or f_raw.f_incident == 0:
                raise InputError(f"channel {ch.name}: no incident pulse found")
            gain = model_peak[id(sensor)] / float(f_raw.f_incident)
            feats = pulse_features(gain * filled, t)
            records.append(ShotRecord(channel=ch, t=t, raw=raw, gain=gain, delay_s=delay,
                                      features=feats, model=sensor.force))
        out.append(records)
    return out


def _peak_unit(sensor: SensorResult) -> str:
    return "V_s" if is_physics_mss(sensor) else "N"


def gain_unit(sensor: SensorResult) -> str:
    """Unit of a channel's conversion factor K."""
    if is_physics_mss(sensor):
        return "V/V"
    return "N/(V s)" if sensor.sensor.kind is SensorKind.MSS else "N/V"


def _check_coverage(record: ShotRecord, m: PulseFeatures) -> None:
    """The aligned record must span the model's incident and reflected peaks: outside it,
    features would be taken from whatever the record holds instead (ringing, noise)."""
    covered = record.t[np.isfinite(record.raw)]
    first, last = float(covered[0]), float(covered[-1])
    for label, when in (("incident", m.t_incident), ("reflected", m.t_reflected)):
        if np.isfinite(when) and not first <= float(when) <= last:
            raise InputError(
                f"channel {record.channel.name}: no {label} pulse in the record: aligned "
                f"with the model it covers {first * 1e6:.0f} .. {last * 1e6:.0f} us after "
                f"impact, the model's {label} peak is at {float(when) * 1e6:.0f} us")


def _metrics(record: ShotRecord, setup: SetupResult, sensor: SensorResult,
             m: PulseFeatures) -> dict[str, float]:
    _check_coverage(record, m)
    model = _model_force(setup, sensor)
    ok = np.isfinite(record.raw)
    diff = record.force[ok] - model[ok]
    scale = float(np.max(np.abs(model[ok])))
    corr = float(np.corrcoef(record.force[ok], model[ok])[0, 1])
    f = record.features
    unit = _peak_unit(sensor)
    out = {
        # one convention with synth and diagnose: measured = gain x model; K (Eq. 11) is
        # its inverse
        GAIN_KEY: 1.0 / record.gain,
        "conversion_factor_K": record.gain,
        "tof_us": float(f.tof) * 1e6,
        "ar": float(f.ar),
        "width_us": float(f.width) * 1e6,
        f"incident_peak_{unit}": float(f.f_incident),
        f"reflected_peak_{unit}": float(f.f_reflected),
        "incident_time_error_us": float(f.t_incident - m.t_incident) * 1e6,
        "reflected_time_error_us": float(f.t_reflected - m.t_reflected) * 1e6,
        "nrmse": float(np.sqrt(np.mean(diff**2)) / scale),
        "correlation": corr,
    }
    if is_physics_mss(sensor):
        out["offset_V"] = record.offset
    bad = [k for k, x in out.items() if not np.isfinite(x)]
    if bad:
        missing = ("no reflected pulse found" if not np.isfinite(f.f_reflected)
                   else "no pulse width found" if not np.isfinite(f.width)
                   else "non-finite metrics")
        raise InputError(
            f"channel {record.channel.name}: {missing} in the measured record "
            f"({', '.join(bad)} undefined; it covers {record.t[ok][0] * 1e6:.0f} .. "
            f"{record.t[ok][-1] * 1e6:.0f} us after impact, the model's reflected peak is "
            f"at {float(m.t_reflected) * 1e6:.0f} us)")
    return out


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
        ``{"setup", "shots", "model_processing", "channels": [{"channel", "kind",
        "particle", "model": {...}, "run": {...}, "measured": {metric: {"mean", "std"}},
        "gain_measured_per_model_unit", "K_unit", "record"}], "gain_convention",
        "speed": {...}}`` — the content of ``compare.json``. ``gain_measured_per_model``
        (measured = gain x model, as synth's ``truth_gain_*`` and diagnose's gains) is in
        V/N (bead, rod), V/(N/s) (four-contact MsS) or V/V (physics MsS);
        ``conversion_factor_K``, its inverse (paper Eq. 11), in N/V, N/(V s) or V/V. The model's
        features come from the pipeline of ``msens run``
        (:func:`msens.signals.features.model_features`) with one difference, named in
        ``model_processing``: the records are low-passed as the measured ones are
        (:data:`MODEL_PROCESSING`); ``run`` holds the unfiltered values ``msens run``
        reports (a physics MsS's peaks there in newtons of sensitivity-weighted force, here
        in V s of integrated DAQ voltage) and ``speed.run_m_per_s`` its speed.

    Raises
    ------
    InputError
        If no setup matches the data's channels, the metadata give a unit other than V, or
        a measured record has no pulse (or no reflected pulse) to take features from.
    """
    check_units(waveform)
    setup = match_setup(result, waveform)
    shots = shot_records(setup, waveform)
    t = setup.history.t
    channels = []
    model_feats = {}
    for sensor in setup.sensors:
        m = lowpassed_features(_model_force(setup, sensor), t)
        model_feats[sensor.sensor.particle] = m
        per_shot = [
            _metrics(r, setup, sensor, m) for recs in shots for r in recs
            if r.channel.kind == sensor.sensor.kind.value
            and r.channel.particle == sensor.sensor.particle
        ]
        unit = _peak_unit(sensor)
        model = {"tof_us": float(m.tof) * 1e6, "ar": float(m.ar),
                 "width_us": float(m.width) * 1e6,
                 f"incident_peak_{unit}": float(m.f_incident)}
        f = sensor.features
        entry = {
            "channel": f"{sensor.sensor.kind.value}@{sensor.sensor.particle}",
            "kind": sensor.sensor.kind.value,
            "particle": sensor.sensor.particle,
            "model": model,
            "run": {"tof_us": float(f.tof) * 1e6, "ar": float(f.ar),
                    "width_us": float(f.width) * 1e6},
            "measured": _stats(per_shot),
            f"{GAIN_KEY}_unit": measured_gain_unit(sensor),
            "K_unit": gain_unit(sensor),
        }
        if is_physics_mss(sensor):
            entry["record"] = "integrated DAQ voltage, V s"
        channels.append(entry)
    out = {"setup": setup.setup.name, "shots": len(shots),
           "gain_convention": f"{GAIN_CONVENTION} ({GAIN_KEY}, as synth's truth_gain_*); "
                              "conversion_factor_K = 1 / gain, model per measured volt "
                              "(paper Eq. 11)",
           "model_processing": model_processing(), "channels": channels}
    parts = sorted(s.sensor.particle for s in setup.sensors)
    if len(parts) >= 2:
        d = centre_distance(setup.chain.length, parts[0], parts[-1])
        speeds = []
        for recs in shots:
            by_p = {r.channel.particle: r for r in recs}
            if parts[0] in by_p and parts[-1] in by_p:
                speeds.append(float(wave_speed(d, by_p[parts[0]].features.t_incident,
                                               by_p[parts[-1]].features.t_incident)))
        # the measured speed comes from low-passed records: so does the model's
        model_speed = float(wave_speed(d, model_feats[parts[0]].t_incident,
                                       model_feats[parts[-1]].t_incident))
        out["speed"] = {"model_m_per_s": model_speed, "run_m_per_s": setup.speed_incident,
                        "measured_m_per_s": {"mean": float(np.mean(speeds)),
                                             "std": float(np.std(speeds, ddof=1))
                                             if len(speeds) > 1 else 0.0}}
    return out


def model_processing() -> dict:
    """What a workflow that reads the model's features as measured ones does to them beyond
    ``msens run`` (the ``model_processing`` of ``compare.json`` and ``diagnosis.json``)."""
    return {"lowpass_hz": FEATURE_CUTOFF_HZ, "description": MODEL_PROCESSING}

"""Synthetic measurements: model records dressed with the effects of a real rig.

A synthetic shot is the model's sensor record seen through an unknown channel gain, a DC
offset, a trigger delay with shot-to-shot jitter, white noise and the DAQ's sampling. The
truth (gains, delays) is written into the metadata under ``truth_*`` keys so that tests can
score what calibration and diagnosis recover; nothing in msens reads those keys back.

Every channel is written in volts (metadata ``units: V``, design.md §8). What the volts are
depends on the sensor's model:

- bead, rod: dynamic force (N) times a gain in V/N (:attr:`RigEffects.gain_force`);
- four-contact MsS: d(force)/dt (N/s) times a gain in V per N/s (paper Eq. 5,
  :attr:`RigEffects.gain_rate`);
- physics MsS: the predicted DAQ voltage (V) times an amplifier gain of order 1, V/V
  (:attr:`RigEffects.gain_amplifier`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msens.config.schema import MssModel
from msens.io.waveform import Channel, Waveform
from msens.readout.sensors import SensorKind
from msens.results import SensorResult, SetupResult

#: Metadata key and value saying what unit the channels' samples are in.
UNITS_KEY = "units"
UNITS = "V"
#: The one convention for a channel's gain in msens (synth's ``truth_gain_*``, compare's and
#: diagnose's fitted gains): measured volts = gain x the model's record, so the gain is in
#: V/N (bead, rod), V per N/s (four-contact MsS) or V/V (physics MsS). The paper's
#: conversion factor K (Eq. 11, model per measured volt) is its inverse.
GAIN_KEY = "gain_measured_per_model"
#: Metadata key naming the convention in a synthetic file (files written before it have
#: the same convention).
GAIN_CONVENTION_KEY = "gain_convention"
GAIN_CONVENTION = "measured = gain x model"


@dataclass(frozen=True)
class RigEffects:
    """What a real acquisition adds to a model record.

    Attributes
    ----------
    shots : int
        Number of repeated shots (channels get ``#k`` suffixes when > 1).
    noise : float
        White-noise standard deviation as a fraction of each channel's peak, dimensionless.
    trigger_delay_s : tuple of float
        Range (s) of the unknown delay between impact and the record's t = 0.
    jitter_s : float
        Shot-to-shot trigger jitter, uniform in ±jitter_s, s.
    pretrigger_s : float
        Record length before the trigger, s.
    gain_force : tuple of float
        Range (log-uniform) of bead/rod channel gains, V/N.
    gain_rate : tuple of float
        Range (log-uniform) of four-contact MsS gains, V per N/s.
    gain_amplifier : tuple of float
        Range (log-uniform) of the amplifier gain after a physics MsS, whose model record is
        already the DAQ voltage, V/V.
    offset : float
        DC offset range, ± fraction of the channel's peak.
    seed : int
        Seed of the random generator: same seed, same data.
    """

    shots: int = 1
    noise: float = 0.01
    trigger_delay_s: tuple[float, float] = (20e-6, 60e-6)
    jitter_s: float = 0.5e-6
    pretrigger_s: float = 20e-6
    gain_force: tuple[float, float] = (0.02, 0.2)
    gain_rate: tuple[float, float] = (1e-8, 1e-7)
    gain_amplifier: tuple[float, float] = (0.5, 2.0)
    offset: float = 0.02
    seed: int = 0


def model_signal(sensor: SensorResult) -> np.ndarray:
    """What a sensor's output is proportional to, shape (nt,).

    Bead and rod: dynamic force, N. Four-contact MsS: d(force)/dt, N/s (paper Eq. 5). A
    physics MsS: its predicted DAQ voltage, V.
    """
    if sensor.sensor.kind is SensorKind.MSS:
        return sensor.voltage_shape
    return sensor.force


def is_physics_mss(sensor: SensorResult) -> bool:
    """Whether the sensor's model record is a DAQ voltage in volts (a physics MsS)."""
    return sensor.sensor.kind is SensorKind.MSS and sensor.sensor.model is MssModel.PHYSICS


def gain_bounds(sensor: SensorResult, effects: RigEffects) -> tuple[float, float]:
    """Range of the unknown gain between :func:`model_signal` and the channel's volts."""
    if is_physics_mss(sensor):
        return effects.gain_amplifier
    if sensor.sensor.kind is SensorKind.MSS:
        return effects.gain_rate
    return effects.gain_force


def truth_gain_key(kind: str, particle: int) -> str:
    """Metadata key holding a synthetic channel's true gain (:data:`GAIN_CONVENTION`)."""
    return f"truth_gain_{kind}_{particle}"


def gain_unit(sensor: SensorResult) -> str:
    """Unit of a channel's gain (:data:`GAIN_CONVENTION`): measured volts per model unit."""
    if is_physics_mss(sensor):
        return "V/V"
    return "V/(N/s)" if sensor.sensor.kind is SensorKind.MSS else "V/N"


def _log_uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    lo, hi = np.log(bounds[0]), np.log(bounds[1])
    return float(np.exp(rng.uniform(lo, hi)))


def synthesize(setup: SetupResult, effects: RigEffects = RigEffects(), *,
               metadata: dict[str, str] | None = None) -> Waveform:
    """Synthetic measured waveform of one simulated setup.

    Parameters
    ----------
    setup : SetupResult
        A simulated setup (see :func:`msens.pipeline.run_study`).
    effects : RigEffects
    metadata : dict, optional
        Extra ``key: value`` metadata.

    Returns
    -------
    Waveform
        Channels ``<kind>@<particle>[#k]``, volts, on the model's sample grid shifted so
        that t = 0 is the trigger. Metadata: ``units: V``, the effects and the truth
        (``truth_gain_<kind>_<particle>``: the gain of :func:`gain_bounds`, V/N, V per N/s
        or V/V, measured = gain x model as ``gain_convention`` says;
        ``truth_trigger_delay_s``, ``truth_delay_s_<k>``: impact to trigger, s).
    """
    rng = np.random.default_rng(effects.seed)
    t = setup.history.t
    dt = float(t[1] - t[0])
    n_pre = round(effects.pretrigger_s / dt)
    delay = float(rng.uniform(*effects.trigger_delay_s))
    # the record spans the model's time span, starting n_pre samples before the trigger
    n_rec = t.size - int(np.ceil((delay + effects.jitter_s) / dt)) + n_pre - 1
    tau = (np.arange(n_rec) - n_pre) * dt
    sensors = setup.sensors
    # one draw per sensor whatever its kind, so a seed gives the other channels the same data
    gains = [_log_uniform(rng, gain_bounds(s, effects)) for s in sensors]
    columns, channels = [], []
    meta = {UNITS_KEY: UNITS, "synthetic": "true", "seed": str(effects.seed),
            "setup": setup.setup.name, "shots": str(effects.shots),
            "noise_fraction": repr(effects.noise), "truth_trigger_delay_s": repr(delay),
            GAIN_CONVENTION_KEY: GAIN_CONVENTION}
    for s, g in zip(sensors, gains, strict=True):
        meta[truth_gain_key(s.sensor.kind.value, s.sensor.particle)] = repr(g)
    jitters = rng.uniform(-effects.jitter_s, effects.jitter_s, effects.shots)
    for k in range(effects.shots):
        shot_delay = delay + jitters[k]
        meta[f"truth_delay_s_{k + 1}"] = repr(float(shot_delay))
        for s, g in zip(sensors, gains, strict=True):
            sig = g * model_signal(s)
            peak = float(np.max(np.abs(sig)))
            clean = np.interp(tau + shot_delay, t, sig, left=0.0, right=0.0)
            offset = rng.uniform(-effects.offset, effects.offset) * peak
            noisy = clean + offset + rng.normal(0.0, effects.noise * peak, tau.size)
            columns.append(noisy)
            channels.append(Channel(s.sensor.kind.value, s.sensor.particle,
                                    k + 1))
    meta.update(metadata or {})
    return Waveform(time=tau, data=np.column_stack(columns), channels=tuple(channels),
                    metadata=meta)

"""Sampled signals: processing, pulse features, checks of measured records.

- :mod:`.features` — incident and reflected pulses, TOF, AR, speed, width.
- :mod:`.processing` — baseline, shot statistics, drift-corrected integration, filters.
- :mod:`.alignment` — threshold crossings, cross-correlation delays, aligned shots.
- :mod:`.signalcheck` — checks that a measured record carries a signal to compare.
"""

from msens._lazy import attribute, names

_HOMES = {
    "features": ("PulseFeatures", "centre_distance", "expected_round_trip", "pulse_features",
                 "wave_speed"),
    "processing": ("ShotStatistics", "bandpass", "baseline", "highpass",
                   "integrate_drift_corrected", "lowpass", "remove_baseline", "shot_statistics"),
    "alignment": ("align_shots", "shift_signal", "threshold_crossing", "xcorr_delay"),
    "signalcheck": ("check_against_model", "check_amplitudes", "check_pulses", "check_shots",
                    "noise_level", "orientation", "pulse_width"),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)

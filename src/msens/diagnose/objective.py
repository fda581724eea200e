"""How far a predicted set of sensor records is from the measurement.

Two objectives share one interface (``rss(records) -> (sensors,)``, ``n_obs``, ``sigma``):

- :class:`WaveformObjective`: the measured channels of every shot against the model's
  channel signals (force for bead and rod, dF/dt for the four-contact MsS, paper Eq. 5).
  Per shot one time offset D (impact to trigger) common to all channels — a single offset
  keeps the delays between sensors, which carry the speed — and per shot and channel one
  gain and one DC offset, all profiled out: for a given D, gain (kept >= 0) and offset are
  the linear least-squares fit y ~ g m + b (the pre-trigger mean removes the offset only to
  ~noise / sqrt(pre-trigger samples), which over a whole record would otherwise cost chi^2 of
  order tens and bias shape parameters), and D is found by an FFT cross-correlation over
  +-``MAX_SHIFT_S`` followed by a bounded Brent refinement of the exact residual. The model
  is interpolated onto the data's own sample times, so the data's noise stays white and
  independent (what the BIC assumes). The channel's noise ``sigma`` is the standard
  deviation of its pre-trigger samples.
- :class:`FeatureObjective`: published features (TOF and AR per sensor, e.g. the paper's
  Table 2) against the model's, each residual divided by the published shot-to-shot std.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft
from scipy.optimize import minimize_scalar

from msens.compare import align_shot
from msens.diagnose.predict import feature_records, model_features_of, signal
from msens.errors import InputError
from msens.io.waveform import Channel, Waveform
from msens.results import SetupResult
from msens.sensors import SensorKind
from msens.study import MssModel, ReferenceRow, SetupSpec

#: Largest change of the impact-to-trigger offset searched per candidate model, s. A 3x
#: faster striker moves the first arrival by less than this.
MAX_SHIFT_S = 80e-6
#: Fewest pre-trigger samples for a noise estimate.
MIN_PRETRIGGER = 20
#: A channel is usable when its largest excursion exceeds this many noise stds.
MIN_SNR = 8.0


@dataclass(frozen=True)
class Shot:
    """One shot's channels, baseline-free, in the order of the setup's sensors.

    Attributes
    ----------
    tau : ndarray, shape (n,)
        Record times (trigger = 0) used in the fit, s.
    y : ndarray, shape (sensors, n)
        Measured signals, V.
    sigma : ndarray, shape (sensors,)
        Pre-trigger noise std, V (NaN when the record has too few pre-trigger samples).
    delay0 : float
        Impact-to-trigger offset found against the baseline model, s (model t = tau + D).
    """

    tau: np.ndarray
    y: np.ndarray
    sigma: np.ndarray
    delay0: float


@dataclass(frozen=True)
class Alignment:
    """The profiled nuisance parameters of one shot for one model."""

    delay: float
    gains: np.ndarray
    offsets: np.ndarray
    rss: np.ndarray


def check_channels(waveform: Waveform) -> None:
    """Fail early (before any simulation) on a channel without a pulse above its noise.

    Raises
    ------
    InputError
        A channel whose largest excursion from its pre-trigger mean is not above
        ``MIN_SNR`` x its pre-trigger std (or is not positive at all).
    """
    tau = waveform.time
    pre = tau < 0.0
    for j, ch in enumerate(waveform.channels):
        v = np.asarray(waveform.data[:, j], dtype=float)
        if pre.sum() >= MIN_PRETRIGGER:
            v = v - v[pre].mean()
            noise = float(np.std(v[pre], ddof=1))
        else:
            noise = 0.0
        peak = float(np.max(np.abs(v)))
        if not (peak > 0.0 and peak > MIN_SNR * noise):
            raise InputError(f"channel {ch.name} has no usable pulse (peak {peak:.3g} V "
                             f"against pre-trigger noise {noise:.3g} V; needs > {MIN_SNR:g}x)")


def _shots(waveform: Waveform) -> list[list[Channel]]:
    repeats = sorted({c.repeat for c in waveform.channels})
    return [[c for c in waveform.channels if c.repeat == r] for r in repeats]


class WaveformObjective:
    """Residual of model signals against measured shots (see module docstring).

    Parameters
    ----------
    waveform : Waveform
        Measured channels; every channel must match a sensor of ``baseline.setup``.
    baseline : SetupResult
        The baseline model, used once to find each shot's starting time offset.
    kinds : tuple of SensorKind
        Observation kind of each sensor (the setup's order).

    Raises
    ------
    InputError
        When no channel carries a pulse above the noise (``MIN_SNR``).
    """

    def __init__(self, waveform: Waveform, baseline: SetupResult) -> None:
        setup = baseline.setup
        self.kinds = tuple(s.kind for s in setup.sensors)
        #: Whether each sensor is a physics MsS (its model record is the DAQ voltage).
        self.physics = tuple(s.model is MssModel.PHYSICS for s in setup.sensors)
        self.t = baseline.history.t
        self.dt = float(self.t[1] - self.t[0])
        t_end = float(self.t[-1])
        self.shots: list[Shot] = []
        for channels in _shots(waveform):
            by_key = {(c.kind, c.particle): c for c in channels}
            order = [by_key[(s.kind.value, s.particle)] for s in setup.sensors]
            delay0 = align_shot(baseline, waveform, channels)
            tau = waveform.time
            keep = tau + delay0 <= t_end - MAX_SHIFT_S - 5 * self.dt
            pre = tau < 0.0
            ys, sig = [], []
            for ch in order:
                v = np.asarray(waveform.channel(ch), dtype=float)
                base = v[pre].mean() if pre.sum() >= MIN_PRETRIGGER else np.median(v[:50])
                v = v - base
                ys.append(v[keep])
                sig.append(float(np.std(v[pre], ddof=1)) if pre.sum() >= MIN_PRETRIGGER
                           else np.nan)
            self.shots.append(Shot(tau=tau[keep], y=np.array(ys), sigma=np.array(sig),
                                   delay0=float(delay0)))
        self._check_usable(waveform, setup)
        sig = np.array([s.sigma for s in self.shots])
        #: Pre-trigger noise std per sensor (RMS over shots), V; NaN if unknown.
        self.sigma = np.sqrt(np.mean(sig**2, axis=0))
        #: Samples per sensor over all shots.
        self.n_obs = np.full(len(self.kinds), sum(s.tau.size for s in self.shots), dtype=float)
        self._weights = np.where(np.isfinite(self.sigma), 1.0 / self.sigma**2, 1.0)

    def _check_usable(self, waveform: Waveform, setup: SetupSpec) -> None:
        for j, spec in enumerate(setup.sensors):
            for s in self.shots:
                y = s.y[j]
                noise = s.sigma[j] if np.isfinite(s.sigma[j]) else 0.0
                peak = float(np.max(np.abs(y))) if y.size else 0.0
                if not (np.isfinite(peak) and peak > 0.0 and peak > MIN_SNR * noise):
                    raise InputError(
                        f"channel {spec.kind.value}@{spec.particle} has no usable pulse "
                        f"(peak {peak:.3g} V against noise {noise:.3g} V; needs > {MIN_SNR:g}x "
                        f"the pre-trigger noise)")

    # ---------------------------------------------------------------- evaluation

    def signals(self, records: np.ndarray) -> np.ndarray:
        """Model signals (sensors, nt) of model records (sensors, nt)."""
        return np.array([signal(k, r, self.t, ph) for k, r, ph
                         in zip(self.kinds, records, self.physics, strict=True)])

    def _rss_at(self, shot: Shot, sig: np.ndarray, delay: float) -> Alignment:
        m = np.array([np.interp(shot.tau + delay, self.t, s, left=0.0, right=0.0)
                      for s in sig])
        # least squares y ~ g m + b per channel (2x2 normal equations), g kept >= 0
        n = float(shot.tau.size)
        sm, sy = m.sum(axis=1), shot.y.sum(axis=1)
        mm = np.einsum("ij,ij->i", m, m)
        ym = np.einsum("ij,ij->i", shot.y, m)
        yy = np.einsum("ij,ij->i", shot.y, shot.y)
        det = n * mm - sm**2
        ok = det > 1e-12 * n * np.maximum(mm, 1e-300)
        g = np.where(ok, (n * ym - sm * sy) / np.where(ok, det, 1.0), 0.0)
        g = np.maximum(g, 0.0)
        b = (sy - g * sm) / n
        rss = yy + g**2 * mm + n * b**2 - 2 * g * ym - 2 * b * sy + 2 * g * b * sm
        return Alignment(delay=delay, gains=g, offsets=b, rss=np.maximum(rss, 0.0))

    def align(self, shot: Shot, sig: np.ndarray) -> Alignment:
        """Best time offset and gains of ``shot`` for model signals ``sig`` (sensors, nt)."""
        nt = self.t.size
        yhat = np.array([np.interp(self.t - shot.delay0, shot.tau, y, left=0.0, right=0.0)
                         for y in shot.y])
        nfft = fft.next_fast_len(2 * nt)
        corr = fft.irfft(np.conj(fft.rfft(yhat, nfft)) * fft.rfft(sig, nfft), nfft)
        norm = np.einsum("ij,ij->i", sig, sig)
        w = self._weights / np.where(norm > 0, norm, 1.0)
        score = (w[:, None] * np.maximum(corr, 0.0) ** 2).sum(axis=0)
        lags = np.arange(nfft)
        lags[lags >= nfft // 2] -= nfft
        limit = int(MAX_SHIFT_S / self.dt)
        score[np.abs(lags) > limit] = -np.inf
        d1 = shot.delay0 + lags[int(np.argmax(score))] * self.dt
        opt = minimize_scalar(lambda d: float(self._weights @ self._rss_at(shot, sig, d).rss),
                              bounds=(d1 - 1.5 * self.dt, d1 + 1.5 * self.dt),
                              method="bounded", options={"xatol": 1e-3 * self.dt})
        return self._rss_at(shot, sig, float(opt.x))

    def rss(self, records: np.ndarray) -> np.ndarray:
        """Residual sum of squares per sensor over all shots, V^2, shape (sensors,).

        Parameters
        ----------
        records : ndarray, shape (sensors, nt)
            Model force records (N) on the model's output times.
        """
        sig = self.signals(records)
        return np.sum([self.align(s, sig).rss for s in self.shots], axis=0)

    def aligned(self, records: np.ndarray) -> list[tuple[Alignment, np.ndarray, np.ndarray]]:
        """Per shot: alignment, data on model time (tau + D) and the scaled model there.

        Returns
        -------
        list of (Alignment, t_data (n,), model (sensors, n)) with the data itself in
        ``self.shots[i].y``.
        """
        sig = self.signals(records)
        out = []
        for s in self.shots:
            a = self.align(s, sig)
            tm = s.tau + a.delay
            m = np.array([g * np.interp(tm, self.t, x, left=0.0, right=0.0) + b
                          for g, b, x in zip(a.gains, a.offsets, sig, strict=True)])
            out.append((a, tm, m))
        return out


class FeatureObjective:
    """Published features (TOF, AR per sensor) against the model's (see module docstring).

    Parameters
    ----------
    setup : SetupSpec
    rows : dict
        Reference row of each sensor position (``"top"``/``"bottom"``/``"single"``).
    positions : list of str
        Position of each sensor of ``setup`` (its order).
    t : ndarray, shape (nt,)
        Model output times, s.
    """

    def __init__(self, setup: SetupSpec, rows: dict[str, ReferenceRow],
                 positions: list[str], t: np.ndarray) -> None:
        self.physics = tuple(s.model is MssModel.PHYSICS for s in setup.sensors)
        missing = [p for p in positions if p not in rows]
        if missing:
            raise InputError(f"setup {setup.name!r}: the study has no [reference] row for "
                             f"position(s) {', '.join(missing)}")
        self.rows = [rows[p] for p in positions]
        self.t = t
        self.n_obs = np.full(len(positions), 2.0)
        self.sigma = np.ones(len(positions))

    def residuals(self, records: np.ndarray) -> np.ndarray:
        """Normalised residuals (sensors, 2): (TOF, AR) model minus measured over std."""
        f = model_features_of(feature_records(records, self.physics, self.t), self.t)
        out = np.empty((len(self.rows), 2))
        for j, r in enumerate(self.rows):
            out[j, 0] = (float(f.tof[j]) * 1e6 - r.tof_us) / r.tof_std_us
            out[j, 1] = (float(f.ar[j]) - r.ar) / r.ar_std
        return np.where(np.isfinite(out), out, 1e3)  # a missing reflection: a huge misfit

    def rss(self, records: np.ndarray) -> np.ndarray:
        """Sum of squared normalised residuals per sensor, shape (sensors,)."""
        return (self.residuals(records) ** 2).sum(axis=1)


def mss_kinds(kinds: tuple[SensorKind, ...]) -> bool:
    """Whether any sensor is an MsS (its signal is a rate)."""
    return any(k is SensorKind.MSS for k in kinds)

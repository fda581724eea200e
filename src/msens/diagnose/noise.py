"""The noise of a measurement, estimated before and independently of any model fit, and the
ensemble mean of a file's shots.

A diagnosis compares a model with the data; whether the remaining residual is "noise" must be
judged against a noise level that no fit has touched. Two estimates are model-free:

- the *pre-trigger record* (the part before t = 0, where the chain is still at rest): the
  white noise of one shot;
- the *scatter between shots* of a file: everything the rig does not repeat (noise, trigger
  jitter left after alignment, striker-speed jitter).

:func:`ensemble` aligns every shot of a file onto the first by whole samples (one common shift
per shot for all its channels: the trigger's jitter; whole samples keep the noise white and
uncorrelated), removes each shot's pre-trigger mean, and returns the ensemble mean with the
variance of each of its samples: per sample the shot-to-shot variance (ddof = 1, smoothed over
``SMOOTH_S``), never below the pre-trigger variance, divided by the number of shots. One shot:
the pre-trigger variance. A record without a pre-trigger part and with one shot falls back to
the sample-to-sample differences (robust MAD of the first differences over sqrt 2), said so in
``source``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft
from scipy.ndimage import uniform_filter1d

from msens.errors import InputError, internal
from msens.io.waveform import Waveform

#: Fewest pre-trigger samples for a noise estimate.
MIN_PRETRIGGER = 20
#: Window over which the shot-to-shot variance is averaged, s (a tenth of a pulse width: the
#: variance changes over the pulse, and 7 degrees of freedom per sample of an 8-shot file
#: are too few on their own).
SMOOTH_S = 2e-6
#: Largest shift between two shots of a file searched, s (the trigger's jitter; as
#: :data:`msens.diagnose.objective.MAX_SHIFT_S`).
MAX_SHOT_SHIFT_S = 80e-6
#: MAD to standard deviation of a normal distribution.
_MAD = 1.4826


@dataclass(frozen=True)
class Ensemble:
    """The mean of a file's shots and the variance of each of its samples.

    Attributes
    ----------
    tau : ndarray, shape (n,)
        Record time of the mean, s (the first shot's trigger at 0).
    y : ndarray, shape (sensors, n)
        Ensemble mean, each shot's pre-trigger mean removed, V.
    var : ndarray, shape (sensors, n)
        Variance of each sample of ``y``, V^2.
    sigma_pretrigger : ndarray, shape (sensors,)
        Noise std of one shot from its pre-trigger record (RMS over shots), V; NaN without
        a pre-trigger record.
    scatter : ndarray, shape (sensors,)
        RMS over the record of the shot-to-shot std, V; NaN for one shot.
    shots : int
    shifts : ndarray of int, shape (shots,)
        Samples by which each shot lags the first.
    source : str
        How ``var`` was estimated.
    dof : float
        Degrees of freedom of the noise estimate (the denominator of the F test of a
        residual against it).
    """

    tau: np.ndarray
    y: np.ndarray
    var: np.ndarray
    sigma_pretrigger: np.ndarray
    scatter: np.ndarray
    shots: int
    shifts: np.ndarray
    source: str
    dof: float

    def to_json(self, names: list[str]) -> dict:
        """The noise section of a report (per channel, V)."""
        return {"source": self.source, "shots": self.shots, "dof": self.dof,
                "shot_shifts_samples": [int(s) for s in self.shifts],
                "channels": [{"channel": n, "sigma_pretrigger_V": float(p),
                              "shot_scatter_V": float(s),
                              "sigma_of_mean_rms_V": float(np.sqrt(np.mean(v)))}
                             for n, p, s, v in zip(names, self.sigma_pretrigger, self.scatter,
                                                   self.var, strict=True)]}


def shot_matrix(waveform: Waveform, order: list[tuple[str, int]]) -> np.ndarray:
    """The records of every shot, shape (shots, sensors, nt), channels in ``order``.

    Raises
    ------
    InputError
        A shot lacks a channel of ``order`` or has one twice, or has a channel the setup
        does not read; or a channel holds non-finite values (e.g. a shorter shot padded).
    """
    repeats = sorted({c.repeat for c in waveform.channels})
    wanted = ", ".join(f"{k}@{p}" for k, p in order)
    out = np.empty((len(repeats), len(order), waveform.time.size))
    for i, r in enumerate(repeats):
        chans = [c for c in waveform.channels if c.repeat == r]
        keys = [(c.kind, c.particle) for c in chans]
        missing = [f"{k}@{p}" for k, p in order if (k, p) not in keys]
        extra = sorted({f"{k}@{p}" for k, p in keys if (k, p) not in order})
        if missing or extra or len(keys) != len(set(keys)):
            what = (f"has no channel {', '.join(missing)}" if missing else
                    f"has channel(s) {', '.join(extra)} that the others lack" if extra else
                    "repeats a channel")
            raise InputError(f"shot #{r} {what}: every shot of a file needs the same channels "
                             f"({wanted}); found {', '.join(c.name for c in chans)}")
        for j, key in enumerate(order):
            v = np.asarray(waveform.channel(chans[keys.index(key)]), dtype=float)
            if not np.all(np.isfinite(v)):
                raise InputError(f"channel {chans[keys.index(key)].name} has missing or "
                                 "non-finite samples: every shot must span the same "
                                 f"{waveform.time.size} time samples")
            out[i, j] = v
    return out


def _lag(ref: np.ndarray, rec: np.ndarray, limit: int) -> int:
    """Samples by which ``rec`` (sensors, nt) lags ``ref``, by the channels' summed
    normalised cross-correlation within +-limit."""
    nt = ref.shape[-1]
    nfft = fft.next_fast_len(2 * nt)
    norm = np.sqrt(np.einsum("ij,ij->i", ref, ref) * np.einsum("ij,ij->i", rec, rec))
    corr = fft.irfft(np.conj(fft.rfft(ref, nfft)) * fft.rfft(rec, nfft), nfft)
    score = (corr / np.where(norm > 0, norm, 1.0)[:, None]).sum(axis=0)
    lags = np.arange(nfft)
    lags[lags >= nfft // 2] -= nfft
    score[np.abs(lags) > limit] = -np.inf
    return int(lags[int(np.argmax(score))])


def ensemble(waveform: Waveform, order: list[tuple[str, int]],
             shifts: np.ndarray | None = None) -> Ensemble:
    """The aligned ensemble mean of a file's shots and its per-sample variance.

    Parameters
    ----------
    waveform : Waveform
        One or more shots (``#k`` repeats) of the same channels.
    order : list of (kind, particle)
        The channels, in the order of the setup's sensors.
    shifts : ndarray of int, shape (shots,), optional
        Samples by which each shot lags the first (e.g. from each shot's own fit,
        :mod:`msens.diagnose.shots`); default: the lag of the best cross-correlation with
        the first shot.

    Returns
    -------
    Ensemble

    Raises
    ------
    InputError
        Shots with different channels (see :func:`shot_matrix`).
    """
    data = shot_matrix(waveform, order)
    tau = waveform.time
    dt = float(waveform.dt)
    pre = tau < 0.0
    k = data.shape[0]
    if pre.sum() >= MIN_PRETRIGGER:
        data = data - data[..., pre].mean(axis=-1, keepdims=True)
        var_pre = data[..., pre].var(axis=-1, ddof=1)  # (shots, sensors)
    else:
        data = data - np.median(data[..., :50], axis=-1, keepdims=True)
        var_pre = None
    limit = max(1, int(MAX_SHOT_SHIFT_S / dt))
    if shifts is None:
        shifts = [0] + [_lag(data[0], data[i], limit) for i in range(1, k)]
    shifts = np.asarray(shifts, dtype=int)
    internal(shifts.shape == (k,) and not np.any(np.abs(shifts) >= tau.size // 2),
             f"internal: bad shot shifts {shifts} for {k} shots")
    # shot i at sample j + shift_i is the first shot at sample j, for j in [lo, hi)
    lo, hi = int(max(0, -shifts.min())), int(tau.size - max(0, shifts.max()))
    aligned = np.stack([data[i, :, lo + s:hi + s] for i, s in enumerate(shifts)])
    tau = tau[lo:hi]
    mean = aligned.mean(axis=0)
    sigma_pre = (np.sqrt(var_pre.mean(axis=0)) if var_pre is not None
                 else np.full(len(order), np.nan))
    smooth = max(1, round(SMOOTH_S / dt))
    if k > 1:
        scatter = uniform_filter1d(aligned.var(axis=0, ddof=1), smooth, axis=-1,
                                   mode="nearest")
        floor = var_pre.mean(axis=0)[:, None] if var_pre is not None else 0.0
        var1 = np.maximum(scatter, floor)
        source = (f"shot-to-shot scatter of {k} aligned shots (averaged over "
                  f"{SMOOTH_S * 1e6:g} us), at least the pre-trigger noise")
        dof = float((k - 1) * smooth)
        scatter_rms = np.sqrt(scatter.mean(axis=-1))
    elif var_pre is not None:
        var1 = np.broadcast_to(var_pre[0][:, None], mean.shape).copy()
        source = f"pre-trigger record ({int(pre.sum())} samples)"
        dof = float(pre.sum() - 1)
        scatter_rms = np.full(len(order), np.nan)
    else:
        d = np.diff(mean, axis=-1)
        s2 = (_MAD * np.median(np.abs(d - np.median(d, axis=-1, keepdims=True)), axis=-1)
              / np.sqrt(2.0)) ** 2
        var1 = np.broadcast_to(s2[:, None], mean.shape).copy()
        source = "sample-to-sample differences (no pre-trigger record, one shot)"
        dof = 0.37 * mean.shape[-1]  # efficiency of the MAD against the standard deviation
        scatter_rms = np.full(len(order), np.nan)
    var = var1 / k
    if not np.all(var > 0):
        raise InputError("the data have no noise at all (constant pre-trigger record and "
                         "identical shots): the diagnosis needs a noise estimate")
    return Ensemble(tau=tau, y=mean, var=var, sigma_pretrigger=sigma_pre, scatter=scatter_rms,
                    shots=k, shifts=shifts, source=source, dof=dof)

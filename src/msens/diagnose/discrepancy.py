"""The model-form discrepancy a fit leaves, estimated from its own residual.

The likelihood holds the noise, a diagonal model variance and the field model's modes
(:mod:`msens.diagnose.likelihood`, :mod:`msens.diagnose.field_modes`). Whatever else the
model gets wrong shows in the residual of the final fit as a *correlated* part: the noise is
white: whitened by the likelihood's standard deviation at each sample (sigma_t = 1/sqrt(w_t)),
the residual's periodogram has the level E|R(f)|^2 = n at every frequency, and the part of
the smoothed periodogram significantly above that level is the discrepancy's spectrum (in
whitened units; its draws are scaled back by sigma_t).

A parameter's interval from the curvature assumes that the residual is what the likelihood
says. The discrepancy that the data hold along the parameter's own signature is not visible
in the residual (the fit took it up: the residual is orthogonal to that signature at the
optimum), so its effect on the parameter is estimated by draws: Gaussian records with the
discrepancy's spectrum (random phases) and its variance profile in time (an envelope from
the Wiener-filtered residual), each added to the model, moving the optimum as
:func:`msens.diagnose.fit.field_spread` computes. The spread of those moves is the
discrepancy's part of the parameter's uncertainty. On a residual that is white at the
expected level the draws are zero and nothing widens.

Based on the "surrogate data" construction of Theiler et al., Physica D 58:77-94 (1992)
(phase-randomised records with a given power spectrum), with an amplitude envelope for
discrepancies that are concentrated around the pulses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft
from scipy.ndimage import gaussian_filter1d, uniform_filter1d

#: Joint draws of the discrepancy per named effect.
DRAWS = 32
#: Half-width of the running mean that smooths the periodogram, bins (a 17-bin average: the
#: periodogram's relative scatter of 1 drops to 0.24).
SMOOTH_BINS = 8
#: A smoothed periodogram counts as above the white level only beyond this many of its
#: standard deviations (1/sqrt(2 SMOOTH_BINS + 1) of the level): without it the noise's own
#: scatter would read as a discrepancy of ~10 % of a white residual's power.
SIGNIFICANCE = 2.0


@dataclass(frozen=True)
class Discrepancy:
    """One channel's estimated discrepancy.

    Attributes
    ----------
    spectrum : ndarray, shape (n // 2 + 1,)
        Its power at each rfft frequency of the whitened record (unnormalised rfft, like
        the periodogram it comes from; dimensionless).
    envelope : ndarray, shape (n,)
        Its standard deviation at each sample, V.
    share : float
        Its part of the residual's power, in [0, 1]; the rest is what the likelihood
        expects (noise, model variance).
    """

    spectrum: np.ndarray
    envelope: np.ndarray
    share: float

    def to_json(self) -> dict:
        return {"share_of_residual": float(self.share),
                "rms_V": float(np.sqrt(np.mean(self.envelope**2)))}


def estimate(residual: np.ndarray, variance: np.ndarray) -> Discrepancy:
    """The discrepancy in one channel's residual.

    Parameters
    ----------
    residual : ndarray, shape (n,)
        Data less the fitted model on the data's samples, V.
    variance : ndarray, shape (n,)
        The variance the likelihood gives each sample (noise and diagonal model variance),
        V^2.

    Returns
    -------
    Discrepancy
    """
    # whitened by the likelihood's own standard deviation: white noise of any variance
    # profile becomes stationary with unit variance (level n in the periodogram)
    scale = np.sqrt(np.asarray(variance, dtype=float))
    r = np.asarray(residual, dtype=float) / scale
    n = r.size
    spec = fft.rfft(r)
    power = np.abs(spec) ** 2
    smooth = uniform_filter1d(power, 2 * SMOOTH_BINS + 1, mode="nearest")
    floor = float(n)
    excess = np.where(smooth > floor * (1.0 + SIGNIFICANCE / np.sqrt(2 * SMOOTH_BINS + 1)),
                      smooth - floor, 0.0)
    gain = np.divide(excess, smooth, out=np.zeros_like(smooth), where=smooth > 0)
    wiener = fft.irfft(spec * gain, n)
    weights = np.full(excess.size, 2.0)
    weights[0] = 1.0
    if n % 2 == 0:
        weights[-1] = 1.0
    total = float(weights @ excess)  # n^2 x the mean variance per sample (Parseval)
    if total <= 0.0:
        return Discrepancy(spectrum=excess, envelope=np.zeros(n), share=0.0)
    # the envelope: the Wiener estimate's square smoothed over a quarter of its mean period
    # (the spectrum's mean frequency), which removes the square's ripple at twice that
    # frequency to < 1 % and follows the pulses
    mean_bin = float(weights @ (excess * np.arange(excess.size))) / total
    width = 0.25 * n / max(mean_bin, 1.0)
    profile = gaussian_filter1d(wiener**2, max(width, 1.0), mode="constant")
    profile *= (total / n**2) / max(float(profile.mean()), 1e-300)
    share = total / max(float(weights @ power), 1e-300)
    return Discrepancy(spectrum=excess, envelope=np.sqrt(profile) * scale,
                       share=min(share, 1.0))


def draws(d: Discrepancy, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` Gaussian records (count, n), V, with the spectrum's shape and the
    envelope's standard deviation at each sample (zeros when there is no discrepancy)."""
    n = d.envelope.size
    if not np.any(d.envelope > 0):
        return np.zeros((count, n))
    amp = np.sqrt(d.spectrum)
    phase = rng.uniform(0.0, 2.0 * np.pi, size=(count, amp.size))
    s = fft.irfft(amp * np.exp(1j * phase), n, axis=-1)
    s /= np.sqrt(np.mean(s**2, axis=-1, keepdims=True))
    return s * d.envelope


def model_changes(objective, records: np.ndarray, count: int = DRAWS, seed: int = 0
                  ) -> tuple[np.ndarray, list[Discrepancy]]:
    """Draws of the discrepancy that the fitted ``records`` leave, as changes of the model's
    records, and the per-channel estimates.

    Parameters
    ----------
    objective : WaveformObjective
    records : ndarray, shape (sensors, nt)
        The fitted model's records on the model's times.
    count : int
    seed : int
        The draws' seed (a diagnosis is reproducible).

    Returns
    -------
    changes : ndarray, shape (count, sensors, nt)
        In the records' units: a data-side draw s becomes s / gain on the model's time axis
        (the objective fits data ~ gain x model + offset), zero outside the data's span.
    estimates : list of Discrepancy
        Per channel, from the first shot of the objective.
    """
    rng = np.random.default_rng(seed)
    a, tm, m = objective.aligned(records)[0]
    shot = objective.shots[0]
    changes = np.zeros((count, *records.shape))
    estimates = []
    for j in range(records.shape[0]):
        d = estimate(shot.y[j] - m[j], 1.0 / shot.w[j])
        estimates.append(d)
        g = float(a.gains[j])
        if g <= 0.0:
            continue
        for k, s in enumerate(draws(d, count, rng)):
            changes[k, j] = np.interp(objective.t, tm, s / g, left=0.0, right=0.0)
    return changes, estimates

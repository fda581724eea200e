"""The likelihood of a measured record given a model: the one that ``diagnose`` and
``calibrate`` share.

A measured sample y_i is the model's record m_i (after the record calibration: gain, offset,
time offset) plus two independent Gaussian errors:

- the measurement noise, variance ``noise_var`` (estimated without any fit:
  :mod:`msens.diagnose.noise`);
- the model's own error (model-form error), variance ``model_var``: what a correct but
  slightly different physics would change in the record. It is estimated from the model's
  signal by :class:`ModelUncertainty`: a relative amplitude error and a timing error that
  grows with the time since impact (a wave speed known to a fraction),
  ``model_var = (a m)^2 + (r t dm/dt)^2``.

so ``-2 ln L = sum_i r_i^2 / v_i + ln(2 pi v_i)`` with ``v_i = noise_var_i + model_var_i``.

A physics MsS's field-model error is also correlated over the record: a 1 % error of one
contact's sensitivity or one bead's pull moves whole lobes of the pulse. That part is a
low-rank covariance ``sum_k u_k u_k^T`` of record modes (:mod:`msens.diagnose.field_modes`),
whose amplitudes the objective profiles with their unit Gaussian prior
(:class:`msens.diagnose.objective.WaveformObjective`): by Woodbury's identity the same chi^2
as ``r^T (diag(v) + sum_k u_k u_k^T)^{-1} r``.
With the model variance fixed (computed once from the baseline model, as diagnose does) the
second term is a constant and ``chi^2 = sum r^2 / v`` is all a fit needs.

The size of the physics MsS's model uncertainty is measured, not assumed: changing the bias
magnets' remanence by 1 % (about a 2 % change of their pull on the beads and a 1 % change of
the contact sensitivities, the disagreement of two good field solvers) changes the main
study's two MsS records, with gain, offset and trigger delay profiled out, by 0.23-0.27 % of
their peak RMS and 0.7-1.0 % at most; 68-78 % of that change is a timing stretch of 0.08 %
of the time since impact, the rest a shape change of ~0.5 % of the signal.

API for calibration (``msens calibrate``): :func:`model_uncertainty` (per sensor),
:meth:`ModelUncertainty.variance`, then :func:`chi2` or :func:`log_likelihood` of the
residual, and :func:`variance_split` for the report.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msens.readout.sensors import SensorKind


@dataclass(frozen=True)
class ModelUncertainty:
    """Model-form error of one sensor's record, as a variance per sample.

    Attributes
    ----------
    relative_amplitude : float
        Std of the record's shape error as a fraction of the signal (dimensionless).
    relative_timing : float
        Std of the timing error as a fraction of the time since impact (dimensionless): a
        wave speed known to that fraction.
    reason : str
        Where the sizes come from.
    """

    relative_amplitude: float = 0.0
    relative_timing: float = 0.0
    reason: str = "none"

    def __post_init__(self) -> None:
        if not (self.relative_amplitude >= 0.0 and self.relative_timing >= 0.0):
            raise ValueError(f"model uncertainty must be >= 0, got {self}")

    def variance(self, m: np.ndarray, t_since_impact: np.ndarray) -> np.ndarray:
        """Model variance per sample, in the record's unit squared.

        Parameters
        ----------
        m : ndarray, shape (..., n)
            The model's record on the data's samples, in the data's unit (gain applied,
            offset removed), e.g. V.
        t_since_impact : ndarray, shape (n,)
            Time of each sample since striker impact, s (uniformly spaced).

        Returns
        -------
        ndarray, shape (..., n)
            ``(a m)^2 + (r t dm/dt)^2``.
        """
        m = np.asarray(m, dtype=float)
        t = np.asarray(t_since_impact, dtype=float)
        out = (self.relative_amplitude * m) ** 2
        if self.relative_timing > 0.0 and t.size > 1:
            slope = np.gradient(m, t, axis=-1)
            out = out + (self.relative_timing * np.maximum(t, 0.0) * slope) ** 2
        return out

    def to_json(self) -> dict:
        """The sizes and their reason, for reports."""
        return {"relative_amplitude": self.relative_amplitude,
                "relative_timing": self.relative_timing, "reason": self.reason}


#: A physics MsS: its record goes through the field model (the magnets' pull on the beads,
#: each contact's sensitivity), known to about 1 % (two good field solvers).
PHYSICS_MSS = ModelUncertainty(
    relative_amplitude=0.005, relative_timing=1e-3,
    reason="the field model's ~1 % accuracy (magnets' pull, contact sensitivities): a 1 % "
           "change of the bias magnets' remanence stretches the MsS records' timing by "
           "0.08 % of the time since impact and changes their shape by ~0.5 %; taken as "
           "0.1 % and 0.5 %")
#: A record without a field model (bead, rod, four-contact MsS): its model is the chain's,
#: whose uncertainty is that of the study's inputs (``msens uq``), not a model form.
NO_FIELD_MODEL = ModelUncertainty(
    reason="no field model in the record: the chain model alone (its inputs' uncertainty "
           "is msens uq's)")


def model_uncertainty(kind: SensorKind, physics: bool) -> ModelUncertainty:
    """The model-form error of a sensor's record.

    Parameters
    ----------
    kind : SensorKind
    physics : bool
        Whether the sensor is a physics MsS (its record is the DAQ voltage of a field model).

    Returns
    -------
    ModelUncertainty
    """
    return PHYSICS_MSS if kind is SensorKind.MSS and physics else NO_FIELD_MODEL


def chi2(residual: np.ndarray, noise_var: np.ndarray, model_var: np.ndarray | float = 0.0
         ) -> np.ndarray:
    """Residual squares over the likelihood's variance, per sample.

    Parameters
    ----------
    residual : ndarray, shape (..., n)
        Measured minus model, in the record's unit.
    noise_var, model_var : ndarray or float
        Variances (broadcast against ``residual``), unit squared.

    Returns
    -------
    ndarray, shape (..., n)
    """
    return np.asarray(residual) ** 2 / (np.asarray(noise_var) + np.asarray(model_var))


def log_likelihood(residual: np.ndarray, noise_var: np.ndarray,
                   model_var: np.ndarray | float = 0.0) -> float:
    """Gaussian log-likelihood of a residual with noise and model variance.

    Returns
    -------
    float
        ``-0.5 sum(r^2 / v + ln(2 pi v))``, v = noise_var + model_var.
    """
    v = np.broadcast_to(np.asarray(noise_var) + np.asarray(model_var),
                        np.shape(residual))
    return float(-0.5 * np.sum(np.asarray(residual) ** 2 / v + np.log(2 * np.pi * v)))


def variance_split(noise_var: np.ndarray, model_var: np.ndarray,
                   mask: np.ndarray | None = None) -> dict:
    """How much of the variance a residual is allowed is noise and how much model
    uncertainty, over the samples ``mask`` selects (all by default).

    Returns
    -------
    dict
        ``noise_share`` and ``model_uncertainty_share`` (fractions summing to 1).
    """
    n = np.asarray(noise_var, dtype=float)
    m = np.broadcast_to(np.asarray(model_var, dtype=float), n.shape)
    if mask is not None:
        n, m = n[mask], m[mask]
    total = float(np.sum(n) + np.sum(m))
    share = float(np.sum(m)) / total if total > 0 else 0.0
    return {"noise_share": 1.0 - share, "model_uncertainty_share": share}

"""How far a predicted set of sensor records is from the measurement.

Two objectives share one interface (``rss(records) -> (sensors,)``: chi^2 per sensor,
``n_obs``, ``sigma``):

- :class:`WaveformObjective`: the measured channels against the model's channel signals
  (force for bead and rod, dF/dt for the four-contact MsS, paper Eq. 5). The shots of a file
  are first merged into their aligned ensemble mean, whose per-sample variance comes from
  the pre-trigger record and the shot-to-shot scatter, never from a fit
  (:func:`msens.diagnose.noise.ensemble`), plus, once added, the model's own uncertainty
  (:mod:`msens.diagnose.likelihood`, the likelihood diagnose and calibrate share). Against
  it, one time offset D (impact to trigger) common to all channels — a single offset keeps
  the delays between sensors, which carry the speed — and per channel one gain and one DC
  offset, all profiled out: for a given D, gain (kept >= 0) and offset are the weighted
  linear least-squares fit y ~ g m + b (the pre-trigger mean removes the offset only to
  ~noise / sqrt(pre-trigger samples), which over a whole record would otherwise cost chi^2
  of order tens and bias shape parameters), and D is found by an FFT cross-correlation over
  +-``MAX_SHIFT_S`` followed by a bounded Brent refinement of the exact residual. The model
  is interpolated onto the data's own sample times, so the data's noise stays independent
  (what the BIC assumes). ``rss`` is the residual weighted by each sample's inverse variance
  (chi^2), so ``sigma`` is 1.
- :class:`FeatureObjective`: published features (TOF and AR per sensor, e.g. the paper's
  Table 2) against the model's, each residual divided by the published shot-to-shot std.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import fft
from scipy.optimize import minimize_scalar

from msens.compare import align_shot
from msens.config.schema import MssModel, ReferenceRow, SetupSpec
from msens.diagnose.likelihood import model_uncertainty, variance_split
from msens.diagnose.noise import MIN_PRETRIGGER, Ensemble, ensemble
from msens.diagnose.predict import feature_records, model_features_of, signal
from msens.errors import InputError, internal
from msens.io.waveform import Channel, Waveform
from msens.readout.sensors import SensorKind
from msens.results import SetupResult

#: Largest change of the impact-to-trigger offset searched per candidate model, s. A 3x
#: faster striker moves the first arrival by less than this.
MAX_SHIFT_S = 80e-6
#: With field-model modes, the whole samples on either side of the correlation's peak at
#: which the profiled chi^2 is compared before the sub-sample refinement.
LAG_WINDOW = 6
#: A channel is usable when its largest excursion exceeds this many noise stds.
MIN_SNR = 8.0
#: Field-model mode directions whose variance over the whole record is below this many
#: noise variances are dropped (:meth:`ModeBasis.of`): they cannot change chi^2 by more.
MODE_TOL = 1e-2


@dataclass(frozen=True)
class Shot:
    """The measured channels a model is fitted to (a file's ensemble mean), baseline-free, in
    the order of the setup's sensors.

    Attributes
    ----------
    tau : ndarray, shape (n,)
        Record times (trigger = 0) used in the fit, s.
    y : ndarray, shape (sensors, n)
        Measured signals, V.
    sigma : ndarray, shape (sensors,)
        Pre-trigger noise std of one shot, V (NaN without a pre-trigger record).
    delay0 : float
        Impact-to-trigger offset found against the baseline model, s (model t = tau + D).
    w : ndarray, shape (sensors, n)
        Inverse variance of each sample of ``y``, 1/V^2: of the noise and, once
        :meth:`WaveformObjective.add_model_uncertainty` is called, of the model's own
        uncertainty (:mod:`msens.diagnose.likelihood`).
    noise_var : ndarray, shape (sensors, n), optional
        The noise's part of that variance, V^2 (None: all of it).
    model_var : ndarray, shape (sensors, n), optional
        The model uncertainty's part, V^2 (None: none).
    modes : tuple of (ModeBasis or None), optional
        Per sensor, the directions in which its (scaled) model record may move within the
        field model's accuracy, one standard deviation each
        (:mod:`msens.diagnose.field_modes`); their amplitudes are profiled with a unit
        Gaussian prior. None: no such modes.
    """

    tau: np.ndarray
    y: np.ndarray
    sigma: np.ndarray
    delay0: float
    w: np.ndarray
    noise_var: np.ndarray | None = None
    model_var: np.ndarray | None = None
    modes: tuple | None = None


@dataclass(frozen=True)
class Alignment:
    """The profiled nuisance parameters of one shot for one model."""

    delay: float
    gains: np.ndarray
    offsets: np.ndarray
    rss: np.ndarray
    #: Per sensor, the profiled amplitudes along the field-model modes' principal
    #: directions (unit prior), and their sum in the record (n,) (None without modes).
    amplitudes: tuple | None = None
    shifts: tuple | None = None


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


def _first_shot(waveform: Waveform) -> list[Channel]:
    first = min(c.repeat for c in waveform.channels)
    return [c for c in waveform.channels if c.repeat == first]


class WaveformObjective:
    """Residual of model signals against measured shots (see module docstring).

    Parameters
    ----------
    waveform : Waveform
        Measured channels; every channel must match a sensor of ``baseline.setup``.
    baseline : SetupResult
        The baseline model, used once to find the starting time offset.
    shifts : ndarray of int, shape (shots,), optional
        Samples by which each shot lags the first (see :func:`msens.diagnose.noise.ensemble`).

    Raises
    ------
    InputError
        When no channel carries a pulse above the noise (``MIN_SNR``).
    """

    def __init__(self, waveform: Waveform, baseline: SetupResult,
                 shifts: np.ndarray | None = None) -> None:
        setup = baseline.setup
        self.kinds = tuple(s.kind for s in setup.sensors)
        #: Whether each sensor is a physics MsS (its model record is the DAQ voltage).
        self.physics = tuple(s.model is MssModel.PHYSICS for s in setup.sensors)
        self.t = baseline.history.t
        self.dt = float(self.t[1] - self.t[0])
        t_end = float(self.t[-1])
        #: The file's shots merged: ensemble mean, per-sample variance, noise estimates.
        self.ensemble: Ensemble = ensemble(
            waveform, [(s.kind.value, s.particle) for s in setup.sensors], shifts)
        ens = self.ensemble
        # the mean is on the first shot's record time
        delay0 = align_shot(baseline, waveform, _first_shot(waveform))
        keep = ens.tau + delay0 <= t_end - MAX_SHIFT_S - 5 * self.dt
        self.shots: list[Shot] = [Shot(tau=ens.tau[keep], y=ens.y[:, keep],
                                       sigma=ens.sigma_pretrigger, delay0=float(delay0),
                                       w=1.0 / ens.var[:, keep])]
        self._check_usable(waveform, setup)
        #: chi^2 is already in units of the noise: 1 per sensor.
        self.sigma = np.ones(len(self.kinds))
        #: Samples per sensor.
        self.n_obs = np.full(len(self.kinds), float(self.shots[0].tau.size))
        #: Mean inverse variance per sensor, 1/V^2 (weights of the coarse alignment).
        self._weights = self.shots[0].w.mean(axis=1)
        #: Each sensor's model uncertainty, once added (:meth:`add_model_uncertainty`).
        self.model_uncertainty: tuple = ()
        #: Each sensor's field-model modes, once added (None: not a physics MsS).
        self.field_modes: tuple = ()

    def _check_usable(self, waveform: Waveform, setup: SetupSpec) -> None:
        for j, spec in enumerate(setup.sensors):
            for s in self.shots:
                y = s.y[j]
                if y.size == 0:  # a mean over nothing: NaN and a numpy warning
                    raise InputError(
                        f"channel {spec.kind.value}@{spec.particle}: no sample of the record "
                        "falls inside the model's time window (from the striker's impact to "
                        "the study's simulation.t_end_s); check the record's time axis")
                noise = float(np.sqrt(np.mean(1.0 / s.w[j])))
                peak = float(np.max(np.abs(y)))
                if not (np.isfinite(peak) and peak > 0.0 and peak > MIN_SNR * noise):
                    raise InputError(
                        f"channel {spec.kind.value}@{spec.particle} has no usable pulse "
                        f"(peak {peak:.3g} V against noise {noise:.3g} V; needs > {MIN_SNR:g}x "
                        f"the noise of the shots' mean)")

    def add_model_uncertainty(self, records: np.ndarray, modes: tuple | None = None) -> None:
        """Add the model's own uncertainty to the likelihood.

        The model variance (:func:`msens.diagnose.likelihood.model_uncertainty` of each
        sensor) is computed once, from ``records`` (the baseline model's) aligned on the
        data, and held fixed for every candidate: the likelihood's variance is then the
        same for all of them, and chi^2 stays comparable between them. The field model's
        modes (:func:`msens.diagnose.field_modes.record_modes`), aligned and scaled as the
        baseline is, are fixed the same way; every later chi^2 profiles their amplitudes.

        Parameters
        ----------
        records : ndarray, shape (sensors, nt)
            The baseline model's records.
        modes : tuple of (RecordModes or None), optional
            Per sensor, the field model's modes of its record (None: none).
        """
        unc = [model_uncertainty(k, ph) for k, ph in zip(self.kinds, self.physics, strict=True)]
        #: Each sensor's model uncertainty.
        self.model_uncertainty = tuple(unc)
        self.field_modes = tuple(modes) if modes is not None else ()
        self._before = (self.shots, self._weights, np.array(records, copy=True))
        diagonal = not all(u.relative_amplitude == 0.0 and u.relative_timing == 0.0
                           for u in unc)
        if not diagonal and not any(m is not None for m in self.field_modes):
            return
        out = []
        for shot, (a, tm, m) in zip(self.shots, self.aligned(records), strict=True):
            noise_var = 1.0 / shot.w if shot.noise_var is None else shot.noise_var
            scaled = m - a.offsets[:, None]  # gain applied, offset removed
            model_var = np.array([u.variance(x, tm) for u, x in zip(unc, scaled, strict=True)])
            shot = dataclasses.replace(shot, w=1.0 / (noise_var + model_var),
                                       noise_var=noise_var, model_var=model_var)
            if any(md is not None for md in self.field_modes):
                shot = dataclasses.replace(shot, modes=tuple(
                    None if md is None or not len(md.names) else ModeBasis.of(
                        g * np.array([np.interp(tm, self.t, u, left=0.0, right=0.0)
                                      for u in md.records]), shot.w[j], shot.y[j])
                    for j, (md, g) in enumerate(zip(self.field_modes, a.gains,
                                                    strict=True))))
            out.append(shot)
        self.shots = out
        self._weights = self.shots[0].w.mean(axis=1)

    def without_modes(self, names) -> WaveformObjective:
        """A copy of this likelihood whose field-model modes leave out those named in
        ``names`` (e.g. quantities profiled exactly instead: :mod:`msens.diagnose.
        inductance`); the model variance and the other modes are the same."""
        internal(hasattr(self, "_before"), "internal: no model uncertainty to leave out of")
        new = copy.copy(self)
        new.shots, new._weights, records = self._before
        new.add_model_uncertainty(records, tuple(
            None if m is None else m.without(names) for m in self.field_modes))
        return new

    def variance_split(self) -> dict:
        """Per sensor and overall: the noise's and the model uncertainty's shares of the
        variance the residual is measured against (:func:`~msens.diagnose.likelihood.
        variance_split`)."""
        shot = self.shots[0]
        if shot.model_var is None:
            return {"noise_share": 1.0, "model_uncertainty_share": 0.0}
        return variance_split(shot.noise_var, shot.model_var)

    # ---------------------------------------------------------------- evaluation

    def signals(self, records: np.ndarray) -> np.ndarray:
        """Model signals (sensors, nt) of model records (sensors, nt)."""
        return np.array([signal(k, r, self.t, ph) for k, r, ph
                         in zip(self.kinds, records, self.physics, strict=True)])

    def _rss_at(self, shot: Shot, sig: np.ndarray, delay: float) -> Alignment:
        m = np.array([np.interp(shot.tau + delay, self.t, s, left=0.0, right=0.0)
                      for s in sig])
        # weighted least squares y ~ g m + b per channel (2x2 normal equations), g kept >= 0
        g, b, chi2, _ = _fit_many(shot.w, shot.y, m, None)
        if shot.modes is None:
            return Alignment(delay=delay, gains=g, offsets=b, rss=chi2)
        amps, shifts = [], []
        for j, u in enumerate(shot.modes):
            if u is None:
                amps.append(None)
                shifts.append(None)
                continue
            gj, bj, cj, a = _fit_many(shot.w[j], shot.y[j], m[j][None], u)
            g[j], b[j], chi2[j] = gj[0], bj[0], cj[0]
            amps.append(a[0])
            shifts.append(a[0] @ u.u)
        return Alignment(delay=delay, gains=g, offsets=b, rss=chi2,
                         amplitudes=tuple(amps), shifts=tuple(shifts))

    def _chi2_at(self, shot: Shot, sig: np.ndarray, delays: np.ndarray) -> np.ndarray:
        """The profiled chi^2 summed over the sensors at each of ``delays`` (L,), s: what
        :meth:`_rss_at` gives at each, in one batch of products and solves."""
        x = shot.tau[None, :] + np.asarray(delays, dtype=float)[:, None]
        total = np.zeros(x.shape[0])
        for j, s in enumerate(sig):
            m = np.interp(x, self.t, s, left=0.0, right=0.0)
            basis = None if shot.modes is None else shot.modes[j]
            total += _fit_many(shot.w[j], shot.y[j], m, basis)[2]
        return total

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
        if shot.modes is not None:
            # the profiled modes can move the chi^2 optimum a few samples off the
            # correlation's peak (the pull's modes shift the pulse's timing): the best
            # whole sample near it, or the chi^2 jumps when the peak's sample does
            near = d1 + np.arange(-LAG_WINDOW, LAG_WINDOW + 1) * self.dt
            d1 = float(near[np.argmin(self._chi2_at(shot, sig, near))])
        opt = minimize_scalar(lambda d: float(self._rss_at(shot, sig, d).rss.sum()),
                              bounds=(d1 - 1.5 * self.dt, d1 + 1.5 * self.dt),
                              method="bounded", options={"xatol": 1e-3 * self.dt})
        return self._rss_at(shot, sig, float(opt.x))

    def rss(self, records: np.ndarray) -> np.ndarray:
        """chi^2 per sensor: residual squares over each sample's variance, shape (sensors,).

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
            if a.shifts is not None:  # the profiled field-model modes
                m = m + np.array([np.zeros(m.shape[1]) if d is None else d
                                  for d in a.shifts])
            out.append((a, tm, m))
        return out


@dataclass(frozen=True)
class ModeBasis:
    """One channel's field-model modes on the data's samples, with the products the
    profiled chi^2 needs precomputed (the inverse variances, data and modes are fixed for a
    diagnosis; only the model's record changes between candidates).

    Attributes
    ----------
    u : ndarray, shape (k, n)
        The modes' principal directions, scaled so that each amplitude has a unit prior
        (their covariance ``u^T u`` is that of the field model's modes), V.
    uw : ndarray, shape (k, n)
        ``u * w``, 1/V.
    gram : ndarray, shape (k, k)
        ``u w u^T + I`` (the modes' unit Gaussian prior on the diagonal).
    u1, uy : ndarray, shape (k,)
        ``u w 1`` and ``u w y``.
    """

    u: np.ndarray
    uw: np.ndarray
    gram: np.ndarray
    u1: np.ndarray
    uy: np.ndarray

    @classmethod
    def of(cls, u: np.ndarray, w: np.ndarray, y: np.ndarray, tol: float = MODE_TOL
           ) -> ModeBasis:
        """The basis of modes ``u`` (k, n) for inverse variances ``w`` and data ``y`` (n,).

        The modes are first compressed to the principal directions of their covariance
        ``u^T u`` in the noise-whitened record: directions whose variance is below ``tol``
        times the noise's (per whole record) are dropped, since no amplitude along them can
        change chi^2 by more than ``tol``. The covariance is otherwise kept exactly, and
        the many collinear modes (e.g. the pulls of neighbouring beads, which mostly shift
        the pulse's timing) shrink to a few tens of directions.
        """
        root = np.sqrt(w)
        _, sv, vt = np.linalg.svd(u * root, full_matrices=False)
        keep = sv**2 > tol
        u = (sv[keep, None] * vt[keep]) / root
        uw = u * w
        return cls(u=u, uw=uw, gram=uw @ u.T + np.eye(u.shape[0]), u1=uw.sum(axis=1),
                   uy=uw @ y)


def _fit_many(w: np.ndarray, y: np.ndarray, m: np.ndarray, basis: ModeBasis | None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """Gain g >= 0, offset b and mode amplitudes a minimising, for each of L model signals
    at once, ``sum w (y - g m - b - a @ u)^2 + |a|^2`` (the modes' unit Gaussian prior), and
    that minimum: the chi^2 of the residual against the covariance ``diag(1/w) + u^T u``
    (Woodbury), with gain and offset profiled. Without ``basis``, the weighted least-squares
    fit ``y ~ g m + b`` alone (2x2 normal equations).

    Parameters
    ----------
    w, y : ndarray, shape (n,), or (L, n) without ``basis``
        Inverse variances (1/V^2) and data (V): one channel's, or one per signal.
    m : ndarray, shape (L, n)
        Model signals on the data's samples, V.
    basis : ModeBasis or None
        The channel's modes and their products with ``w`` and ``y``.

    Returns
    -------
    g, b, chi2 : ndarray, shape (L,)
    a : ndarray, shape (L, k), or None without ``basis``
    """
    wm = m * w
    mm = np.einsum("ln,ln->l", wm, m)
    s1, my = wm.sum(axis=-1), (wm * y).sum(axis=-1)
    s0, sy, yy = w.sum(axis=-1), (w * y).sum(axis=-1), (w * y * y).sum(axis=-1)
    if basis is None:
        det = s0 * mm - s1**2
        ok = det > 1e-12 * s0 * np.maximum(mm, 1e-300)
        g = np.maximum(np.where(ok, (s0 * my - s1 * sy) / np.where(ok, det, 1.0), 0.0), 0.0)
        b = (sy - g * s1) / s0
        chi2 = yy + g**2 * mm + s0 * b**2 - 2 * g * my - 2 * b * sy + 2 * g * b * s1
        return g, b, np.maximum(chi2, 0.0), None
    k = basis.u.shape[0]
    h = np.empty((m.shape[0], k + 2, k + 2))
    um = m @ basis.uw.T
    h[:, 0, 0], h[:, 0, 1], h[:, 1, 0], h[:, 1, 1] = mm, s1, s1, s0
    h[:, 0, 2:] = h[:, 2:, 0] = um
    h[:, 1, 2:] = h[:, 2:, 1] = basis.u1
    h[:, 2:, 2:] = basis.gram
    rhs = np.empty((m.shape[0], k + 2))
    rhs[:, 0], rhs[:, 1], rhs[:, 2:] = my, sy, basis.uy
    theta = np.linalg.solve(h, rhs[..., None])[..., 0]
    neg = theta[:, 0] < 0.0
    if neg.any():  # the gain kept >= 0: without the model column (the same for every row)
        theta[neg, 0] = 0.0
        theta[neg, 1:] = np.linalg.solve(h[0, 1:, 1:], rhs[0, 1:])
    chi2 = yy - np.einsum("lk,lk->l", theta, rhs)
    return theta[:, 0], theta[:, 1], np.maximum(chi2, 0.0), theta[:, 2:]


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

    def features(self, records: np.ndarray) -> np.ndarray:
        """The model's (TOF in µs, AR) of each sensor, shape (sensors, 2), read as the
        measured records are (NaN where a pulse is not found)."""
        f = model_features_of(feature_records(records, self.physics, self.t), self.t)
        return np.column_stack([np.asarray(f.tof, dtype=float) * 1e6,
                                np.asarray(f.ar, dtype=float)])[:len(self.rows)]

    def residuals(self, records: np.ndarray) -> np.ndarray:
        """Normalised residuals (sensors, 2): (TOF, AR) model minus measured over std."""
        f = self.features(records)
        out = np.empty((len(self.rows), 2))
        for j, r in enumerate(self.rows):
            out[j, 0] = (f[j, 0] - r.tof_us) / r.tof_std_us
            out[j, 1] = (f[j, 1] - r.ar) / r.ar_std
        return np.where(np.isfinite(out), out, 1e3)  # a missing reflection: a huge misfit

    def rss(self, records: np.ndarray) -> np.ndarray:
        """Sum of squared normalised residuals per sensor, shape (sensors,)."""
        return (self.residuals(records) ** 2).sum(axis=1)


def mss_kinds(kinds: tuple[SensorKind, ...]) -> bool:
    """Whether any sensor is an MsS (its signal is a rate)."""
    return any(k is SensorKind.MSS for k in kinds)

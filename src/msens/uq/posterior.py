"""The posterior of chosen uncertain inputs given a measurement: prior times likelihood.

- The **prior** of each calibrated input is its distribution in the uncertainty file
  (:mod:`msens.uq.inputs`), restricted to its support; every input not calibrated is held at
  its nominal value (the study's).
- The **likelihood** is the one ``msens diagnose`` judges a model by
  (:mod:`msens.diagnose.likelihood`), through its objectives:

  - a measured waveform file: :class:`~msens.diagnose.objective.WaveformObjective` built by
    :func:`msens.diagnose.workflow.waveform_baseline` — the shots' ensemble mean against the
    model's records, each sample weighted by the inverse of the noise variance (pre-trigger
    noise and shot scatter) plus the model's own uncertainty, with the record calibration
    (one impact-to-trigger offset, a gain and a DC offset per channel) profiled out;
  - published features (TOF and AR per sensor with their shot-to-shot std, e.g. the paper's
    Table 2): :class:`~msens.diagnose.objective.FeatureObjective`.

  Either gives ``chi^2(theta)``; with the variance fixed, ``ln L = -chi^2 / 2`` up to a
  constant. A profiled gain makes the likelihood blind to the record's absolute scale: a
  waveform constrains timing and shape, not volts.

The model of a row of input values is :func:`msens.uq.model.evaluate` (``msens run``'s own
chain and read-out), in batches: the sampler asks for many rows at once.

The sampler works in standardised coordinates ``z = (theta - nominal) / prior std`` so that
all inputs have a comparable scale (an affine map: the posterior density changes by a
constant factor only).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from msens.errors import InputError
from msens.uq.inputs import InputSet, UncertainInput
from msens.uq.model import Task, evaluate

#: Inputs calibrated when none are named, in this order, those the uncertainty file
#: propagates: the striker's speed (drop height), the contact dissipation (Eq. 10 has an
#: uncertainty of its own) and the bias magnet's strength (the undocumented part).
DEFAULT_CALIBRATED = ("striker.drop_height_m", "chain.gamma_contact_kg_per_s",
                      "sensor.magnet.remanence_factor")
#: Input kinds that take whole numbers: not calibrated by a continuous sampler.
INTEGER_KINDS = ("sensor[i].coil.turns",)


def select(inputs: InputSet, names: Sequence[str] | None) -> tuple[int, ...]:
    """Columns (in :attr:`InputSet.propagated` order) of the inputs to calibrate.

    Parameters
    ----------
    inputs : InputSet
    names : sequence of str or None
        Input names; None: those of :data:`DEFAULT_CALIBRATED` the file propagates.

    Returns
    -------
    tuple of int

    Raises
    ------
    InputError
        An unknown name, an input held at its nominal value, a whole-number input, a name
        given twice, or nothing to calibrate.
    """
    propagated = [p.name for p in inputs.propagated]
    held = {p.name: p for p in inputs.held}
    if names is None:
        names = [n for n in DEFAULT_CALIBRATED if n in propagated]
        if not names:
            raise InputError(f"{inputs.source}: none of the default inputs to calibrate "
                             f"({', '.join(DEFAULT_CALIBRATED)}) is sampled; name them with "
                             f"--param (allowed: {', '.join(propagated)})")
    names = list(names)
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f"--param names {', '.join(dup)} more than once")
    cols = []
    for n in names:
        if n in held:
            raise InputError(f"--param {n}: held at its nominal value in {inputs.source} "
                             f"({held[n].held_reason}); calibrate one of "
                             f"{', '.join(propagated)}")
        if n not in propagated:
            raise InputError(f"--param {n!r} is not an input of {inputs.source}; allowed: "
                             f"{', '.join(propagated)}")
        p = inputs.propagated[propagated.index(n)]
        if p.kind.pattern in INTEGER_KINDS:
            raise InputError(f"--param {n}: a whole number ({p.kind.description}) cannot be "
                             "calibrated by the continuous sampler; allowed: "
                             + ", ".join(q.name for q in inputs.propagated
                                         if q.kind.pattern not in INTEGER_KINDS))
        cols.append(propagated.index(n))
    if not cols:
        raise InputError("--param: nothing to calibrate")
    return tuple(cols)


@dataclass(frozen=True)
class Coordinates:
    """The map between the sampler's standardised coordinates and input values.

    Attributes
    ----------
    inputs : tuple of UncertainInput
        The calibrated inputs.
    nominal : ndarray, shape (p_all,)
        Every propagated input's nominal value, SI (the row of the held ones).
    columns : ndarray of int, shape (k,)
        The calibrated inputs' columns in that row.
    center, scale : ndarray, shape (k,)
        Nominal value and prior std of each calibrated input, SI.
    """

    inputs: tuple[UncertainInput, ...]
    nominal: np.ndarray
    columns: np.ndarray
    center: np.ndarray
    scale: np.ndarray

    @classmethod
    def of(cls, inputs: InputSet, columns: Sequence[int]) -> Coordinates:
        """The coordinates of the calibrated ``columns`` of ``inputs``."""
        chosen = tuple(inputs.propagated[c] for c in columns)
        return cls(inputs=chosen,
                   nominal=np.array([p.nominal for p in inputs.propagated], dtype=float),
                   columns=np.asarray(columns, dtype=int),
                   center=np.array([p.nominal for p in chosen], dtype=float),
                   scale=np.array([float(p.distribution.frozen().std()) for p in chosen]))

    @property
    def names(self) -> tuple[str, ...]:
        """The calibrated inputs' names."""
        return tuple(p.name for p in self.inputs)

    def values(self, z: np.ndarray) -> np.ndarray:
        """Calibrated input values, SI, shape (rows, k), of coordinates ``z`` (rows, k)."""
        return self.center + self.scale * np.atleast_2d(z)

    def coordinates(self, theta: np.ndarray) -> np.ndarray:
        """Coordinates of calibrated input values ``theta`` (rows, k)."""
        return (np.atleast_2d(theta) - self.center) / self.scale

    def rows(self, theta: np.ndarray) -> np.ndarray:
        """Full rows of propagated input values (rows, p_all): ``theta`` in the calibrated
        columns, the nominal values elsewhere."""
        theta = np.atleast_2d(theta)
        out = np.tile(self.nominal, (theta.shape[0], 1))
        out[:, self.columns] = theta
        return out

    def log_prior(self, theta: np.ndarray) -> np.ndarray:
        """Sum of the calibrated inputs' prior log densities, shape (rows,); -inf outside a
        support."""
        theta = np.atleast_2d(theta)
        out = np.zeros(theta.shape[0])
        for j, p in enumerate(self.inputs):
            lo, hi = p.distribution.support
            x = theta[:, j]
            with np.errstate(divide="ignore"):
                lp = p.distribution.frozen().logpdf(x)
            out += np.where((x >= lo) & (x <= hi), lp, -np.inf)
        return out


class Likelihood:
    """chi^2 of rows of input values against one measurement (see the module docstring).

    Parameters
    ----------
    study : Study
        The study whose model is evaluated (with its fitted dissipation, if any).
    inputs : InputSet
    setup : SetupSpec
        The setup the measurement belongs to (its sensors in order).
    objective : WaveformObjective or FeatureObjective
        ``objective.rss(records)`` gives chi^2 per sensor for records (sensors, nt).
    """

    def __init__(self, study, inputs: InputSet, setup, objective) -> None:
        self.study = study
        self.inputs = inputs
        self.setup = setup
        self.objective = objective
        self.keys = [f"{setup.name}/{s.kind.value}@{s.particle}" for s in setup.sensors]
        #: Model runs made.
        self.runs = 0

    def records(self, rows: np.ndarray) -> np.ndarray:
        """Model records of rows of propagated input values, shape (rows, sensors, nt).

        Raises
        ------
        InputError
            A row the model refuses (e.g. magnets that pull the beads apart).
        """
        rows = np.atleast_2d(rows)
        ev = evaluate(Task(self.study, self.inputs, rows, np.ones(rows.shape[0], bool),
                           setups=(self.setup.name,), precise=True))
        self.runs += ev.runs
        return np.stack([ev.waveforms[k] for k in self.keys], axis=1)

    def chi2(self, rows: np.ndarray) -> np.ndarray:
        """chi^2 of each row (rows,); +inf for a row the model refuses."""
        rows = np.atleast_2d(rows)
        try:
            recs = self.records(rows)
        except InputError:
            if rows.shape[0] == 1:
                return np.array([np.inf])
            return np.concatenate([self.chi2(r[None]) for r in rows])
        out = np.array([float(np.sum(self.objective.rss(r))) for r in recs])
        return np.where(np.isfinite(out), out, np.inf)


class Posterior:
    """Log posterior density in the sampler's coordinates (vectorised over walkers).

    Parameters
    ----------
    coords : Coordinates
    likelihood : Likelihood
    """

    def __init__(self, coords: Coordinates, likelihood: Likelihood) -> None:
        self.coords = coords
        self.likelihood = likelihood

    def __call__(self, z: np.ndarray) -> np.ndarray:
        """``ln prior + ln L`` of coordinates ``z`` (walkers, k), shape (walkers,).

        The likelihood is evaluated only where the prior is positive.
        """
        z = np.atleast_2d(np.asarray(z, dtype=float))
        theta = self.coords.values(z)
        lp = self.coords.log_prior(theta)
        ok = np.isfinite(lp)
        if ok.any():
            chi2 = self.likelihood.chi2(self.coords.rows(theta[ok]))
            lp[ok] = lp[ok] - 0.5 * chi2
        return np.where(np.isfinite(lp), lp, -np.inf)


__all__ = ["DEFAULT_CALIBRATED", "INTEGER_KINDS", "Coordinates", "Likelihood", "Posterior",
           "select"]

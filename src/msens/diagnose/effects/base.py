"""What a candidate effect is: a named, bounded change of the baseline model.

The model a diagnosis varies is a :class:`ModelState`: the chain, the striker speed, the
particle each sensor reads, and operations applied to the sensor records afterwards (the
acquisition). An effect is a pure function ``apply(context, state, params) -> state`` with
named SI parameters and bounds; it never simulates. Prediction (simulation + observation)
lives in :mod:`msens.diagnose.predict`, so that many states are run in one batch.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import lfilter

from msens.chain.model import Chain
from msens.config.schema import SetupSpec
from msens.config.study import Study
from msens.diagnose.models import ModelBank, PhysicsMss
from msens.readout.sensors import SensorKind

#: A record operation: (records (..., nt), sample interval s) -> records (..., nt).
RecordOp = Callable[[np.ndarray, float], np.ndarray]


@dataclass(frozen=True)
class Context:
    """The study and setup a diagnosis works on (read-only inputs of every effect), and the
    run's field models (:class:`~msens.diagnose.models.ModelBank`: each Context, i.e. each
    diagnosis run, has its own)."""

    study: Study
    setup: SetupSpec
    models: ModelBank = field(default_factory=ModelBank, compare=False, repr=False)


@dataclass(frozen=True)
class ModelState:
    """Everything that defines one prediction of a setup's sensor records.

    Attributes
    ----------
    chain : Chain
    velocity : float
        Striker speed at impact, m/s.
    particles : tuple of int
        1-based particle each sensor reads, in the order of ``setup.sensors``.
    kinds : tuple of SensorKind
        Observation operator of each sensor.
    post : tuple of RecordOp
        Operations applied, in order, to the sensor records after observation.
    physics : tuple of (PhysicsMss or None)
        Per sensor, the physics MsS it is (its record is then its DAQ voltage, V); empty
        when the setup has none.
    velocity_spread : float
        Relative std of the striker speed over the shots of a file (the rig's shot-to-shot
        jitter, measured per shot): the prediction is then the mean record over that spread
        of speeds around ``velocity``, as the shots' ensemble mean is. 0: one speed.
    """

    chain: Chain
    velocity: float
    particles: tuple[int, ...]
    kinds: tuple[SensorKind, ...]
    post: tuple[RecordOp, ...] = ()
    physics: tuple[PhysicsMss | None, ...] = ()
    velocity_spread: float = 0.0


@dataclass(frozen=True)
class Parameter:
    """One fitted parameter of an effect.

    Attributes
    ----------
    name : str
        Parameter name with its SI unit in it (e.g. ``gamma_wall_kg_per_s``).
    lower, upper : float
        Bounds of the search.
    log : bool
        Search (grid and refinement) in log space: for scale parameters.
    integer : bool
        Integer parameter: searched exhaustively on lower..upper, no refinement.
    plausible : tuple of float, optional
        Physical range (lower, upper), SI: a fit outside it is reported as implausible and
        not named. Default: the search bounds. The search may reach beyond it on purpose, so
        that an impossible optimum is seen as such instead of being clipped to the bound.
    reason : str
        Why the physical range is what it is (source or argument), for reports.
    floor : float
        Practical-significance floor: the smallest change from the baseline value, SI,
        that a rig can set or hold (below it the effect is not named). 0: any change.
    floor_reason : str
        Where the floor comes from.
    """

    name: str
    lower: float
    upper: float
    log: bool = False
    integer: bool = False
    plausible: tuple[float, float] | None = None
    reason: str = ""
    floor: float = 0.0
    floor_reason: str = ""

    def __post_init__(self) -> None:
        if not self.lower < self.upper or (self.log and self.lower <= 0):
            raise ValueError(f"bad bounds for {self.name}: [{self.lower}, {self.upper}]")
        if self.plausible is not None and not self.plausible[0] <= self.plausible[1]:
            raise ValueError(f"bad physical range for {self.name}: {self.plausible}")
        if not self.floor >= 0.0:
            raise ValueError(f"bad significance floor for {self.name}: {self.floor}")

    @property
    def physical(self) -> tuple[float, float]:
        """The physical range (lower, upper), SI."""
        return self.plausible if self.plausible is not None else (self.lower, self.upper)

    def is_plausible(self, value: float) -> bool:
        """Whether ``value`` lies in the physical range (1e-9 relative slack for rounding)."""
        lo, hi = self.physical
        slack = 1e-9 * max(abs(lo), abs(hi), 1e-300)
        return lo - slack <= value <= hi + slack


@dataclass(frozen=True)
class Effect:
    """A candidate missing effect.

    Attributes
    ----------
    name : str
        Fixed public name (``wall_dissipation``, ...).
    description : str
        One line, for reports.
    space : callable (Context, ModelState) -> tuple of Parameter
        Parameters and their bounds for this setup and baseline.
    baseline : callable (Context, ModelState) -> dict
        Value of each parameter in the baseline model (None when the baseline is not a
        value of the parameter, e.g. a different law).
    apply : callable (Context, ModelState, Mapping[str, float]) -> ModelState
        Pure: the state with the effect at the given parameter values.
    applies : callable (Context) -> bool
        Whether the effect makes sense for the setup (e.g. magnets only on MsS setups).
    grid_points : int
        Points per continuous parameter of the batched start grid.
    strides : callable (Context) -> dict of str -> int
        Per integer parameter, a stride for a coarse first search (coarse to fine, for
        effects whose states are costly on some setups); empty: every combination.
    """

    name: str
    description: str
    space: Callable[[Context, ModelState], tuple[Parameter, ...]]
    baseline: Callable[[Context, ModelState], dict[str, float | None]]
    apply: Callable[[Context, ModelState, Mapping[str, float]], ModelState]
    applies: Callable[[Context], bool] = lambda ctx: True
    grid_points: int = 12
    strides: Callable[[Context], Mapping[str, int]] = lambda ctx: {}


@dataclass(frozen=True)
class FirstOrderLowpass:
    """Causal first-order low-pass y' = (x - y) / tau applied along the last axis.

    Discretised exactly for an input held constant over each sample (zero-order hold):
    y[k] = a y[k-1] + (1 - a) x[k], a = exp(-dt / tau). Its group delay at low frequency
    is tau (not removed: a real DAQ filter delays the record).

    Attributes
    ----------
    tau_s : float
        Time constant, s (> 0).
    """

    tau_s: float

    def __call__(self, records: np.ndarray, dt: float) -> np.ndarray:
        a = float(np.exp(-dt / self.tau_s))
        return lfilter([1.0 - a], [1.0, -a], records, axis=-1)

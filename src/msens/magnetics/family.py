"""Transducers as a smooth function of one parameter of the field model.

A parameter that changes the field model (the magnets' remanence, the steel's small-signal
permeability) needs a nonlinear field solve per value. A family solves the geometry at a few
values of the parameter (its *nodes*, through the cached transducer core) and interpolates
every transducer quantity with a cubic spline through them, in the parameter itself or in
its logarithm; a diagnosis or a propagation then evaluates any value inside the nodes in
microseconds. :class:`~msens.magnetics.variants.RemanenceFamily` and
:class:`~msens.magnetics.reversibility.ReversibilityFamily` are the two families; each says
which parameter it varies and on which axis it interpolates. With eddy currents the coils'
frequency responses change with the same parameters: a :class:`ResponseFamily` interpolates
them the same way (:class:`~msens.magnetics.variants.RemanenceResponses`,
:class:`~msens.magnetics.reversibility.ReversibilityResponses`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from scipy.interpolate import CubicSpline

from msens.errors import internal, require
from msens.field.geometry import SensorGeometry
from msens.magnetics.transducer import Transducer, magnetic_precompression

if TYPE_CHECKING:
    from msens.magnetics.frequency_response import FrequencyResponse

#: Transducer quantities that depend on the field model, interpolated element by element
#: (Wb/N, Wb/m, N; the offset profiles with their offsets axis). The inductance (H) is
#: interpolated too; contacts, stiffness, resistance, turns and the offsets grid are the same
#: for every member.
QUANTITIES = ("sensitivity_villari", "dlambda_dapproach", "magnetic_particle_force",
              "villari_by_offset", "approach_by_offset")


@dataclass(frozen=True)
class TransducerFamily:
    """Transducers of one geometry at the parameter values :attr:`nodes`.

    Attributes
    ----------
    geometry : SensorGeometry
        Nominal geometry (parameter value 1).
    nodes : tuple of float
        Parameter values solved, increasing.
    members : tuple of dict
        ``{particle: Transducer}`` at each node.
    """

    geometry: SensorGeometry
    nodes: tuple[float, ...]
    members: tuple[dict[int, Transducer], ...]

    #: What the parameter is, for messages ("remanence factor").
    parameter: ClassVar[str] = "parameter"
    #: Whether the splines run in the logarithm of the parameter.
    log_axis: ClassVar[bool] = False
    #: What an interpolated coil adds to its ``source`` ({x}: the value, {n}: the nodes).
    source_format: ClassVar[str] = "{parameter} {x:.6g} (spline over {n} field models)"

    @property
    def bounds(self) -> tuple[float, float]:
        """Smallest and largest parameter value covered."""
        return self.nodes[0], self.nodes[-1]

    def _at(self, values: list, x: float) -> np.ndarray:
        # cubic spline through the nodes' values (stacked along axis 0), evaluated at x
        axis = np.log if self.log_axis else np.asarray
        return CubicSpline(axis(np.array(self.nodes)), np.stack(values), axis=0)(axis(x))

    def _base(self, trs: list[Transducer]) -> Transducer:
        # the member whose fixed data (contacts, resistance, turns, source) the result keeps:
        # the nominal one (value 1) when solved
        return trs[self.nodes.index(1.0)] if 1.0 in self.nodes else trs[0]

    def _source(self, base: Transducer, x: float) -> str:
        return f"{base.source}; " + self.source_format.format(
            parameter=self.parameter, x=x, n=len(self.nodes))

    def particle_force(self, x: float) -> np.ndarray:
        """Static magnetic force on each particle at parameter value ``x``, N, shape (n,)
        (+ toward the wall, as :func:`msens.magnetics.transducer.magnetic_precompression`)."""
        self._check(x)
        return self._at([magnetic_precompression(m) for m in self.members], x)

    def transducer(self, particle: int, x: float) -> Transducer:
        """The coil at ``particle`` at parameter value ``x`` (interpolated).

        Every quantity of :data:`QUANTITIES` and the inductance come from the splines; all
        coils of one value carry the same ``source``, so
        :func:`~msens.magnetics.transducer.magnetic_precompression` counts their magnets once.
        """
        self._check(x)
        trs = [m[particle] for m in self.members]
        base = self._base(trs)
        out = {name: None if getattr(base, name) is None else self._at(
            [np.asarray(getattr(t, name), dtype=float) for t in trs], x)
            for name in QUANTITIES}
        return replace(base, inductance_H=float(self._at([t.inductance_H for t in trs], x)),
                       **out, source=self._source(base, x))

    def _check(self, x: float) -> None:
        lo, hi = self.bounds
        require(lo <= x <= hi, f"{self.parameter} {x} outside the solved range {lo:g}..{hi:g}")


#: Frequency-response quantities interpolated over a family's parameter (complex, element
#: by element; real and imaginary parts apart); frequencies, contacts and R are the same for
#: every member.
RESPONSE_QUANTITIES = ("villari", "approach", "impedance")


@dataclass(frozen=True)
class ResponseFamily:
    """Eddy-current frequency responses of one geometry at the parameter values
    :attr:`nodes`, splines in the parameter (or its logarithm) as :class:`TransducerFamily`.

    Attributes
    ----------
    geometry : SensorGeometry
        Nominal geometry.
    nodes : tuple of float
        Parameter values solved, increasing.
    members : tuple of dict
        ``{particle: FrequencyResponse}`` at each node (same frequencies and contacts;
        solved without offset profiles).
    """

    geometry: SensorGeometry
    nodes: tuple[float, ...]
    members: tuple[dict, ...]

    parameter: ClassVar[str] = "parameter"
    log_axis: ClassVar[bool] = False
    source_format: ClassVar[str] = ("{parameter} {x:.6g} (spline over {n} eddy-current "
                                    "models)")

    def __post_init__(self) -> None:
        freqs = [np.asarray(r.frequencies) for m in self.members for r in m.values()]
        internal(all(f.shape == freqs[0].shape and np.array_equal(f, freqs[0])
                     for f in freqs), "internal: family responses at other frequencies")

    bounds = TransducerFamily.bounds
    _at = TransducerFamily._at
    _check = TransducerFamily._check

    def response(self, particle: int, x: float) -> FrequencyResponse:
        """The coil at ``particle`` at parameter value ``x``
        (:class:`~msens.magnetics.frequency_response.FrequencyResponse`; S_c(ω), D_c(ω),
        Z(ω) and the static inductance from the splines; no offset profiles or screening
        split)."""
        self._check(x)
        rs = [m[particle] for m in self.members]
        base = rs[self.nodes.index(1.0)] if 1.0 in self.nodes else rs[0]

        def at(values):
            v = np.stack([np.asarray(a) for a in values])
            return self._at(list(v.real), x) + 1j * self._at(list(v.imag), x)

        out = {name: at([getattr(r, name) for r in rs]) for name in RESPONSE_QUANTITIES}
        static = float(self._at([r.static_inductance_H for r in rs], x))
        return replace(base, **out, static_inductance_H=static, offsets=None,
                       villari_by_offset=None, approach_by_offset=None, screening=None,
                       source=f"{base.source}; " + self.source_format.format(
                           parameter=self.parameter, x=x, n=len(self.nodes)))


__all__ = ["QUANTITIES", "RESPONSE_QUANTITIES", "ResponseFamily", "TransducerFamily"]

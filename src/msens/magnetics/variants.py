"""Transducers as a smooth function of the bias magnets' remanence.

A magnet of another strength (another batch or grade, ageing, temperature) changes the bias
state: the magnets' pull on the beads and every contact's sensitivity. Each field model is a
nonlinear solve (~20 s), so :class:`RemanenceFamily` solves the geometry at a few remanence
factors (:data:`NODES`, all magnets scaled together) through the cached transducer core and
interpolates every quantity with a cubic spline in the factor
(:class:`~msens.magnetics.family.TransducerFamily`); a diagnosis or a sweep then
evaluates any factor in microseconds. The interpolation error against a direct solve is
checked in ``tests/magnetics/test_variants.py``.

With eddy currents the coils' frequency responses change with the bias state too:
:class:`RemanenceResponses` solves the eddy-current model (:func:`msens.magnetics.
dynamic_cache.dynamic_report`) at the same factors and interpolates S_c(ω), D_c(ω), Z(ω)
and the static inductance the same way (real and imaginary parts, frequency by frequency).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import pairwise
from typing import ClassVar

from msens.errors import internal
from msens.field.geometry import SensorGeometry
from msens.magnetics.family import ResponseFamily, TransducerFamily
from msens.magnetics.transducer_cache import transducers_for

#: Remanence factors (B_r / nominal) at which the field model is solved.
NODES = (0.5, 0.75, 1.0, 1.25, 1.5)


def scaled_geometry(geometry: SensorGeometry, factor: float) -> SensorGeometry:
    """The geometry with every magnet's remanence multiplied by ``factor``."""
    units = tuple(u if u.magnet is None else
                  replace(u, magnet=replace(u.magnet, remanence=u.magnet.remanence * factor))
                  for u in geometry.sensors)
    return replace(geometry, sensors=units)


@dataclass(frozen=True)
class RemanenceFamily(TransducerFamily):
    """Transducers of one geometry at the remanence factors :attr:`nodes` (all magnets
    scaled together; factor 1 is the nominal geometry), splines in the factor."""

    parameter: ClassVar[str] = "remanence factor"
    source_format: ClassVar[str] = "remanence x {x:.6g} (spline over {n} field models)"


def remanence_family(geometry: SensorGeometry, nodes: tuple[float, ...] = NODES,
                     **kwargs) -> RemanenceFamily:
    """Solve (or read from the transducer cache) the geometry at each remanence factor.

    Keyword arguments go to :func:`msens.magnetics.transducer_cache.transducers_for`.
    """
    internal(all(a < b for a, b in pairwise(nodes)) and len(nodes) >= 2,
             "internal: remanence nodes must increase")
    members = tuple(transducers_for(scaled_geometry(geometry, f), **kwargs) for f in nodes)
    return RemanenceFamily(geometry=geometry, nodes=tuple(nodes), members=members)


@dataclass(frozen=True)
class RemanenceResponses(ResponseFamily):
    """Eddy-current frequency responses of one geometry at the remanence factors
    :attr:`nodes` (all magnets scaled together; factor 1 is the nominal geometry), splines
    in the factor."""

    parameter: ClassVar[str] = "remanence factor"
    source_format: ClassVar[str] = "remanence x {x:.6g} (spline over {n} eddy-current models)"


def remanence_responses(geometry: SensorGeometry, nodes: tuple[float, ...] = NODES,
                        **kwargs) -> RemanenceResponses:
    """Solve (or read from the store) the eddy-current model at each remanence factor.

    Keyword arguments go to :func:`msens.magnetics.dynamic_cache.dynamic_report` (``options``,
    ``steel``, ``store``...; no offsets).
    """
    from msens.magnetics.dynamic_cache import dynamic_report

    internal(all(a < b for a, b in pairwise(nodes)) and len(nodes) >= 2,
             "internal: remanence nodes must increase")
    internal("offsets" not in kwargs, "internal: remanence responses have no offset profiles")
    members = tuple(dynamic_report(scaled_geometry(geometry, f), **kwargs).responses
                    for f in nodes)
    return RemanenceResponses(geometry=geometry, nodes=tuple(nodes), members=members)


__all__ = ["NODES", "RemanenceFamily", "RemanenceResponses",
           "remanence_family", "remanence_responses", "scaled_geometry"]

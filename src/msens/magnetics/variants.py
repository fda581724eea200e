"""Transducers as a smooth function of the bias magnets' remanence.

A magnet of another strength (another batch or grade, ageing, temperature) changes the bias
state: the magnets' pull on the beads and every contact's sensitivity. Each field model is a
nonlinear solve (~20 s), so :class:`RemanenceFamily` solves the geometry at a few remanence
factors (:data:`NODES`, all magnets scaled together) through the cached transducer core and
interpolates every quantity with a cubic spline in the factor; a diagnosis or a sweep then
evaluates any factor in microseconds. The interpolation error against a direct solve is
checked in ``tests/magnetics/test_variants.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import pairwise

import numpy as np
from scipy.interpolate import CubicSpline

from msens.errors import internal, require
from msens.field.geometry import SensorGeometry
from msens.magnetics.transducer import Transducer, magnetic_precompression
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
class RemanenceFamily:
    """Transducers of one geometry at the remanence factors :data:`NODES`.

    Attributes
    ----------
    geometry : SensorGeometry
        Nominal geometry (factor 1).
    nodes : tuple of float
    members : tuple of dict
        ``{particle: Transducer}`` at each node.
    """

    geometry: SensorGeometry
    nodes: tuple[float, ...]
    members: tuple[dict[int, Transducer], ...]

    @property
    def bounds(self) -> tuple[float, float]:
        """Smallest and largest factor covered."""
        return self.nodes[0], self.nodes[-1]

    def _spline(self, values: list[np.ndarray]) -> CubicSpline:
        return CubicSpline(np.array(self.nodes), np.stack(values), axis=0)

    def particle_force(self, factor: float) -> np.ndarray:
        """Static magnetic force on each particle at ``factor``, N, shape (n,)."""
        self._check(factor)
        return self._spline([magnetic_precompression(m) for m in self.members])(factor)

    def transducer(self, particle: int, factor: float) -> Transducer:
        """The coil at ``particle`` with the magnets at ``factor`` (interpolated)."""
        self._check(factor)
        trs = [m[particle] for m in self.members]
        nominal = trs[self.nodes.index(1.0)] if 1.0 in self.nodes else trs[0]

        def at(name: str) -> np.ndarray | float:
            return self._spline([np.asarray(getattr(t, name), dtype=float) for t in trs])(
                factor)

        return replace(nominal, sensitivity_villari=at("sensitivity_villari"),
                       dlambda_dapproach=at("dlambda_dapproach"),
                       inductance_H=float(at("inductance_H")),
                       magnetic_particle_force=at("magnetic_particle_force"),
                       villari_by_offset=at("villari_by_offset"),
                       approach_by_offset=at("approach_by_offset"),
                       source=f"{nominal.source}; remanence x {factor:.6g} (spline over "
                              f"{len(self.nodes)} field models)")

    def _check(self, factor: float) -> None:
        lo, hi = self.bounds
        require(lo <= factor <= hi,
                f"remanence factor {factor} outside the solved range {lo:g}..{hi:g}")


def remanence_family(geometry: SensorGeometry, nodes: tuple[float, ...] = NODES,
                     **kwargs) -> RemanenceFamily:
    """Solve (or read from the transducer cache) the geometry at each remanence factor.

    Keyword arguments go to :func:`msens.magnetics.transducer_cache.transducers_for`.
    """
    internal(all(a < b for a, b in pairwise(nodes)) and len(nodes) >= 2,
             "internal: remanence nodes must increase")
    members = tuple(transducers_for(scaled_geometry(geometry, f), **kwargs) for f in nodes)
    return RemanenceFamily(geometry=geometry, nodes=tuple(nodes), members=members)


__all__ = ["NODES", "RemanenceFamily", "remanence_family", "scaled_geometry"]

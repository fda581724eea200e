"""Transducers as a smooth function of the steel's small-signal reversibility c.

The small-signal permeability the coil sees about the bias point is c times the differential
susceptibility of the steel's B–H curve (:class:`msens.field.regions.NonlinearSoft`; 1 =
differential, ~0.1 = the reversible part quoted for steels). It is not measured for the
paper's beads and it sets every contact's sensitivity and the coil's inductance, so
``msens uq`` propagates it. Each value is a new bias and coil solve on the study's mesh
(about 10 s with the mesh cached), so :class:`ReversibilityFamily` solves the geometry at a
few reversibilities (:data:`NODES`, log-spaced over [0.1, 1]) through the cached transducer
core, and interpolates every transducer quantity with a cubic spline in log c, as
:class:`msens.magnetics.variants.RemanenceFamily` does in the remanence factor. The nonlinear
contact maps are full solves that do not depend on c (they are shared by every c in the
store): the interpolated coils read the study's maps (:meth:`Transducer.reading_maps_of`).

The surrogate's error against direct solves at held-out reversibilities is measured by
``python benchmarks/uq_reversibility.py`` (main study, 24 seeded log-uniform values: the
coils' peak DAQ voltage and EMF within 0.01 %; the magnets' pull does not depend on c) and
checked on five of them to 1 % in ``tests/uq/test_reversibility_slow.py``.
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

#: Reversibilities at which the field model is solved: five log-spaced values over [0.1, 1]
#: (rounded to three digits: they are the keys of the stored solves).
NODES = (0.1, 0.178, 0.316, 0.562, 1.0)
#: Transducer quantities that depend on c, interpolated per element.
QUANTITIES = ("sensitivity_villari", "dlambda_dapproach", "magnetic_particle_force",
              "villari_by_offset", "approach_by_offset")


@dataclass(frozen=True)
class ReversibilityFamily:
    """Transducers of one geometry at the reversibilities :attr:`nodes`.

    Attributes
    ----------
    geometry : SensorGeometry
        Nominal geometry (its ``reversibility`` is the study's c).
    nodes : tuple of float
        Reversibilities solved, increasing, unit 1.
    members : tuple of dict
        ``{particle: Transducer}`` at each node (without contact maps).
    """

    geometry: SensorGeometry
    nodes: tuple[float, ...]
    members: tuple[dict[int, Transducer], ...]

    @property
    def bounds(self) -> tuple[float, float]:
        """Smallest and largest reversibility covered."""
        return self.nodes[0], self.nodes[-1]

    def _at(self, values: list, c: float) -> np.ndarray:
        # cubic spline in log c through the nodes' values (stacked along axis 0)
        return CubicSpline(np.log(self.nodes), np.stack(values), axis=0)(np.log(c))

    def particle_force(self, c: float) -> np.ndarray:
        """Static magnetic force on each particle at reversibility ``c``, N, shape (n,)
        (+ toward the wall, as :func:`msens.magnetics.transducer.magnetic_precompression`)."""
        self._check(c)
        return self._at([magnetic_precompression(m) for m in self.members], c)

    def transducer(self, particle: int, c: float) -> Transducer:
        """The coil at ``particle`` with the steel's reversibility ``c`` (interpolated).

        Every quantity of :data:`QUANTITIES` (Wb/N, Wb/m, N; the offset profiles with their
        offsets axis) and the inductance (H) come from the spline in log c; the particle's
        contacts, stiffness, resistance, turns and offsets grid are the same at every c.
        All coils of one c carry the same ``source``, so
        :func:`~msens.magnetics.transducer.magnetic_precompression` counts their magnets
        once.
        """
        self._check(c)
        trs = [m[particle] for m in self.members]
        base = trs[-1]
        out = {name: None if getattr(base, name) is None else self._at(
            [np.asarray(getattr(t, name), dtype=float) for t in trs], c)
            for name in QUANTITIES}
        inductance = float(self._at([t.inductance_H for t in trs], c))
        return replace(base, inductance_H=inductance, **out,
                       source=f"{base.source}; reversibility {c:.6g} (spline in log c over "
                              f"{len(self.nodes)} field models)")

    def _check(self, c: float) -> None:
        lo, hi = self.bounds
        require(lo <= c <= hi,
                f"reversibility {c} outside the solved range {lo:g}..{hi:g}")


def reversibility_family(geometry: SensorGeometry, nodes: tuple[float, ...] = NODES,
                         **kwargs) -> ReversibilityFamily:
    """Solve (or read from the artifact store) the geometry at each reversibility of
    ``nodes`` (increasing, in (0, 1]).

    Keyword arguments go to :func:`msens.magnetics.transducer_cache.transducers_for`
    (e.g. ``store``).
    """
    internal(all(a < b for a, b in pairwise(nodes)) and len(nodes) >= 4,
             "internal: reversibility nodes must increase (at least four)")
    members = tuple(transducers_for(replace(geometry, reversibility=float(c)), **kwargs)
                    for c in nodes)
    return ReversibilityFamily(geometry=geometry, nodes=tuple(float(c) for c in nodes),
                               members=members)


__all__ = ["NODES", "QUANTITIES", "ReversibilityFamily", "reversibility_family"]

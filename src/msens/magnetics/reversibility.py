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

With eddy currents the coils' frequency responses depend on c as well (the skin depth goes as
1/√μ): :class:`ReversibilityResponses` solves the eddy-current model at the same nodes and
interpolates S_c(ω), D_c(ω), Z(ω) in log c (``benchmarks/uq_reversibility.py --eddy``
measures it against direct solves).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import pairwise
from typing import ClassVar

from msens.errors import internal
from msens.field.geometry import SensorGeometry
from msens.magnetics.family import QUANTITIES, ResponseFamily, TransducerFamily
from msens.magnetics.transducer_cache import transducers_for

#: Reversibilities at which the field model is solved: five log-spaced values over [0.1, 1]
#: (rounded to three digits: they are the keys of the stored solves).
NODES = (0.1, 0.178, 0.316, 0.562, 1.0)


@dataclass(frozen=True)
class ReversibilityFamily(TransducerFamily):
    """Transducers of one geometry at the reversibilities :attr:`nodes` (unit 1; the
    nominal geometry carries the study's c), splines in log c."""

    parameter: ClassVar[str] = "reversibility"
    log_axis: ClassVar[bool] = True
    source_format: ClassVar[str] = "reversibility {x:.6g} (spline in log c over {n} field models)"


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


@dataclass(frozen=True)
class ReversibilityResponses(ResponseFamily):
    """Eddy-current frequency responses of one geometry at the reversibilities
    :attr:`nodes`, splines in log c: c sets the steel's small-signal permeability, so both
    the static sensitivities and the skin depth (∝ 1/√μ) change with it."""

    parameter: ClassVar[str] = "reversibility"
    log_axis: ClassVar[bool] = True
    source_format: ClassVar[str] = ("reversibility {x:.6g} (spline in log c over {n} "
                                    "eddy-current models)")


def reversibility_responses(geometry: SensorGeometry, nodes: tuple[float, ...] = NODES,
                            **kwargs) -> ReversibilityResponses:
    """Solve (or read from the store) the eddy-current model at each reversibility of
    ``nodes``.

    Keyword arguments go to :func:`msens.magnetics.dynamic_cache.dynamic_report`
    (``options``, ``steel``, ``store``...; no offsets).
    """
    from msens.magnetics.dynamic_cache import dynamic_report

    internal(all(a < b for a, b in pairwise(nodes)) and len(nodes) >= 4,
             "internal: reversibility nodes must increase (at least four)")
    internal("offsets" not in kwargs, "internal: family responses have no offset profiles")
    members = tuple(dynamic_report(replace(geometry, reversibility=float(c)),
                                   **kwargs).responses for c in nodes)
    return ReversibilityResponses(geometry=geometry, nodes=tuple(float(c) for c in nodes),
                                  members=members)


__all__ = ["NODES", "QUANTITIES", "ReversibilityFamily", "ReversibilityResponses",
           "reversibility_family", "reversibility_responses"]

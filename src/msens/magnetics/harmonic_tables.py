"""Eddy-current source potentials tabulated for coil design: one complex table per frequency.

A coil is air and carries no current while it reads, so the harmonic potential of every
mechanism source, (K_t + jωM_σ) a_s(ω) = f_s (:mod:`msens.magnetics.dynamic`), does not
depend on it. Solving each source once per frequency (one factorisation per frequency, one
back-substitution per source) and tabulating 2π r a_s(ω) as a summed-area table
(:func:`msens.magnetics.potentials.linkage_table`, complex values) gives every coil design's
complex sensitivities S_c(ω), D_c(ω) by four table look-ups — the frequency-dependent
counterpart of the static coil-sweep table. :func:`msens.magnetics.dynamic.frequency_responses`
reads the same sources by reciprocity with the run's coil instead; both agree to the table's
quadrature error (tests).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from msens.errors import require
from msens.field.eddy import HarmonicOperator
from msens.field.geometry import SensorGeometry
from msens.magnetics.dynamic import sensor_conductivity
from msens.magnetics.mechanisms import MechanismPotentials
from msens.magnetics.potentials import _interp_weights, table_grid, tabulate
from msens.params.materials import SIGMA_1018

#: Coils whose linkages are formed at once (the temporaries, 1 MB on the main study, stay in
#: the processor's cache).
_BLOCK = 64


@dataclass(frozen=True)
class HarmonicTables:
    """Summed-area tables of the sources' harmonic potentials at each solved frequency.

    Attributes
    ----------
    frequencies : ndarray, shape (n_f,)
        Hz, increasing from 0.
    r, z : ndarray, shapes (nr,), (nz,)
        Grid lines, m.
    cumulative : ndarray of complex, shape (n_f, n_sources, nr, nz)
        As :attr:`msens.magnetics.potentials.LinkageTable.cumulative`, per frequency
        (Villari sources first, then approach sources, the order of
        :class:`MechanismPotentials`).
    """

    frequencies: np.ndarray
    r: np.ndarray
    z: np.ndarray
    cumulative: np.ndarray

    def linkage(self, turns: np.ndarray, r0: np.ndarray, r1: np.ndarray, z0: np.ndarray,
                z1: np.ndarray) -> np.ndarray:
        """Each coil's complex flux linkage of every source at every frequency.

        :func:`msens.magnetics.potentials.rect_integral` of each frequency's table (the same
        bilinear corners, the same arithmetic), read at once for all frequencies and sources
        from the table's per-node layout (:attr:`by_node`).

        Parameters
        ----------
        turns : ndarray, shape (n_d,)
        r0, r1, z0, z1 : ndarray, shape (n_d,)
            Winding rectangles, m.

        Returns
        -------
        ndarray of complex, shape (n_d, n_f, n_sources)
            Wb per unit source.
        """
        per_area = np.asarray(turns, float) / ((r1 - r0) * (z1 - z0))
        nodes = self.by_node
        out = np.empty((per_area.size, nodes.shape[2]), dtype=nodes.dtype)

        def corner(rv, zv):
            i, u = _interp_weights(self.r, rv)
            j, v = _interp_weights(self.z, zv)
            u, v = u[:, None], v[:, None]
            return ((1 - u) * (1 - v) * nodes[i, j] + u * (1 - v) * nodes[i + 1, j]
                    + (1 - u) * v * nodes[i, j + 1] + u * v * nodes[i + 1, j + 1])

        for lo in range(0, per_area.size, _BLOCK):  # temporaries stay in cache
            b = slice(lo, lo + _BLOCK)
            out[b] = (per_area[b, None] * (corner(r1[b], z1[b]) - corner(r0[b], z1[b])
                                           - corner(r1[b], z0[b]) + corner(r0[b], z0[b])))
        return out.reshape(per_area.size, *self.cumulative.shape[:2])

    @cached_property
    def by_node(self) -> np.ndarray:
        """:attr:`cumulative` laid out per grid node, shape (nr, nz, n_f × n_sources)
        (computed once, not pickled)."""
        c = self.cumulative
        return np.ascontiguousarray(np.moveaxis(c, (0, 1), (2, 3))).reshape(
            c.shape[2], c.shape[3], -1)

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k != "by_node"}


def harmonic_tables(model: MechanismPotentials, geometry: SensorGeometry,
                    frequencies: Sequence[float], r_range: tuple[float, float],
                    z_range: tuple[float, float], spacing: float, *,
                    steel: float = SIGMA_1018,
                    magnets: Mapping[str, float] | None = None) -> HarmonicTables:
    """Solve every source of ``model`` at each frequency and tabulate it over a rectangle.

    Parameters
    ----------
    model : MechanismPotentials
        Bias solution and source loads of ``geometry``.
    geometry : SensorGeometry
    frequencies : sequence of float
        Hz, increasing from 0.
    r_range, z_range : (float, float)
        Region every coil design lies in, m.
    spacing : float
        Table grid spacing, m.
    steel, magnets
        Conductivities as :func:`msens.magnetics.dynamic.frequency_responses`.
    """
    return harmonic_tables_over(model, geometry, frequencies, [(r_range, z_range)], spacing,
                                steel=steel, magnets=magnets)[0]


def harmonic_tables_over(model: MechanismPotentials, geometry: SensorGeometry,
                         frequencies: Sequence[float],
                         ranges: Sequence[tuple[tuple[float, float], tuple[float, float]]],
                         spacing: float, *, steel: float = SIGMA_1018,
                         magnets: Mapping[str, float] | None = None) -> list[HarmonicTables]:
    """:func:`harmonic_tables` over several rectangles (e.g. the windows of several coils)
    from one factorisation and one set of source solves per frequency.

    Parameters
    ----------
    ranges : sequence of ((float, float), (float, float))
        (r_range, z_range) of each table, m.

    Other parameters as :func:`harmonic_tables`.

    Returns
    -------
    list of HarmonicTables
        One per rectangle, in the order of ``ranges``.
    """
    freqs = np.asarray([float(f) for f in frequencies])
    require(freqs.size >= 1 and freqs[0] == 0.0 and bool(np.all(np.diff(freqs) > 0)),
            f"frequencies must increase from 0 Hz, got {freqs.tolist()}")
    sol = model.solution
    op = HarmonicOperator(sol, sensor_conductivity(sol.problem.mesh, geometry, steel=steel,
                                                   magnets=magnets))
    # one probe matrix per rectangle for all frequencies
    grids = [table_grid(sol, r_rng, z_rng, spacing) for r_rng, z_rng in ranges]
    cumulative: list[list[np.ndarray]] = [[] for _ in grids]
    for f in freqs:
        pots = op.solve(op.factor(f), model.rhs)
        for acc, grid in zip(cumulative, grids, strict=True):
            acc.append(tabulate(grid, pots).cumulative)
    return [HarmonicTables(frequencies=freqs, r=g.r, z=g.z, cumulative=np.stack(acc))
            for g, acc in zip(grids, cumulative, strict=True)]


__all__ = ["HarmonicTables", "harmonic_tables", "harmonic_tables_over"]

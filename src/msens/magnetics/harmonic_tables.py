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

import numpy as np

from msens.errors import require
from msens.field.eddy import HarmonicOperator
from msens.field.geometry import SensorGeometry
from msens.magnetics.dynamic import sensor_conductivity
from msens.magnetics.mechanisms import MechanismPotentials
from msens.magnetics.potentials import LinkageTable, rect_integral, table_grid, tabulate
from msens.params.materials import SIGMA_1018


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
        As :attr:`LinkageTable.cumulative`, per frequency (Villari sources first, then
        approach sources, the order of :class:`MechanismPotentials`).
    """

    frequencies: np.ndarray
    r: np.ndarray
    z: np.ndarray
    cumulative: np.ndarray

    def linkage(self, turns: np.ndarray, r0: np.ndarray, r1: np.ndarray, z0: np.ndarray,
                z1: np.ndarray) -> np.ndarray:
        """Each coil's complex flux linkage of every source at every frequency.

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
        out = np.stack([rect_integral(LinkageTable(self.r, self.z, c), r0, r1, z0, z1)
                        for c in self.cumulative], axis=1)
        return per_area[:, None, None] * out


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
    freqs = np.asarray([float(f) for f in frequencies])
    require(freqs.size >= 1 and freqs[0] == 0.0 and bool(np.all(np.diff(freqs) > 0)),
            f"frequencies must increase from 0 Hz, got {freqs.tolist()}")
    sol = model.solution
    op = HarmonicOperator(sol, sensor_conductivity(sol.problem.mesh, geometry, steel=steel,
                                                   magnets=magnets))
    grid = table_grid(sol, r_range, z_range, spacing)  # one probe matrix for all frequencies
    tables = []
    for f in freqs:
        pots = op.solve(op.factor(f), model.rhs)
        tables.append(tabulate(grid, pots))
    return HarmonicTables(frequencies=freqs, r=tables[0].r, z=tables[0].z,
                          cumulative=np.stack([t.cumulative for t in tables]))


__all__ = ["HarmonicTables", "harmonic_tables"]

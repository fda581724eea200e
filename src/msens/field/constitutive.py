"""Per-element material data and the constitutive law H(B) at quadrature points.

Every region kind is reduced to H = ν B − H_c e_z with a per-element linear reluctivity ν and
coercivity H_c, except nonlinear soft regions whose ν depends on |B| (see :mod:`.bh`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from msens.errors import InputError
from msens.field.bh import MonotoneBH, monotone_bh
from msens.field.mesh import AxiMesh
from msens.field.regions import (
    Air,
    CurrentRegion,
    LinearMagnetic,
    NonlinearSoft,
    PermanentMagnet,
    Region,
)
from msens.params.units import MU0

NU0 = 1.0 / MU0
#: Flux density (T) whose secant reluctivity starts Newton in nonlinear regions.
INITIAL_SECANT_B = 1.8


@dataclass(frozen=True)
class Materials:
    """Material fields per element.

    Attributes
    ----------
    nu : ndarray, shape (n_elements,)
        Linear reluctivity, m/H (in nonlinear elements the secant value at
        ``INITIAL_SECANT_B``, Newton's initial guess).
    hc : ndarray, shape (n_elements,)
        Coercivity along +z, A/m (B_r/(μ0 μ_rec) in magnets).
    br : ndarray, shape (n_elements,)
        Remanence along +z, T.
    j : ndarray, shape (n_elements,)
        Azimuthal current density, A/m².
    soft : tuple of (ndarray, MonotoneBH)
        Element indices and B–H law of each nonlinear region.
    """

    nu: np.ndarray
    hc: np.ndarray
    br: np.ndarray
    j: np.ndarray
    soft: tuple[tuple[np.ndarray, MonotoneBH], ...]
    reversibility: tuple[float, ...] = ()

    @property
    def nonlinear(self) -> bool:
        """Whether any region is nonlinear."""
        return bool(self.soft)

    def take(self, elements: np.ndarray) -> Materials:
        """The fields of ``elements`` (int, shape (k,)), renumbered 0..k-1 in that order."""
        elements = np.asarray(elements)
        position = np.full(self.nu.size, -1)
        position[elements] = np.arange(elements.size)
        soft = []
        for el, law in self.soft:
            kept = position[el]
            soft.append((np.sort(kept[kept >= 0]), law))
        return Materials(nu=self.nu[elements], hc=self.hc[elements], br=self.br[elements],
                         j=self.j[elements], soft=tuple(soft), reversibility=self.reversibility)


def material_fields(mesh: AxiMesh, regions: Mapping[str, Region]) -> Materials:
    """Reduce the region records to per-element arrays."""
    ne = mesh.n_elements
    nu = np.full(ne, NU0)
    hc, br, j = np.zeros(ne), np.zeros(ne), np.zeros(ne)
    soft, reversibility = [], []
    for name, reg in regions.items():
        el = mesh.subdomains[name]
        if isinstance(reg, Air):
            continue
        if isinstance(reg, LinearMagnetic):
            nu[el] = NU0 / reg.mu_r
        elif isinstance(reg, PermanentMagnet):
            nu[el] = NU0 / reg.recoil_permeability
            hc[el] = reg.remanence * NU0 / reg.recoil_permeability
            br[el] = reg.remanence
        elif isinstance(reg, CurrentRegion):
            j[el] = reg.current_density
        elif isinstance(reg, NonlinearSoft):
            law = monotone_bh(reg.curve)
            # Newton's start: the secant reluctivity at 1.8 T (moderate saturation, mu_r ~ 120 for
            # 1018). On fieldmodel's hard sensor variant (269k dofs) starting at 1.0/1.4/1.6/1.8/
            # 2.0 T took 17/16/8/7/11 iterations; on the test models the choice barely matters.
            nu[el] = float(law.reluctivity(np.array(INITIAL_SECANT_B)))
            soft.append((el, law))
            reversibility.append(float(reg.reversibility))
        else:
            raise InputError(f"region '{name}': unknown region kind {type(reg).__name__}")
    soft, reversibility = _grouped(soft, reversibility)
    return Materials(nu=nu, hc=hc, br=br, j=j, soft=tuple(soft),
                     reversibility=tuple(reversibility))


def _grouped(soft: list, reversibility: list) -> tuple[list, list]:
    """One entry per (B–H curve, reversibility): every bead is its own region, and the
    Newton loop evaluates each entry's law once per iteration (33 small calls → 1)."""
    groups: dict[tuple, tuple[list, MonotoneBH, float]] = {}
    for (el, law), c in zip(soft, reversibility, strict=True):
        k = (law.curve.name, law.curve.b.tobytes(), law.curve.h.tobytes(), c)
        groups.setdefault(k, ([], law, c))[0].append(el)
    return ([(np.sort(np.concatenate(els)), law) for els, law, _ in groups.values()],
            [c for *_, c in groups.values()])


def reluctivities(mat: Materials, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Secant and differential reluctivity at quadrature points.

    Parameters
    ----------
    b : ndarray, shape (n_elements, n_qp, 2)
        Flux density, T.

    Returns
    -------
    nu, nu_d : ndarray, shape (n_elements, n_qp)
        H = ν B − H_c e_z; dH/dB along B is ν_d (equal to ν in linear elements), m/H.
    """
    nu = np.broadcast_to(mat.nu[:, None], b.shape[:2]).copy()
    nu_d = nu.copy()
    if mat.soft:
        bmag = np.sqrt(np.sum(b**2, axis=-1))
        for el, law in mat.soft:
            nu[el] = law.reluctivity(bmag[el])
            nu_d[el] = law.differential_reluctivity(bmag[el])
    return nu, nu_d


def field_strength(mat: Materials, b: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """H = ν B − H_c e_z, A/m, shape like ``b`` (n_elements, n_qp, 2)."""
    h = nu[..., None] * b
    h[..., 1] -= mat.hc[:, None]
    return h


def tangent(b: np.ndarray, nu: np.ndarray, nu_d: np.ndarray) -> np.ndarray:
    """Tangent reluctivity tensor dH/dB = ν I + (ν_d − ν) b̂ b̂ᵀ, shape (..., 2, 2)."""
    bmag = np.sqrt(np.sum(b**2, axis=-1))
    bhat = b / np.where(bmag > 0, bmag, 1.0)[..., None]
    out = (nu_d - nu)[..., None, None] * bhat[..., :, None] * bhat[..., None, :]
    out[..., 0, 0] += nu
    out[..., 1, 1] += nu
    return out


def small_signal_tangent(mat: Materials, b: np.ndarray) -> np.ndarray:
    """dH/dB for small signals about the bias flux density ``b``, shape (..., 2, 2).

    :func:`tangent` of the bias state, except that along B each nonlinear soft region sees only
    the reversible part c of its differential susceptibility (``NonlinearSoft.reversibility``):
    μ_along = μ0 + c (1/ν_d − μ0). Across B the secant reluctivity stays (a small transverse
    field rotates M reversibly). Newton's Jacobian of the bias solve is :func:`tangent`.
    """
    nu, nu_d = reluctivities(mat, b)
    for (el, _), c in zip(mat.soft, mat.reversibility, strict=False):
        if c != 1.0:
            nu_d[el] = 1.0 / (MU0 + c * (1.0 / nu_d[el] - MU0))
    return tangent(b, nu, nu_d)


def energy_density(mat: Materials, b: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Stored energy density w(B), J/m³, shape (n_elements, n_qp).

    Linear parts: ν |B − B_r e_z|²/2 (for a magnet the recoil-line energy, zero at B = B_r);
    nonlinear parts: ∫_0^|B| H dB'. ``nu`` is only used in the linear elements.
    """
    d = b.copy()
    d[..., 1] -= mat.br[:, None]
    w = 0.5 * nu * np.sum(d**2, axis=-1)
    if mat.soft:
        bmag = np.sqrt(np.sum(b**2, axis=-1))
        for el, law in mat.soft:
            w[el] = law.energy_density(bmag[el])
    return w

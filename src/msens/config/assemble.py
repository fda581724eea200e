"""Build the discrete chain of one setup from a validated study.

The chain package knows nothing of studies; this module is the one place that maps a
study's beads, rods, wall, damping and static precompression onto per-particle and
per-contact arrays (paper Eq. 6–9).
"""

from __future__ import annotations

import numpy as np

from msens.chain.model import Chain
from msens.config.schema import PrecompressionSpec, SetupSpec
from msens.config.study import Study
from msens.mechanics.hertz import hertz_sphere_flat, hertz_sphere_sphere


def precompression_forces(n_particles: int,
                          specs: tuple[PrecompressionSpec, ...]) -> np.ndarray:
    """Static particle forces that add a compression to a run of contacts.

    A force +F (toward the wall) on particle ``first`` and -F on particle ``last + 1``
    compress contacts c_first..c_last by F and leave every other contact unchanged, as a
    magnet pulling the beads of its gap together does.

    Returns
    -------
    ndarray, shape (n_particles,)
        Force on each particle, N, positive toward the wall.
    """
    f = np.zeros(n_particles)
    for s in specs:
        f[s.first - 1] += s.force_n
        f[s.last] -= s.force_n
    return f


def build_chain(study: Study, setup: SetupSpec, *, gamma_contact: float | None = None,
                gamma_wall: float | None = None,
                static_force: np.ndarray | None = None) -> Chain:
    """The chain of ``setup``: beads, inserted rods, wall, damping and static forces.

    Parameters
    ----------
    study : Study
    setup : SetupSpec
    gamma_contact, gamma_wall : float, optional
        Override the study's damping coefficients (used by calibration).
    static_force : ndarray, shape (n,), optional
        Extra static particle forces, N (e.g. magnetic, from the field model); added to the
        setup's declared precompression.

    Returns
    -------
    Chain
    """
    c = study.chain
    n = c.n_particles
    radius = 0.5 * c.bead_diameter_m
    mass = np.full(n, c.bead_mass_kg)
    length = np.full(n, c.bead_diameter_m)
    is_rod = np.zeros(n, dtype=bool)
    rod_e = np.zeros(n)
    rod_nu = np.zeros(n)
    for ins in setup.inserts:
        k = ins.particle - 1
        mass[k], length[k], is_rod[k] = ins.mass_kg, ins.length_m, True
        rod_e[k], rod_nu[k] = ins.youngs_modulus_pa, ins.poisson_ratio

    e, nu = c.youngs_modulus_pa, c.poisson_ratio
    a_ss = hertz_sphere_sphere(e, nu, radius, e, nu, radius)
    stiffness = np.full(n, a_ss)
    for k in range(n - 1):
        if is_rod[k] and is_rod[k + 1]:
            raise ValueError("two adjacent rods: flat-on-flat contact is not modelled")
        if is_rod[k] or is_rod[k + 1]:
            j = k if is_rod[k] else k + 1
            stiffness[k] = hertz_sphere_flat(e, nu, radius, rod_e[j], rod_nu[j])
    if is_rod[n - 1]:
        raise ValueError("a rod standing on the wall is not modelled")
    stiffness[n - 1] = hertz_sphere_flat(e, nu, radius, c.wall.youngs_modulus_pa,
                                         c.wall.poisson_ratio)

    gc = c.gamma_contact if gamma_contact is None else gamma_contact
    gw = c.gamma_wall if gamma_wall is None else gamma_wall
    damping = np.full(n, gc)
    damping[n - 1] = gw

    force = precompression_forces(n, setup.precompression)
    if static_force is not None:
        force = force + np.asarray(static_force, dtype=float)
    return Chain(mass=mass, stiffness=stiffness, damping=damping, static_force=force,
                 gravity=c.gravity_m_per_s2, damping_law=c.damping, length=length)

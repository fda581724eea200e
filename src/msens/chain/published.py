"""The chain of the reference paper ("A Comparative Study on Three Different Transducers for
the Measurement of Nonlinear Solitary Waves", shared/reference/hnsw-transducers-paper.txt),
as a parameter set for tests, benchmarks and examples.

Striker + 29 low-carbon steel beads (4.76 mm, 0.45 g; paper §2) on a steel base treated as a
half-space (E_w = 200 GPa, nu_w = 0.29: an assumption, the paper does not give the base
material), gamma_c = 4.8 kg/s, gamma_w = 0 (paper §5.1), drop height 7.2 mm. Piezo rods
(paper §2) can replace particles; their contacts with the neighbouring spheres use the
sphere-on-flat Hertz law of the two materials (paper §4.1).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from msens.chain.model import Chain, DampingLaw
from msens.mechanics.hertz import hertz_sphere_flat, hertz_sphere_sphere
from msens.params.materials import BEAD_STEEL, PIEZO_ROD, PIEZO_ROD_LENGTH, PIEZO_ROD_MASS
from msens.params.paper import BEAD_MASS, BEAD_RADIUS
from msens.params.units import G0

#: Particles including the striker (paper §2).
N_PARTICLES = 30
#: Striker drop height, m (paper §2).
DROP_HEIGHT = 7.2e-3
#: Fitted dissipation of the bead contacts, kg/s (paper §5.1).
GAMMA_CONTACT = 4.8
#: Fitted dissipation of the wall contact, kg/s (paper §5.1).
GAMMA_WALL = 0.0


def striker_velocity(drop_height: float = DROP_HEIGHT, gravity: float = G0) -> float:
    """Impact speed sqrt(2 g h) of a striker dropped from rest, m/s."""
    return float(np.sqrt(2.0 * gravity * drop_height))


def paper_chain(gamma_contact: float = GAMMA_CONTACT, gamma_wall: float = GAMMA_WALL, *,
                damping_law: DampingLaw = DampingLaw.LINEAR,
                rods_at: Iterable[int] = (), gravity: float = G0,
                static_force: np.ndarray | None = None,
                wall_modulus: float = BEAD_STEEL.youngs_modulus,
                wall_poisson: float = BEAD_STEEL.poisson_ratio) -> Chain:
    """The paper's 30-particle chain.

    Parameters
    ----------
    gamma_contact, gamma_wall : float
        Dissipation of bead-bead (and bead-rod) contacts and of the wall contact.
    damping_law : DampingLaw
        ``LINEAR_LOADING`` reproduces the paper's Table 2 with gamma_c = 4.8 kg/s.
    rods_at : iterable of int
        1-based particle numbers replaced by piezo rods (the paper uses 13 and 18).
    gravity : float
        m/s^2 along the chain.
    static_force : ndarray (30,), optional
        Extra static forces, N, +x.
    wall_modulus, wall_poisson : float
        Elastic constants of the base, Pa and -.

    Returns
    -------
    Chain
    """
    E, nu, R = BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio, BEAD_RADIUS
    n = N_PARTICLES
    mass = np.full(n, BEAD_MASS)
    length = np.full(n, 2.0 * R)
    stiffness = np.full(n, hertz_sphere_sphere(E, nu, R, E, nu, R))
    stiffness[-1] = hertz_sphere_flat(E, nu, R, wall_modulus, wall_poisson)
    rod_contact = hertz_sphere_flat(E, nu, R, PIEZO_ROD.youngs_modulus, PIEZO_ROD.poisson_ratio)
    for p in rods_at:
        if not 2 <= p <= n - 1:
            raise ValueError(f"rods_at: particle {p} must be in 2..{n - 1}")
        k = p - 1
        mass[k] = PIEZO_ROD_MASS
        length[k] = PIEZO_ROD_LENGTH
        stiffness[k - 1] = rod_contact  # sphere above on the rod's top face
        stiffness[k] = rod_contact      # rod's bottom face on the sphere below
    damping = np.full(n, float(gamma_contact))
    damping[-1] = gamma_wall
    return Chain(mass=mass, stiffness=stiffness, damping=damping,
                 static_force=np.zeros(n) if static_force is None else static_force,
                 gravity=gravity, damping_law=damping_law, length=length)

"""Static equilibrium of the chain before impact.

The striker (index 0) touches particle 2 with zero force; particles 2..n rest on the wall
under gravity and the static forces. In a chain the contact forces follow exactly from
cumulative sums of the loads above each contact, and each approach from inverting Hertz,
delta = (F/A)^{2/3}; no iteration is needed.
"""

from __future__ import annotations

import numpy as np

from msens.chain.model import Chain
from msens.errors import InputError
from msens.mechanics.hertz import hertz_approach


def static_contact_forces(chain: Chain) -> np.ndarray:
    """Static force in each contact, N, compressive positive.

    Contact 0 (striker on particle 2) carries zero force; contact k >= 1 carries the load
    (weight + static force) of particles 1..k (0-based).

    Parameters
    ----------
    chain : Chain

    Returns
    -------
    ndarray, shape (n,)

    Raises
    ------
    InputError
        If the loads would put a contact in tension (the chain would come apart): the
        static forces given cannot hold the chain together, a property of the input.
    """
    return contact_forces_from_loads(chain.load())


def contact_forces_from_loads(load: np.ndarray) -> np.ndarray:
    """:func:`static_contact_forces` from the particle loads (N), shape (..., n).

    Leading axes are independent chains (batches of runs).
    """
    force = np.zeros(load.shape)
    force[..., 1:] = np.cumsum(load[..., 1:], axis=-1)
    scale = np.cumsum(np.abs(load[..., 1:]), axis=-1)
    # Forces at rounding level of the loads above them count as zero, not as tension.
    tension = force[..., 1:] < -1e-12 * np.maximum(scale, 1e-300)
    if np.any(tension):
        idx = np.argwhere(tension)[0]
        k = int(idx[-1]) + 1
        n = load.shape[-1]
        what = "the wall" if k == n - 1 else f"particle {k + 2}"
        pos = (*(int(i) for i in idx[:-1]), k)
        run = f" in run {pos[:-1]}" if load.ndim > 1 else ""
        raise InputError(
            f"static loads put contact c_{k + 1} (particle {k + 1} on {what}){run} in tension "
            f"({force[pos]:.6g} N): the chain cannot be in static equilibrium (a static "
            "force pulls its beads apart more than their weight and the forces above hold "
            "them together)")
    return np.maximum(force, 0.0)


def static_equilibrium(chain: Chain) -> np.ndarray:
    """Displacements u0 (m, +x) of the pre-impact static equilibrium.

    Parameters
    ----------
    chain : Chain

    Returns
    -------
    ndarray, shape (n,)
        u0 with u0[n-1] = delta_wall, u0[k] = u0[k+1] + delta_k, and u0[0] = u0[1]
        (striker just touching).
    """
    return equilibrium_from_loads(chain.load(), chain.stiffness)


def equilibrium_from_loads(load: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """:func:`static_equilibrium` from loads (N) and Hertz prefactors (N/m^1.5), shape
    (..., n); leading axes are independent chains."""
    return equilibrium_from_forces(contact_forces_from_loads(load), stiffness)


def equilibrium_from_forces(force: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """:func:`static_equilibrium` from the static contact forces (N, from
    :func:`contact_forces_from_loads`) and Hertz prefactors (N/m^1.5), shape (..., n)."""
    delta = np.array(hertz_approach(force, stiffness), dtype=float, ndmin=1)
    delta[..., 0] = 0.0
    # u_k = sum_{j >= k} delta_j, summed from the wall up.
    return np.cumsum(delta[..., ::-1], axis=-1)[..., ::-1]

"""Static equilibrium: exact force balance from cumulative loads."""

import numpy as np
import pytest

from msens.chain import paper_chain, static_contact_forces, static_equilibrium, uniform_chain
from msens.chain.equilibrium import contact_forces_from_loads, equilibrium_from_loads


def test_contact_forces_are_cumulative_weights():
    c = paper_chain()
    f = static_contact_forces(c)
    w = c.mass[0] * c.gravity
    np.testing.assert_allclose(f, w * np.arange(30), rtol=1e-13)


def test_each_particle_below_the_striker_is_in_equilibrium():
    sf = np.zeros(30)
    sf[[11, 12, 13, 14]] = [1.8, 0.0, -0.3, 0.5]
    c = paper_chain(rods_at=(18,), static_force=sf)
    u = static_equilibrium(c)
    gap = np.concatenate([u[:-1] - u[1:], u[-1:]])
    assert np.all(gap >= 0) and u[0] == u[1]
    F = c.stiffness * np.maximum(gap, 0) ** 1.5
    net = c.load()[1:] + F[:-1] - F[1:]
    assert np.max(np.abs(net)) < 1e-12 * np.max(F)
    np.testing.assert_allclose(F, static_contact_forces(c), rtol=1e-12, atol=1e-300)


def test_pulling_static_force_names_the_contact():
    sf = np.zeros(6)
    sf[3] = -1.0  # pulls particle 4 up harder than the weight above it pushes down
    c = uniform_chain(6, 1e-3, 5e9, 7e9, static_force=sf)
    with pytest.raises(ValueError, match="c_4"):
        static_equilibrium(c)


def test_striker_force_balance_is_zero_and_uncompressed_chain_touches():
    c = uniform_chain(4, 1e-3, 5e9, 7e9, gravity=0.0)
    np.testing.assert_array_equal(static_equilibrium(c), np.zeros(4))
    assert static_contact_forces(c)[0] == 0.0


def test_batched_equilibrium_equals_per_chain():
    """The batched initial state of simulate_batch is the per-chain equilibrium, bit for bit."""
    chains = [paper_chain(static_force=np.linspace(0.0, s, 30)) for s in (0.0, 0.5, 2.0)]
    load = np.array([c.load() for c in chains])
    stiffness = np.array([c.stiffness for c in chains])
    u = equilibrium_from_loads(load, stiffness)
    for c, ui in zip(chains, u, strict=True):
        np.testing.assert_array_equal(ui, static_equilibrium(c))


def test_batched_tension_names_the_run():
    load = np.ones((3, 5))
    load[2, 3] = -10.0
    with pytest.raises(ValueError, match=r"contact c_4 .* in run \(2,\) in tension"):
        contact_forces_from_loads(load)

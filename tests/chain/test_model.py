"""Chain construction and validation."""

import dataclasses

import numpy as np
import pytest

from msens.chain import Chain, DampingLaw, paper_chain, uniform_chain


def _chain(**kw):
    base = dict(mass=np.ones(3), stiffness=np.ones(3), damping=np.zeros(3),
                static_force=np.zeros(3))
    base.update(kw)
    return Chain(**base)


def test_uniform_chain_layout():
    c = uniform_chain(5, 1e-3, 2e9, 3e9, 1.0, 0.5, length=4e-3)
    assert c.n_particles == c.n_contacts == 5
    np.testing.assert_array_equal(c.stiffness, [2e9] * 4 + [3e9])
    np.testing.assert_array_equal(c.damping, [1.0] * 4 + [0.5])
    np.testing.assert_array_equal(c.length, [4e-3] * 5)
    np.testing.assert_allclose(c.load(), 1e-3 * c.gravity)


@pytest.mark.parametrize("kw, word", [
    (dict(mass=np.ones(3), stiffness=np.ones(2)), "stiffness"),
    (dict(mass=-np.ones(3)), "mass"),
    (dict(stiffness=np.zeros(3)), "stiffness"),
    (dict(damping=-np.ones(3)), "damping"),
    (dict(static_force=np.full(3, np.nan)), "static_force"),
    (dict(length=np.ones(2)), "length"),
    (dict(mass=np.ones((3, 1))), "mass"),
    (dict(damping_law="linear"), "damping_law"),
])
def test_invalid_chains_raise_naming_the_field(kw, word):
    with pytest.raises(ValueError, match=word):
        _chain(**kw)


def test_chain_is_frozen_and_owns_read_only_arrays():
    m = np.ones(3)
    c = _chain(mass=m)
    m[0] = 5.0
    assert c.mass[0] == 1.0
    with pytest.raises(ValueError):
        c.mass[0] = 2.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.gravity = 0.0


def test_paper_chain_rods_replace_particles_and_their_contacts():
    c = paper_chain(rods_at=(13,))
    assert c.mass[12] == pytest.approx(0.8144e-3)
    assert c.stiffness[11] == c.stiffness[12] < c.stiffness[10]
    assert c.length[12] == pytest.approx(6e-3)
    assert c.damping_law is DampingLaw.LINEAR
    with pytest.raises(ValueError, match="rods_at"):
        paper_chain(rods_at=(1,))

"""Viscous drag of the particles on the tube (``Chain.drag``): exact solutions, the energy
balance, and the compiled kernel against the numpy reference path."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import simpson

from msens.chain import (
    Chain,
    DampingLaw,
    paper_chain,
    particle_accelerations,
    simulate,
    simulate_batch,
    simulate_reference,
    stable_step,
    striker_velocity,
)


def test_lone_particle_decays_exponentially():
    """One particle moving away from the wall (no contact, no gravity) with drag c:
    v(t) = v0 exp(-c t / m), u(t) = v0 (m / c) (1 - exp(-c t / m)). Asserted to 1e-10 of v0
    and of the travel v0 m / c (measured ~1e-13)."""
    m, c, v0 = 4.5e-4, 0.01, -0.3
    chain = Chain(mass=[m], stiffness=[1e10], damping=[0.0], static_force=[0.0], gravity=0.0,
                  drag=[c])
    t = np.linspace(0.0, 0.02, 2001)  # c t / m up to 0.44
    r = simulate(chain, v0, t, states=True, dt=1e-5)
    decay = np.exp(-c * t / m)
    np.testing.assert_allclose(r.velocity[:, 0], v0 * decay, rtol=0, atol=1e-10 * abs(v0))
    travel = v0 * m / c
    np.testing.assert_allclose(r.displacement[:, 0], travel * (1.0 - decay), rtol=0,
                               atol=1e-10 * abs(travel))
    assert np.all(r.force == 0.0)  # it never touches the wall


def test_zero_drag_is_the_default():
    c = paper_chain()
    assert np.array_equal(c.drag, np.zeros(c.n_particles))
    with pytest.raises(ValueError, match="drag"):
        dataclasses.replace(c, drag=-np.ones(c.n_particles))


def _energy(chain: Chain, u: np.ndarray, v: np.ndarray, delta: np.ndarray) -> np.ndarray:
    # Mechanical energy, J, per sample: kinetic + Hertz (2/5 A delta^{5/2}) - work potential
    # of the constant loads (gravity and static forces).
    d = np.maximum(delta, 0.0)
    return (0.5 * (chain.mass * v**2).sum(axis=1) + 0.4 * (chain.stiffness * d**2.5).sum(axis=1)
            - (chain.load() * u).sum(axis=1))


def _balance(chain: Chain, samples: int, dt: float | None = None) -> tuple[float, float, float]:
    # (E(0) - E(T) - dashpot work - drag work, dashpot work, drag work) over 1 ms, each over
    # the striker's kinetic energy; the powers integrated by Simpson on the samples.
    v0 = striker_velocity()
    t = np.linspace(0.0, 1e-3, samples)
    r = simulate(chain, v0, t, states=True, dt=dt)
    u, v, delta = r.displacement, r.velocity, r.approach
    rate = np.concatenate([v[:, :-1] - v[:, 1:], v[:, -1:]], axis=1)
    elastic = chain.stiffness * np.maximum(delta, 0.0) ** 1.5
    w_dashpot = simpson(((r.force - elastic) * rate).sum(axis=1), x=t)
    w_drag = simpson((chain.drag * v**2).sum(axis=1), x=t)
    e = _energy(chain, u, v, delta)
    ke0 = 0.5 * chain.mass[0] * v0**2
    return ((e[0] - e[-1]) - w_dashpot - w_drag) / ke0, w_dashpot / ke0, w_drag / ke0


def test_energy_balance_with_drag():
    """Paper chain without dashpots, drag 0.05 N s/m on every bead: E(0) - E(T) =
    int sum c v^2 dt. Measured 4.3e-7 of the striker's kinetic energy at the default step
    (5.6e-9 at half of it: the integration error); asserted 1e-6. The drag takes 4 %."""
    chain = dataclasses.replace(paper_chain(gamma_contact=0.0), drag=np.full(30, 0.05))
    balance, w_dashpot, w_drag = _balance(chain, 10001)
    assert abs(w_dashpot) < 1e-12 and w_drag > 0.02
    assert abs(balance) <= 1e-6


def test_energy_balance_with_contact_dashpots_and_drag():
    """Kuwabara-Kono dashpots (force continuous where contacts switch, so the dissipated power
    can be integrated on the samples) and drag 0.05 N s/m: E(0) - E(T) = int (dashpot power
    + sum c v^2) dt. Limited by the quadrature of the power's sqrt(delta) onsets: measured
    1.9e-5 of the striker's kinetic energy on 10 MHz samples, 2.5e-6 on 40 MHz; asserted
    5e-6 on 40 MHz. The dashpots take 84 %, the drag 4 %."""
    base = paper_chain(damping_law=DampingLaw.HERTZ_KUWABARA_KONO, gamma_contact=3e3)
    chain = dataclasses.replace(base, drag=np.full(base.n_particles, 0.05))
    balance, w_dashpot, w_drag = _balance(chain, 40001)
    assert w_dashpot > 0.5 and w_drag > 0.02
    assert abs(balance) <= 5e-6


@pytest.mark.parametrize("law", list(DampingLaw))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kernel_matches_numpy_reference_with_drag(seed, law):
    """Seeded random chains with drag (c/m up to 400/s): the compiled kernel's forces against
    SciPy's DOP853 on the numpy right-hand side (:func:`particle_accelerations`, rtol 1e-12),
    within the tolerances of the drag-free check (3e-7 of the peak force, 1e-6 for
    Kuwabara-Kono); and the drag changes the forces by far more than that."""
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(6, 13))
    mass = rng.uniform(0.01, 0.05, n)
    chain = Chain(mass=mass, stiffness=rng.uniform(5e9, 2e10, n),
                  damping=rng.uniform(0.0, 8.0, n), static_force=rng.uniform(0.0, 1.0, n),
                  damping_law=law, drag=rng.uniform(0.0, 400.0, n) * mass)
    v = rng.uniform(0.1, 1.0)
    t = np.linspace(0.0, 3e-4, 3001)
    ref = simulate_reference(chain, v, t, rtol=1e-12).force
    force = simulate(chain, v, t).force
    tol = 1e-6 if law is DampingLaw.HERTZ_KUWABARA_KONO else 3e-7
    assert np.max(np.abs(force[1:] - ref[1:])) <= tol * np.max(ref)
    no_drag = simulate(dataclasses.replace(chain, drag=None), v, t).force
    assert np.max(np.abs(no_drag - force)) > 100 * tol * np.max(ref)


def test_numpy_accelerations_include_the_drag():
    """m a = load + F_{k-1} - F_k - c v: with all contacts open only load and drag act."""
    chain = dataclasses.replace(paper_chain(), drag=np.linspace(0.0, 0.01, 30))
    u = -np.arange(30.0)[::-1] * 1e-3  # every gap open
    v = np.linspace(-0.1, 0.1, 30)
    expected = (chain.load() - chain.drag * v) / chain.mass
    np.testing.assert_allclose(particle_accelerations(chain, u, v), expected, rtol=1e-15)


def test_batch_with_drag_equals_single_runs():
    v = striker_velocity()
    t = np.linspace(0.0, 5e-4, 501)
    chains = [dataclasses.replace(paper_chain(), drag=np.full(30, c)) for c in (0.0, 2e-3, 1e-2)]
    batch = simulate_batch(chains, v, t)
    for i, c in enumerate(chains):
        np.testing.assert_array_equal(batch.force[i], simulate(c, v, t).force)


def test_stable_step_resolves_a_strong_drag():
    """The step stays below half the drag time m/c."""
    chain = dataclasses.replace(paper_chain(), drag=np.full(30, 1.0))
    assert stable_step(chain, striker_velocity()) <= 0.5 * chain.mass.min() / 1.0

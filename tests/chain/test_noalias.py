"""The kernels compiled with ``njit_noalias`` compute what plain ``njit`` computes from the
same source, on arguments that keep its contract (no written array overlaps another)."""

from __future__ import annotations

import numba as nb
import numpy as np
import pytest

from msens.chain import kernel
from msens.chain.kernel import dop853_step, events, sampling
from msens.chain.kernel.noalias import njit_noalias

N = 30
P = kernel.padded_length(N)
SENSED = np.array([11, 12, 16, 17])

#: The passes over the particle arrays, compiled noalias (see msens.chain.kernel.noalias).
KERNELS = {"rk_step": dop853_step.rk_step, "accelerations": kernel.accelerations,
           "jerks": kernel.jerks, "contact_forces": kernel.contact_forces,
           "violated": events.violated, "openings_within": events.openings_within,
           "switch_candidates": events.switch_candidates, "sample_gaps": sampling.sample_gaps,
           "sample_contacts": sampling.sample_contacts}


def _chain_state(seed=3):
    # A closed, moving 30-particle chain on the kernel's padded layout.
    rng = np.random.default_rng(seed)
    u = np.zeros(P + 1)
    v = np.zeros(P + 1)
    u[:N] = np.cumsum(rng.uniform(0.5e-6, 1.5e-6, N))[::-1]
    v[:N] = rng.uniform(-0.1, 0.1, N)
    cA, cg, load, inv_m, drag = (np.zeros(P) for _ in range(5))
    cA[:N] = rng.uniform(5e9, 1e10, N)
    cg[:N] = rng.uniform(0.0, 9.6, N)
    load[:N] = 0.044
    inv_m[:N] = 1.0 / 4.5e-3
    drag[:N] = rng.uniform(0.0, 50.0, N)  # tube drag c/m, 1/s
    return u, v, cA, cg, load, inv_m, drag


def _calls(name):
    """Argument tuples of one call of each noalias kernel (no two written arrays overlap)."""
    u, v, cA, cg, load, inv_m, drag = _chain_state()
    a = np.zeros(P + 1)
    kernel.accelerations(u, v, cA, cg, kernel.LAW_LINEAR, load, inv_m, drag, a)
    kv = np.zeros((dop853_step.N_STAGES, P + 1))
    closed = np.zeros(P)  # contact states are padded like cA
    closed[:N] = 1.0
    return {
        "rk_step": (u, v, a, 2e-6, dop853_step.STEP_REGULAR, cA, cg, False, load, inv_m, drag, kv,
                    np.zeros(P + 1), np.zeros(P + 1), np.zeros(P + 1), np.zeros(P + 1)),
        "accelerations": (u, v, cA, cg, kernel.LAW_LINEAR_LOADING, load, inv_m, drag,
                          np.zeros(P + 1)),
        "jerks": (u, v, a, cA, cg, inv_m, drag, np.zeros(P + 1)),
        "contact_forces": (u, v, cA, cg, kernel.LAW_HKK, np.zeros(P + 1)),
        "violated": (u, v, closed, closed, cg, 1e-12, True, -1),
        "openings_within": (u, v, a, closed, 2e-6, np.zeros(P)),
        "switch_candidates": (v, a, closed, (cg > 3.0) * closed, cg, 1e-12, 2e-6,
                               np.zeros(P)),
        # two steps' worth of samples (weights) and five (monomial coefficients)
        "sample_gaps": (np.linspace(0.0, 4e-6, 5), 1, 0.0, 2e-6, u, v, a, np.zeros(P + 1),
                         u + 2e-6 * v, v + 2e-6 * a, a, np.zeros(P + 1), cA, cg,
                         kernel.LAW_LINEAR, True, np.zeros((5, P)), np.zeros((5, P)),
                         np.zeros((8, P + 1))),
        "sample_gaps_many": (np.linspace(0.0, 2e-6, 6), 1, 0.0, 2e-6, u, v, a,
                              np.zeros(P + 1), u + 2e-6 * v, v + 2e-6 * a, a, np.zeros(P + 1),
                              cA, cg, kernel.LAW_LINEAR, True, np.zeros((6, P)),
                              np.zeros((6, P)), np.zeros((8, P + 1))),
        # the same for four contacts (the sensors' of the paper)
        "sample_contacts": (np.linspace(0.0, 4e-6, 5), 1, 0.0, 2e-6, u, v, a, np.zeros(P + 1),
                             u + 2e-6 * v, v + 2e-6 * a, a, np.zeros(P + 1), cA, cg,
                             kernel.LAW_LINEAR, True, np.zeros((5, 4)), np.zeros((5, 4)),
                             np.zeros((8, P + 1)), SENSED),
        "sample_contacts_many": (np.linspace(0.0, 2e-6, 6), 1, 0.0, 2e-6, u, v, a,
                                  np.zeros(P + 1), u + 2e-6 * v, v + 2e-6 * a, a,
                                  np.zeros(P + 1), cA, cg, kernel.LAW_LINEAR, True,
                                  np.zeros((6, 4)), np.zeros((6, 4)), np.zeros((8, P + 1)),
                                  SENSED),
    }[name]


@pytest.mark.parametrize("name", ["rk_step", "accelerations", "jerks", "contact_forces",
                                  "violated", "openings_within", "switch_candidates",
                                  "sample_gaps", "sample_gaps_many", "sample_contacts",
                                  "sample_contacts_many"])
def test_noalias_kernel_computes_what_plain_njit_computes(name):
    """Compiled afresh (no cache) with and without the no-overlap declaration: the same
    return value and the same arrays to rounding (the compiler may contract other
    multiply-adds; measured: 1.4e-14 relative at most, in ``accelerations``)."""
    fn = KERNELS[name.removesuffix("_many")]
    options = {k: v for k, v in fn.targetoptions.items() if k == "fastmath"}
    fresh = njit_noalias(**options)(fn.py_func)
    plain = nb.njit(**options)(fn.py_func)
    args = _calls(name)
    copies = [tuple(x.copy() if isinstance(x, np.ndarray) else x for x in args) for _ in "ab"]
    r_fresh = fresh(*copies[0])
    r_plain = plain(*copies[1])
    assert r_fresh == r_plain
    for x, y in zip(*copies, strict=True):
        if isinstance(x, np.ndarray):
            np.testing.assert_allclose(x, y, rtol=1e-13, atol=0.0)

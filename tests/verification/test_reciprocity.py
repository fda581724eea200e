"""Reciprocity (μ0 ∫ h1·ΔM dV) against direct perturbation, and the approach adjoint.

Default group: a small one-sensor model (coarse mesh, ~1 s per solve).
Slow group: the default sensor geometry (both paper sensors, all 29 beads).

Tolerances: the brief's acceptance is 1 %. The linear direct perturbation (re-solving the
tangent problem with ΔM as the source) is the discrete adjoint identity, so it agrees to
round-off (asserted 1e-9). The nonlinear central difference (full Newton re-solve with ±ε ΔM)
is an independent check of the tangent, the incremental solve and reciprocity; its error is
O(ε²) (asserted: < 1e-3 at ε = 0.1 N and an observed order >= 1.8 between ε = 1 and 0.1 N).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, BiasMagnet, Coil, SensorGeometry, SensorUnit
from msens.field.sensor_model import bias_problem, load_mesh
from msens.field.solve import solve
from msens.villari import (
    StressSampler,
    TangentOperator,
    approach_flux_change,
    approach_residuals,
    bead_state,
    bead_stress,
    coil_flux_linkage,
    hertz_approach_rate,
    nonlinear_flux_change,
    reciprocity_flux,
    reluctance_sensitivity,
    stress_magnetisation,
    villari_sensitivities,
)

COARSE = MeshOptions(bead_size=0.6e-3, centre_size=0.3e-3, flat_fraction=0.8, wedge_factor=4.0)


def _setup(geometry, options, mesh_dir):
    axi, _ = load_mesh(geometry, options, mesh_dir)
    sol = solve(bias_problem(geometry, axi), max_iter=40, tol=1e-11)
    return axi, sol


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    g = SensorGeometry(beads=BeadChain(first=9, last=17),
                       sensors=(SensorUnit(Coil(particle=13), BiasMagnet(particle=13)),),
                       air=AirBox(0.06, 0.05))
    axi, sol = _setup(g, COARSE, tmp_path_factory.mktemp("meshes"))
    return g, axi, sol


def _dm(g, axi, sol, coil, particle):
    state = bead_state(sol, coil)
    bs = bead_stress(g, g.beads.contact_load)
    el = axi.subdomains[f"bead_{particle}"]
    return state, el, stress_magnetisation(sol, state, StressSampler(bs), el,
                                           g.beads.center(particle))


def test_reciprocity_equals_linear_direct_perturbation(small):
    g, _, sol = small
    coil = g.sensors[0].coil
    res = villari_sensitivities(sol, g, coil, bead_stress(g, g.beads.contact_load),
                                direct=True)
    assert np.all(np.isfinite(res.direct))
    assert res.relative_error <= 1e-9


@pytest.mark.parametrize("particle", [13, 16])
def test_reciprocity_against_nonlinear_perturbation(small, particle):
    g, axi, sol = small
    coil = g.sensors[0].coil
    state, el, dm = _dm(g, axi, sol, coil, particle)
    s = reciprocity_flux(sol, state, el, dm)
    errs = [abs(nonlinear_flux_change(sol, el, dm, coil, eps) - s) / abs(s)
            for eps in (1.0, 0.1)]
    assert errs[1] < 1e-3
    if errs[0] > 1e-5:  # above round-off: the central difference is second order
        assert math.log10(errs[0] / errs[1]) >= 1.8


def test_direct_solution_flux_is_linear_in_source(small):
    g, axi, sol = small
    coil = g.sensors[0].coil
    _, el, dm = _dm(g, axi, sol, coil, 12)
    op = TangentOperator(sol)
    one = coil_flux_linkage(sol, op.solve_magnetisation(el, dm), coil)
    three = coil_flux_linkage(sol, op.solve_magnetisation(el, 3.0 * dm), coil)
    assert three == pytest.approx(3.0 * one, rel=1e-12)


def test_approach_adjoint_against_nonlinear_resolve(small):
    g, _, sol = small
    coil = g.sensors[0].coil
    state = bead_state(sol, coil)
    res = approach_residuals(sol, g, [12, 13])
    rel = reluctance_sensitivity(state, res, hertz_approach_rate(2.0, g.beads.radius))
    for k, c in enumerate(rel.contacts):
        resolve = approach_flux_change(sol, g, int(c), coil, 1e-9)
        assert resolve == pytest.approx(rel.dlambda_dapproach[k], rel=1e-5)
    # pressing the beads together draws more bias flux through the coil: |Λ| grows
    lam = coil_flux_linkage(sol, sol.a, coil)
    assert np.all(np.sign(rel.dlambda_dapproach) == np.sign(lam))


@pytest.mark.slow
def test_reciprocity_default_model(tmp_path_factory):
    g = SensorGeometry()
    axi, sol = _setup(g, None, tmp_path_factory.mktemp("meshes"))
    bs = bead_stress(g, g.beads.contact_load)
    for unit in g.iter_units():
        coil = unit.coil
        p = coil.particle
        res = villari_sensitivities(sol, g, coil, bs, direct=[p - 1, p, p + 1])
        assert res.relative_error <= 1e-9
        state, el, dm = _dm(g, axi, sol, coil, p)
        s = reciprocity_flux(sol, state, el, dm)
        assert nonlinear_flux_change(sol, el, dm, coil, 0.1) == pytest.approx(s, rel=1e-2)
        rel = reluctance_sensitivity(state, approach_residuals(sol, g, [p]), 1.0)
        assert approach_flux_change(sol, g, p, coil, 1e-9) == pytest.approx(
            rel.dlambda_dapproach[0], rel=1e-2)

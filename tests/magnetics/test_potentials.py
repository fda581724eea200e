"""Source potentials and the summed-area coil quadrature of design sweeps.

Small model (beads 10..16, one sensor at 13) so the default suite stays fast.
"""

from __future__ import annotations

import numpy as np
import pytest

from msens.field.geometry import BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.field.probes import p2_probes
from msens.field.sensor_model import bias_problem, load_mesh
from msens.field.solve import solve
from msens.magnetics.mechanisms import coil_linkage, mechanism_potentials
from msens.magnetics.potentials import (
    LinkageTable,
    _cumtrapz,
    linkage_table,
    rect_integral,
    region_linkage,
)
from msens.magnetics.steel_law import law_for_steel
from msens.store import Store


def _geometry(magnet: bool) -> SensorGeometry:
    unit = SensorUnit(Coil(particle=13), BiasMagnet(particle=13) if magnet else None)
    return SensorGeometry(beads=BeadChain(first=10, last=16), sensors=(unit,))


def _model(g, mesh_dir):
    axi, _ = load_mesh(g, store=Store.at(mesh_dir))
    sol = solve(bias_problem(g, axi), max_iter=40)
    return sol, mechanism_potentials(sol, g, stress_force=g.beads.contact_load,
                                     law=law_for_steel(g.steel))


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    g = _geometry(True)
    sol, m = _model(g, tmp_path_factory.mktemp("meshes"))
    return g, sol, m


def test_sources_of_both_mechanisms(model):
    g, _, m = model
    assert m.particles.tolist() == list(range(10, 17))
    assert m.contacts.tolist() == list(range(10, 17))
    link = coil_linkage(m, g.sensors[0].coil)
    contacts, s_vil, dl = m.contact_profiles(link)
    assert contacts.tolist() == list(range(9, 17))
    # the contact below the coil's bead draws more bias flux through it: the largest
    # approach term sits at the coil
    assert int(contacts[np.argmax(np.abs(dl))]) in (12, 13)
    assert np.all(np.abs(s_vil[3:5]) > 0)


def test_table_quadrature_matches_mesh_quadrature(model):
    g, sol, m = model
    pot = m.potentials
    coil = g.sensors[0].coil
    rect = g.coil_rect(g.sensors[0])
    table = linkage_table(sol, pot, (6.4e-3, rect.r1 + 1e-3), (rect.z0 - 1e-3, rect.z1 + 1e-3))
    got = coil.turns / coil.area * rect_integral(table, np.array([rect.r0]),
                                                 np.array([rect.r1]), np.array([rect.z0]),
                                                 np.array([rect.z1]))[0]
    exact = region_linkage(sol, pot, "coil_13", coil.turns, coil.area)
    np.testing.assert_allclose(got, exact, rtol=1e-4)


def test_p2_probes_match_skfem(model):
    _, sol, m = model
    pot = m.potentials
    rng = np.random.default_rng(0)
    r = rng.uniform(6.5e-3, 15e-3, 12)
    z = rng.uniform(0.05, 0.08, 12)
    ref = sol.basis.probes(np.vstack([r, z])) @ pot[1]
    np.testing.assert_allclose(p2_probes(sol.basis, r, z) @ pot[1], ref, rtol=1e-11,
                               atol=1e-14 * np.max(np.abs(ref)))


def test_rect_integral_converges_second_order():
    def f(r, z):
        return np.exp(-r) * np.cos(2 * z) * r

    def exact(r0, r1, z0, z1):
        fr = lambda r: -(r + 1) * np.exp(-r)  # noqa: E731  ∫ r e^-r dr
        return (fr(r1) - fr(r0)) * (np.sin(2 * z1) - np.sin(2 * z0)) / 2

    rng = np.random.default_rng(3)
    r0, r1 = np.sort(rng.uniform(0.0, 1.0, (2, 40)), axis=0)
    z0, z1 = np.sort(rng.uniform(-1.0, 1.0, (2, 40)), axis=0)
    errs = []
    for n in (11, 21, 41, 81, 161):
        r = np.linspace(0.0, 1.0, n)
        z = np.linspace(-1.0, 1.0, 2 * n - 1)
        cum = _cumtrapz(_cumtrapz(f(*np.meshgrid(r, z, indexing="ij"))[None], r[1] - r[0], 1),
                        z[1] - z[0], 2)
        t = LinkageTable(r, z, cum)
        got = rect_integral(t, r0, r1, z0, z1)[:, 0]
        errs.append(np.max(np.abs(got - exact(r0, r1, z0, z1))))
    order = -np.polyfit(np.log([11, 21, 41, 81, 161]), np.log(errs), 1)[0]
    assert 1.8 < order < 2.3, (order, errs)


def test_no_magnet_no_signal(tmp_path):
    g = _geometry(False)
    _, m = _model(g, tmp_path)
    assert all(np.all(src == 0.0) for _, src in m.villari_sources)
    link = coil_linkage(m, g.sensors[0].coil)
    assert np.all(link == 0.0)

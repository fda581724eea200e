"""The nonlinear contact map Λ_c(δ) against full nonlinear solves on its layer mesh.

A small one-sensor model (coarse mesh, ~0.6 s per nonlinear re-solve). Tolerances: the
brief's acceptance is 1 % of the flux change Λ(δ) − Λ(δ_static) between the table and a full
solve at three pulse loads and one open gap; superposition of two neighbouring contacts
(one solve) against the single-contact changes, 1 % of the joint change.
"""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.field.build import MeshOptions
from msens.field.cache import geometry_key
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.field.sensor_model import bias_problem, load_mesh
from msens.field.solve import solve
from msens.magnetics.approach import hertz_stiffness
from msens.magnetics.contact_map import (
    CLOSED_THICKNESS,
    ContactMap,
    contact_flux,
    contact_map,
    layer_geometry,
    layer_model,
    state_flux,
    static_approach,
)
from msens.magnetics.mechanisms import coil_linkage, mechanism_potentials
from msens.magnetics.steel_law import law_for_steel
from msens.mechanics.hertz import hertz_approach
from msens.store import Store, committed_dirs

COARSE = MeshOptions(bead_size=0.6e-3, centre_size=0.3e-3, flat_fraction=0.8, wedge_factor=4.0)
CONTACT = 12
OPEN = -11.25e-6  # the main study's most negative approach near coil 13 (contact 10)


def _small() -> SensorGeometry:
    return SensorGeometry(beads=BeadChain(first=9, last=17),
                          sensors=(SensorUnit(Coil(particle=13), BiasMagnet(particle=13)),),
                          air=AirBox(0.06, 0.05))


@pytest.fixture(scope="module")
def layered(tmp_path_factory):
    g = _small()
    d = tmp_path_factory.mktemp("meshes")
    model = layer_model(g, CONTACT, COARSE, Store.at(d))
    coil = g.sensors[0].coil
    table = contact_map(model, coil, (0.0, 0.7e-6, 1.4e-6, 2.0e-6),
                        (1e-9, 0.1e-6, 0.5e-6, 2e-6, 6e-6, 14e-6))
    return g, model, coil, table, d


def test_default_geometry_keeps_its_committed_mesh():
    key = geometry_key(SensorGeometry())
    assert any((d / f"sensor-{key}.msh").is_file() for d in committed_dirs())


def test_layer_geometry_lifts_the_beads_above():
    g = _small()
    lg = layer_geometry(g, CONTACT)
    b, lb = g.beads, lg.beads
    h = lb.contact_layer[1]
    for p in b.particles:
        assert lb.center(p) - b.center(p) == pytest.approx(h if p <= CONTACT else 0.0,
                                                           abs=1e-15)
    q = lb.layer_rect()
    assert (q.r0, q.r1) == (0.0, b.flat_radius)
    # the disc fills the space between the two flats exactly
    assert q.z1 == pytest.approx(lb.center(CONTACT) - lb.half_height, abs=1e-15)
    assert q.z0 == pytest.approx(lb.center(CONTACT + 1) + lb.half_height, abs=1e-15)
    with pytest.raises(InputError, match="contact_layer"):
        BeadChain(first=9, last=17, contact_layer=(17, 1e-7))
    with pytest.raises(InputError, match="contact_layer thickness"):
        BeadChain(first=9, last=17, contact_layer=(12, 1e-5))


def test_layer_mesh_has_the_disc(layered):
    _, model, *_ = layered
    axi = model.steel.problem.mesh
    q = model.geometry.beads.layer_rect()
    el = axi.subdomains[q.name]
    p = axi.mesh.p[:, axi.mesh.t[:, el]]
    assert p[0].min() == 0.0
    assert p[0].max() == pytest.approx(q.r1, rel=1e-9)
    assert (p[1].min(), p[1].max()) == (pytest.approx(q.z0, abs=1e-12),
                                        pytest.approx(q.z1, abs=1e-12))
    x, y = axi.mesh.p[:, axi.mesh.t[:, el]]
    area = 0.5 * np.abs((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0])).sum()
    assert area == pytest.approx((q.r1 - q.r0) * (q.z1 - q.z0), rel=1e-9)


def test_closed_branch_is_the_linear_approach_source(layered):
    """The steel disc's slope at δ_s against the plain mesh's approach source (another
    mesh: agreement to the meshes' discretisation error, 2 %)."""
    g, _, coil, table, d = layered
    axi, _ = load_mesh(g, COARSE, Store.at(d))
    sol = solve(bias_problem(g, axi), max_iter=40, tol=1e-11)
    model = mechanism_potentials(sol, g, stress_force=g.beads.contact_load,
                                 law=law_for_steel(g.steel))
    k = int(np.flatnonzero(model.contacts == CONTACT)[0])
    linear = coil_linkage(model, coil)[model.particles.size + k]
    assert table.slope(table.delta_static) == pytest.approx(linear, rel=2e-2)


def test_branches_meet_where_the_gap_closes(layered):
    """The open disc at a 1 nm gap is the closed contact (Λ continuous at δ_s): within 1e-4
    of the change over a 1 µm approach."""
    _, model, coil, table, _ = layered
    ds = table.delta_static
    scale = abs(table(ds + 1e-6))
    steel = state_flux(model, "steel", ds, coil)
    air = state_flux(model, "air", ds - CLOSED_THICKNESS, coil)
    assert abs(air - steel) < 1e-4 * scale


def test_table_against_full_solves(layered):
    """Three pulse loads and one open gap, none a table node: within 1 % of the change from
    the static approach."""
    g, model, coil, table, _ = layered
    stiffness = hertz_stiffness(g.beads.radius)
    static = float(hertz_approach(g.beads.contact_load, stiffness))
    assert static == pytest.approx(static_approach(g), rel=1e-9)  # the flat's own approach
    base = contact_flux(model, static, coil)
    for delta in [*(float(hertz_approach(f, stiffness)) for f in (7.0, 8.5, 10.0)), OPEN]:
        solved = contact_flux(model, delta, coil) - base
        assert float(table(delta) - table(static)) == pytest.approx(solved, rel=1e-2)


def test_blend_inside_the_bridge_range(layered):
    """Between 0 and δ_s the map is the area-weighted blend of the two branches' solves."""
    _, model, coil, table, _ = layered
    ds = table.delta_static
    delta = 0.37 * ds
    ref = state_flux(model, "steel", ds, coil)
    solved = contact_flux(model, delta, coil) - ref
    assert float(table(delta)) == pytest.approx(solved, rel=1e-2)


def test_superposition_of_neighbours(layered):
    """The contact open and its lower neighbour at the 10 N approach in one solve, against
    the sum of the single-contact changes (same mesh): 1 %."""
    g, model, coil, table, _ = layered
    ds = table.delta_static
    nb = float(hertz_approach(10.0, hertz_stiffness(g.beads.radius))) - ds
    ref = state_flux(model, "steel", ds, coil)
    alone = state_flux(model, "air", OPEN, coil) - ref
    neighbour = state_flux(model, "steel", ds, coil, {CONTACT + 1: nb}) - ref
    joint = state_flux(model, "air", OPEN, coil, {CONTACT + 1: nb}) - ref
    assert alone + neighbour == pytest.approx(joint, rel=1e-2)


def test_map_is_continuous_and_blends():
    """Pure-table checks: the blend is continuous at 0 and δ_s and equals each branch
    outside (0, δ_s)."""
    m = ContactMap(contact=5, delta_static=0.5e-6,
                   steel_delta=np.array([0.0, 1e-6, 2e-6]),
                   steel_flux=np.array([1.0, -1.0, -3.0]) * 1e-6,
                   air_gap=np.array([1e-9, 1e-6, 1e-5]),
                   air_flux=np.array([0.0, 1.2, 10.0]) * 1e-6)
    eps = 1e-13
    for x in (0.0, 0.5e-6):
        assert float(m(x - eps)) == pytest.approx(float(m(x + eps)), abs=1e-12)
    assert float(m(-2e-6)) == pytest.approx(float(m.air(-2e-6)), rel=1e-12)
    assert float(m(1.5e-6)) == pytest.approx(float(m.steel(1.5e-6)), rel=1e-12)
    assert float(m(0.25e-6)) == pytest.approx(
        0.5 * float(m.air(0.25e-6)) + 0.5 * float(m.steel(0.25e-6)), rel=1e-12)
    # the equivalent approach is the map's shape: unit slope at δ_s from the closed side
    from msens.magnetics.contact_map import ApproachMap

    eq = ApproachMap((m,)).equivalent(np.array([[0.5e-6], [0.5e-6 + 1e-10]]), np.array([5]))
    assert float(eq[0, 0]) == pytest.approx(0.5e-6, abs=1e-18)
    assert float(eq[1, 0] - eq[0, 0]) == pytest.approx(1e-10, rel=1e-4)


# ----------------------------------------------------------------------------- wiring

def _wired(mapped: bool):
    """A two-contact transducer; contact 10 (if ``mapped``) read through a nonlinear map."""
    from msens.magnetics.contact_map import ApproachMap
    from msens.magnetics.transducer import Transducer

    table = ContactMap(contact=10, delta_static=0.5e-6,
                       steel_delta=np.array([0.0, 0.5e-6, 1.0e-6, 2.0e-6]),
                       steel_flux=np.array([-0.35, 0.0, 0.33, 0.86]) * 1e-6,
                       air_gap=np.array([1e-9, 1e-6, 4e-6, 9e-6, 18e-6]),
                       air_flux=np.array([0.0, -0.7, -2.3, -3.9, -5.7]) * 1e-6)
    tr = Transducer(particle=13, contacts=np.array([10, 11]),
                    sensitivity_villari=np.array([1e-7, 2e-7]),
                    dlambda_dapproach=np.array([0.7, 3.7]),
                    contact_stiffness=hertz_stiffness(2.38e-3), reference_force=1.85,
                    magnetic_particle_force=np.zeros(30), resistance_ohm=100.0,
                    inductance_H=0.03, turns=1100, source="test",
                    approach_map=ApproachMap((table,)) if mapped else None)
    return tr, table


def _history():
    t = np.arange(2000) * 1e-7
    s = np.sin(np.pi * t / t[-1])
    approach = np.zeros((t.size, 12))
    approach[:, 9] = 0.06e-6 - 11.3e-6 * s**2 + 1.5e-6 * s**8  # opens, then closes hard
    approach[:, 10] = 0.45e-6 + 1.2e-6 * s**3
    # Hertz forces of the approaches (the static reading takes δ(0) from the first force)
    force = hertz_stiffness(2.38e-3) * np.clip(approach, 0.0, None) ** 1.5
    return t, force, approach


def _circuit():
    from msens.readout.electronics import ReadoutCircuit

    return ReadoutCircuit(resistance=100.0, inductance=0.03, winding_capacitance=30e-12,
                          cable_capacitance=100e-12, input_resistance=1e6,
                          input_capacitance=20e-12)


def test_mapped_contact_flux_is_the_map():
    """With a map, the record's flux is (∂Λ/∂δ_c / Λ_c'(δ_s)) (Λ_c(δ_c(t)) − Λ_c(δ_c(0))) for
    the mapped contact and the linear source for the others (to round-off); the EMF is
    −dΛ/dt of the same."""
    from msens.readout.mss import MssSensor, mss_signals

    tr, table = _wired(True)
    t, force, approach = _history()
    rec = mss_signals(MssSensor(tr, _circuit()), t, force, 10e6, approach=approach)
    d10, d11 = approach[:, 9], approach[:, 10]
    villari = (force[:, 9:11] - force[0, 9:11]) @ tr.sensitivity_villari
    scale = 0.7 / table.static_slope  # the map's shape, scaled by the coil's sensitivity
    assert 0.9 < scale < 1.1
    expect = villari + scale * (table(d10) - table(d10[0])) + 3.7 * (d11 - d11[0])
    assert np.max(np.abs(rec.flux - expect)) < 1e-9 * np.max(np.abs(expect))
    assert np.max(np.abs(rec.emf + np.gradient(expect, t))) < 1e-6 * np.max(np.abs(rec.emf))
    # the linear reading of the same history differs by the map's nonlinearity
    lin = mss_signals(MssSensor(_wired(False)[0], _circuit()), t, force, 10e6,
                      approach=approach)
    assert np.max(np.abs(lin.flux - rec.flux)) > 0.2 * np.max(np.abs(rec.flux))


def test_hammerstein_with_eddy_currents():
    """With a frequency response, the map acts first (Hammerstein): the mapped transducer
    equals the linear one fed with the equivalent approaches, and at σ = 0 (a flat
    response) its flux is the static map's."""
    from msens.magnetics.frequency_response import FrequencyResponse
    from msens.readout.mss import MssSensor, mss_signals

    tr, table = _wired(True)
    lin, _ = _wired(False)
    t, force, approach = _history()
    f = np.array([0.0, 1e3, 1e6])
    flat = FrequencyResponse(particle=13, frequencies=f, contacts=tr.contacts,
                             villari=np.tile(tr.sensitivity_villari, (3, 1)).astype(complex),
                             approach=np.tile(tr.dlambda_dapproach, (3, 1)).astype(complex),
                             impedance=np.array([100.0, 100 + 2j * np.pi * 1e3 * 0.03,
                                                 100 + 2j * np.pi * 1e6 * 0.03]),
                             resistance_ohm=100.0, static_inductance_H=0.03)
    rec = mss_signals(MssSensor(tr, _circuit()), t, force, 10e6, response=flat,
                      approach=approach)
    eq = approach.copy()
    eq[:, 9:11] = tr.equivalent_approach(approach[:, 9:11])
    ref = mss_signals(MssSensor(lin, _circuit()), t, force, 10e6, response=flat, approach=eq)
    assert np.array_equal(rec.emf, ref.emf)
    d10 = approach[:, 9]
    villari = (force[:, 9:11] - force[0, 9:11]) @ tr.sensitivity_villari
    expect = (villari + 0.7 / table.static_slope * (table(d10) - table(d10[0]))
              + 3.7 * (approach[:, 10] - approach[0, 10]))
    # trapezoidal integral of the FFT-differentiated EMF: agreement to 1e-3 of the range
    assert np.max(np.abs(rec.flux - expect)) < 1e-3 * np.ptp(expect)


def test_moved_coil_reads_the_maps_equivalent_approaches():
    """A moved coil (:meth:`Transducer.shifted`) keeps the contact maps as a Hammerstein
    model: the equivalent approaches are those of the coil the maps were solved for, so the
    mapped contact's static flux scales with the moved coil's sensitivity; no offset gives
    the transducer back, and shifting twice does not compound."""
    from dataclasses import replace

    tr, table = _wired(True)
    tr = replace(tr, offsets=np.array([-1e-3, 0.0, 1e-3]),
                 villari_by_offset=np.tile(tr.sensitivity_villari, (3, 1)),
                 approach_by_offset=np.array([[0.5, 3.0], [0.7, 3.7], [0.9, 4.4]]))
    _, _, approach = _history()
    delta = approach[:, 9:11]
    np.testing.assert_array_equal(tr.shifted(0.0).equivalent_approach(delta),
                                  tr.equivalent_approach(delta))
    moved = tr.shifted(1e-3)
    np.testing.assert_allclose(moved.dlambda_dapproach, [0.9, 4.4], rtol=1e-12)
    np.testing.assert_allclose(moved.equivalent_approach(delta),
                               tr.equivalent_approach(delta), rtol=1e-14)
    flux = moved.dlambda_dapproach[0] * (moved.equivalent_approach(delta)[:, 0]
                                         - table.delta_static)
    np.testing.assert_allclose(flux, 0.9 / table.static_slope * table(delta[:, 0]),
                               rtol=1e-12, atol=0)
    np.testing.assert_array_equal(moved.shifted(-1e-3).equivalent_approach(delta),
                                  tr.shifted(-1e-3).equivalent_approach(delta))
    # a variant of the coil (another remanence) reads the maps the same way
    variant = replace(_wired(False)[0], dlambda_dapproach=np.array([0.8, 3.9]))
    carried = variant.reading_maps_of(tr)
    np.testing.assert_array_equal(carried.equivalent_approach(delta),
                                  tr.equivalent_approach(delta))
    assert variant.reading_maps_of(_wired(False)[0]) is variant


def _tiny_with_maps(tmp_path):
    from pathlib import Path

    from msens import api

    tiny = (Path(__file__).parents[1] / "data" / "tiny-mss.toml").read_text()
    path = tmp_path / "tiny.toml"
    path.write_text(tiny + "\n[field]\ncontact_map = true\n")
    return api.load(path)


def test_contact_maps_in_diagnose(tmp_path):
    """With ``contact_map = true`` diagnose still moves the coil and scales the magnets (the
    maps carry over to both)."""
    from msens.diagnose.effects import Context, registry

    study = _tiny_with_maps(tmp_path)
    ctx = Context(study, study.setups[0])
    searched = {name for name, e in registry().items() if e.applies(ctx)}
    assert {"coil_position", "magnet_remanence"} <= searched


def test_maps_carried_to_a_model_of_other_contacts():
    """A magnet design on a truncated bead column (``bead_padding``) has other contacts than
    the study's coil: the mapped ones are matched by number, the rest pass through."""
    from dataclasses import replace

    tr, table = _wired(True)
    design = replace(_wired(False)[0], contacts=np.array([9, 10, 11, 12]),
                     sensitivity_villari=np.zeros(4),
                     dlambda_dapproach=np.array([0.1, 0.9, 4.0, 0.2]))
    carried = design.reading_maps_of(tr)
    delta = np.array([[0.3e-6, -5e-6, 0.8e-6, 0.4e-6]])
    eq = carried.equivalent_approach(delta)
    np.testing.assert_array_equal(eq[:, [0, 2, 3]], delta[:, [0, 2, 3]])
    assert float(eq[0, 1]) == pytest.approx(
        table.delta_static + table(-5e-6) / table.static_slope, rel=1e-14)
    with pytest.raises(Exception, match="without the mapped contacts"):
        replace(design, contacts=np.array([11, 12, 13, 14])).reading_maps_of(tr)


@pytest.mark.slow
def test_transducers_with_contact_maps(tmp_path):
    """``transducer_report(contact_maps=True)``: maps of the contacts around the coil, their
    static slopes the linear sources' (2 %: two meshes), the cache read back equal, and the
    tables of two worker processes equal to one process's."""
    from msens.magnetics.transducer_cache import transducer_report

    g = SensorGeometry(beads=BeadChain(first=11, last=15),
                       sensors=(SensorUnit(Coil(particle=13), BiasMagnet(particle=13)),),
                       air=AirBox(0.06, 0.05))
    kw = {"options": COARSE, "store": Store.at(tmp_path)}
    report = transducer_report(g, contact_maps=True, **kw)
    tr = report.transducers[13]
    assert tr.approach_map.contacts == (11, 12, 13, 14)
    for m in tr.approach_map.maps:
        k = int(np.flatnonzero(tr.contacts == m.contact)[0])
        assert float(m.slope(m.delta_static)) == pytest.approx(tr.dlambda_dapproach[k],
                                                               rel=2e-2)
    again = transducer_report(g, contact_maps=True, **kw).transducers[13]
    for a, b in zip(tr.approach_map.maps, again.approach_map.maps, strict=True):
        assert np.array_equal(a.air_flux, b.air_flux)
        assert np.array_equal(a.steel_flux, b.steel_flux)
    # two worker processes give the tables of one process (from the same Newton start: the
    # plain mesh's bias, which the report handed to its maps)
    from msens.field.probes import P2Field
    from msens.magnetics.contact_map import approach_maps

    (tmp_path / "pool").mkdir()
    pool = approach_maps(g, "pool", options=COARSE,
                         store=Store.at(tmp_path / "pool", committed=[tmp_path]), workers=2,
                         start=P2Field.of(report.bias))[13]
    for a, b in zip(tr.approach_map.maps, pool.maps, strict=True):
        assert np.array_equal(a.air_flux, b.air_flux)
        assert np.array_equal(a.steel_flux, b.steel_flux)


def test_contact_map_key(tmp_path):
    """``[field] contact_map``: a boolean, off by default; bad values name the key."""
    from pathlib import Path

    from msens import api

    tiny = (Path(__file__).parents[1] / "data" / "tiny-mss.toml").read_text()
    path = tmp_path / "tiny.toml"
    path.write_text(tiny)
    assert api.load(path).field.contact_map is False
    path.write_text(tiny + "\n[field]\ncontact_map = true\n")
    assert api.load(path).field.contact_map is True
    path.write_text(tiny + "\n[field]\ncontact_map = 1\n")
    with pytest.raises(InputError, match="contact_map"):
        api.load(path)


def test_maps_of_one_coil_come_from_the_committed_maps_of_all():
    """``map_particles``: the maps of one coil only (a magnet design's: its six contacts when
    solved); on the main study they are read from the committed maps of both coils (all
    contacts 10-20), not solved again, so the study's own magnet designed reads the run's."""
    from msens.config.fieldsetup import geometry_from_study
    from msens.config.study import default_study_path, load_study
    from msens.magnetics.contact_map import mapped_contacts
    from msens.magnetics.transducer_cache import transducer_report

    g = geometry_from_study(load_study(default_study_path()))
    assert mapped_contacts(g, (13,)) == (10, 11, 12, 13, 14, 15)
    both = transducer_report(g, contact_maps=True).transducers
    one = transducer_report(g, contact_maps=True, map_particles=(13,)).transducers
    assert one[18].approach_map is None
    assert one[13].approach_map.contacts == both[13].approach_map.contacts == tuple(
        range(10, 21))
    full = {m.contact: m for m in both[13].approach_map.maps}
    for m in one[13].approach_map.maps:
        np.testing.assert_array_equal(m.air_flux, full[m.contact].air_flux)
        np.testing.assert_array_equal(m.steel_flux, full[m.contact].steel_flux)


def test_fast_paths_equal_the_plain_solves(layered):
    """The map solves' shortcuts change nothing beyond round-off: the morphed quadrature
    re-evaluates only stretched elements (against every element), the state Newton keeps its
    Jacobian near convergence (against Newton with a fresh one every step, tol 1e-13), and
    the layer model started from the plain mesh's bias has the cold start's solution."""
    import skfem

    import msens.magnetics.potentials as potentials
    from msens.field.forms import quadrature_data
    from msens.field.mesh import from_arrays
    from msens.field.probes import P2Field
    from msens.magnetics.approach import _morphed_quadrature
    from msens.magnetics.contact_map import state_points

    g, model, coil, _, d = layered
    sol = model.air
    p = state_points(model, "air", static_approach(model.geometry) - 6e-6)
    q = _morphed_quadrature(sol, p)
    axi = sol.problem.mesh
    moved = from_arrays(p, axi.mesh.t, axi.subdomains, axi.boundaries)
    full = quadrature_data(skfem.CellBasis(moved.mesh, sol.basis.elem,
                                           intorder=2 * sol.problem.order))
    assert np.allclose(q.g, full.g, rtol=1e-10, atol=1e-10 * np.abs(full.g).max())
    assert np.allclose(q.w, full.w, rtol=1e-10, atol=0.0)

    chord = potentials.nonlinear_resolve(sol, q, tol=1e-13, max_iter=30)
    old = potentials.CHORD_BELOW
    try:
        potentials.CHORD_BELOW = 0.0  # a fresh Jacobian every step
        newton = potentials.nonlinear_resolve(sol, q, tol=1e-13, max_iter=30)
    finally:
        potentials.CHORD_BELOW = old
    assert np.abs(chord - newton).max() <= 1e-11 * np.abs(newton).max()

    axi_plain, _ = load_mesh(g, COARSE, Store.at(d))
    plain = solve(bias_problem(g, axi_plain), tol=1e-10)
    warm = layer_model(g, CONTACT, COARSE, Store.at(d), start=P2Field.of(plain))
    assert warm.steel.iterations < model.steel.iterations
    for state in ("steel", "air"):
        a, b = warm.solution(state).a, model.solution(state).a
        assert np.abs(a - b).max() <= 1e-8 * np.abs(b).max()
    delta = static_approach(model.geometry) + 1.2e-6
    assert state_flux(warm, "steel", delta, coil) == pytest.approx(
        state_flux(model, "steel", delta, coil), rel=1e-10, abs=0.0)


def test_refresh_solves_the_maps_again(tmp_path, monkeypatch):
    """``approach_maps(refresh=True)`` (``transducer_report(refresh=True)`` with maps) solves
    the tables again instead of reading the cache, and rewrites the cache file."""
    import msens.magnetics.contact_map as cm

    calls = []

    def fake(args):
        calls.append(args[1])
        n = len(args[2])
        table = ContactMap(args[1], 5e-7, np.array([0.0, 1e-6]), np.array([0.0, len(calls)]),
                           np.array([CLOSED_THICKNESS, 1e-6]), np.array([0.0, -1.0]))
        return (table,) * n

    monkeypatch.setattr(cm, "_contact_task", fake)
    g = _small()
    store = Store.at(tmp_path)
    first = cm.approach_maps(g, "k", store=store, workers=1)
    n = len(calls)
    assert n == len(cm.mapped_contacts(g))
    again = cm.approach_maps(g, "k", store=store, workers=1)
    assert len(calls) == n  # read from the cache
    assert np.array_equal(again[13].maps[0].steel_flux, first[13].maps[0].steel_flux)
    fresh = cm.approach_maps(g, "k", store=store, workers=1, refresh=True)
    assert len(calls) == 2 * n
    assert not np.array_equal(fresh[13].maps[0].steel_flux, first[13].maps[0].steel_flux)
    cached = cm.approach_maps(g, "k", store=store, workers=1)
    assert np.array_equal(cached[13].maps[0].steel_flux, fresh[13].maps[0].steel_flux)


def test_approach_maps_run_on_the_callers_map(tmp_path):
    """A workflow's map-like ``workers`` (scipy's convention) runs one task per contact; the
    maps come back per coil in contact order and are stored (the solves are stood in for:
    this checks where the work runs and how it is put together)."""
    from msens.magnetics.contact_map import approach_maps, mapped_contacts

    g = _small()
    seen = []

    def standin_map(fn, iterable):
        tasks = list(iterable)
        seen.extend(task[1] for task in tasks)
        return [tuple(ContactMap(contact=task[1], delta_static=0.5e-6 * (1 + task[1] / 100),
                                 steel_delta=np.array([0.0, 1e-6, 2e-6]),
                                 steel_flux=np.array([1.0, -1.0, -3.0]) * 1e-6 * task[1],
                                 air_gap=np.array([1e-9, 1e-6, 1e-5]),
                                 air_flux=np.array([0.0, 1.2, 10.0]) * 1e-6)
                      for _ in task[2]) for task in tasks]

    store = Store.at(tmp_path)
    maps = approach_maps(g, "0" * 16, store=store, workers=standin_map)
    contacts = list(mapped_contacts(g))
    assert seen == contacts and list(maps) == [13]
    assert [m.contact for m in maps[13].maps] == contacts
    assert [float(m.steel_flux[1]) for m in maps[13].maps] == [-1e-6 * c for c in contacts]
    again = approach_maps(g, "0" * 16, store=store, workers=standin_map)  # read back
    assert seen == contacts and [m.contact for m in again[13].maps] == contacts

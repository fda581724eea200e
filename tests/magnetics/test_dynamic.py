"""Eddy-current (magneto-quasi-static) transducer: msens.magnetics.dynamic.

On the coarse one-sensor model of test_transducer (beads 9..17, coil and magnet on bead 13):
the 0 Hz solve is the static transducer to round-off, the coil's own harmonic field reads
every source as the direct solves do (complex symmetric, no conjugate), the coil's loss
matches Re Z − R_dc, and with σ = 0 the frequency-domain read-out is mss_signals.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from msens.errors import InputError
from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.field.sensor_model import bias_problem, coil_resistance, load_mesh
from msens.field.solve import solve
from msens.magnetics.approach import hertz_stiffness
from msens.magnetics.dynamic import (
    frequency_responses,
    join_reports,
    report_from_json,
    report_to_json,
    sensor_conductivity,
)
from msens.magnetics.dynamic_cache import dynamic_report
from msens.magnetics.mechanisms import adjoint_check, coil_linkage, mechanism_potentials
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import Transducer, bias_solution
from msens.parallel import TaskMap
from msens.readout.electronics import coil_transfer_function, readout_circuit, transfer_function
from msens.readout.mss import MssSensor, mss_signals
from msens.store import Store

#: The coarse model of test_transducer (~4k elements, ~2 s with its sources).
COARSE = MeshOptions(bead_size=0.6e-3, centre_size=0.3e-3, flat_fraction=0.8, wedge_factor=4.0)
FREQS = (0.0, 1e3, 1e4, 3e4, 1e5)


def one_sensor() -> SensorGeometry:
    """Beads 9..17, one MsS centred on particle 13 (as test_transducer)."""
    return SensorGeometry(beads=BeadChain(first=9, last=17),
                          sensors=(SensorUnit(Coil(particle=13), BiasMagnet(particle=13)),),
                          air=AirBox(0.06, 0.05))


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    g = one_sensor()
    sol, _ = bias_solution(g, options=COARSE,
                           store=Store.at(tmp_path_factory.mktemp("meshes")))
    return g, mechanism_potentials(sol, g, stress_force=g.beads.contact_load,
                                   law=law_for_steel(g.steel))


@pytest.fixture(scope="module")
def report(model):
    g, m = model
    return frequency_responses(m, g, FREQS, direct=True)


@pytest.fixture(scope="module")
def static(model):
    """The static transducer of coil 13 from the same sources (as compute_transducers)."""
    g, m = model
    coil = g.sensors[0].coil
    link = coil_linkage(m, coil)
    contacts, vil, app = m.contact_profiles(link)
    inductance, _ = adjoint_check(m, coil, link)
    return Transducer(particle=13, contacts=contacts, sensitivity_villari=vil,
                      dlambda_dapproach=app, contact_stiffness=hertz_stiffness(g.beads.radius),
                      reference_force=g.beads.contact_load,
                      magnetic_particle_force=np.zeros(g.beads.count),
                      resistance_ohm=coil_resistance(coil),
                      inductance_H=inductance, turns=coil.turns, source="test")


def test_zero_frequency_is_the_static_transducer(report, static):
    r = report.responses[13]
    assert r.contacts.tolist() == static.contacts.tolist()
    scale_v = np.max(np.abs(static.sensitivity_villari))
    scale_a = np.max(np.abs(static.dlambda_dapproach))
    assert np.max(np.abs(r.villari[0] - static.sensitivity_villari)) < 1e-12 * scale_v
    assert np.max(np.abs(r.approach[0] - static.dlambda_dapproach)) < 1e-12 * scale_a
    assert r.static_inductance_H == pytest.approx(static.inductance_H, rel=1e-10)
    assert r.impedance[0] == r.resistance_ohm
    assert r.inductance[0] == r.static_inductance_H


def test_reciprocity_and_power_balance(report):
    chk = report.details["coils"]["13"]
    # the coil's own harmonic field against the direct source solves: round-off
    assert max(chk["reciprocity_rel_error"]) < 1e-12
    # Re Z − R_dc = ω²∫σ|A|²dV/|I|² (1 % required; Galerkin identity to round-off)
    assert max(chk["power_balance_rel_error"]) < 1e-2
    assert max(chk["power_balance_rel_error"]) < 1e-9


def test_eddy_currents_screen_and_lag(report):
    r = report.responses[13]
    k = np.searchsorted(r.contacts, [12, 13])
    d = r.approach[:, k] / r.approach[0, k]
    # the approach sensitivity falls and lags more with frequency
    assert np.all(np.diff(np.abs(d), axis=0) < 0)
    assert np.all(np.diff(np.angle(d), axis=0) < 0)
    assert np.all(np.angle(d[1:]) < 0)
    # symmetric model: contacts 12 and 13 mirror about bead 13
    assert np.allclose(d[:, 0], d[:, 1], rtol=0.02)
    # losses grow, the inductance falls
    assert np.all(np.diff(r.impedance.real) > 0)
    assert np.all(np.diff(r.inductance.real) < 0)


def test_interpolation(report):
    r = report.responses[13]
    f = np.asarray(r.frequencies)
    np.testing.assert_allclose(r.villari_at(f), r.villari, rtol=1e-12, atol=0)
    np.testing.assert_allclose(r.approach_at(f), r.approach, rtol=1e-12, atol=0)
    np.testing.assert_allclose(r.impedance_at(f), r.impedance, rtol=1e-12)
    # continuous at the first nonzero frequency, static at 0, held beyond the last
    below, above = r.approach_at([f[1] * (1 - 1e-9), f[1] * (1 + 1e-9)])
    assert np.max(np.abs(below - above)) < 1e-6 * np.max(np.abs(r.approach[1]))
    np.testing.assert_allclose(r.approach_at([1e6])[0], r.approach[-1], rtol=1e-12)
    # smooth between samples: within the hull of the neighbours' magnitudes
    mid = np.abs(r.approach_at([np.sqrt(f[2] * f[3])])[0])
    lo = np.minimum(np.abs(r.approach[2]), np.abs(r.approach[3]))
    hi = np.maximum(np.abs(r.approach[2]), np.abs(r.approach[3]))
    assert np.all((mid >= lo * 0.999) & (mid <= hi * 1.001))


def test_json_round_trip(report):
    back = report_from_json(json.loads(json.dumps(report_to_json(report))))
    a, b = report.responses[13], back.responses[13]
    for name in ("frequencies", "contacts", "villari", "approach", "impedance"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.static_inductance_H == b.static_inductance_H


def test_conductivity_by_region(model):
    g, m = model
    mesh = m.solution.problem.mesh
    s = sensor_conductivity(mesh, g)
    assert np.all(s[mesh.subdomains["bead_13"]] == 6e6)
    assert np.all(s[mesh.subdomains["pole_13_upper"]] == 6e6)
    assert np.all(s[mesh.subdomains["magnet_13"]] == 0.0)    # ceramic 8: an insulator
    assert np.all(s[mesh.subdomains["air"]] == 0.0)
    s2 = sensor_conductivity(mesh, g, magnets={"ceramic8": 1.0})
    assert np.all(s2[mesh.subdomains["magnet_13"]] == 1.0)
    with pytest.raises(InputError, match="increase from 0 Hz"):
        frequency_responses(m, g, (1e3, 1e4))


def test_coil_transfer_function_with_r_plus_jwl():
    c = readout_circuit(90.0, 0.03, 15e-12, cable_resistance=5.0)
    f = np.geomspace(1.0, 1e6, 50)
    z = c.resistance + 2j * np.pi * f * c.inductance
    np.testing.assert_allclose(coil_transfer_function(c, f, z), transfer_function(c, f),
                               rtol=1e-14)


def _history():
    """Smooth force pulses passing contacts 1..20 (N), 0.1 µs steps over 0.4 ms."""
    t = np.arange(4001) * 1e-7
    tc = 20e-6 * np.arange(1, 21)
    force = 2.0 + 40.0 * np.exp(-(((t[:, None] - tc[None, :]) / 8e-6) ** 2))
    return t, force


def test_zero_conductivity_reproduces_mss_signals(model, static):
    g, m = model
    rep = frequency_responses(m, g, FREQS, sigma=np.zeros(m.solution.problem.mesh.n_elements))
    r = rep.responses[13]
    np.testing.assert_allclose(r.villari, np.broadcast_to(r.villari[0], r.villari.shape),
                               rtol=1e-10)
    circuit = readout_circuit(static.resistance_ohm, static.inductance_H, 15e-12)
    t, force = _history()
    ref = mss_signals(MssSensor(static, circuit), t, force, 10e6)
    dyn = mss_signals(MssSensor(static, circuit), t, force, 10e6, response=r)
    scale = np.max(np.abs(ref.voltage))
    assert np.max(np.abs(dyn.emf - ref.emf)) < 1e-9 * np.max(np.abs(ref.emf))
    # FFT (band-limited EMF) against the exact first-order-hold response: 7.4e-4 here,
    # ~(ωΔt)²/12 near the circuit's ~80 kHz resonance
    assert np.max(np.abs(dyn.voltage - ref.voltage)) < 1e-3 * scale
    np.testing.assert_array_equal(dyn.t_daq, ref.t_daq)


def test_eddy_currents_lower_the_signal(model, static, report):
    t, force = _history()
    circuit = readout_circuit(static.resistance_ohm, static.inductance_H, 15e-12)
    r = report.responses[13]
    ref = mss_signals(MssSensor(static, circuit), t, force, 10e6)
    dyn = mss_signals(MssSensor(static, circuit), t, force, 10e6, response=r)
    assert np.max(np.abs(dyn.voltage)) < np.max(np.abs(ref.voltage))
    assert np.all(np.isfinite(dyn.voltage))


def test_skin_refinement_option_keeps_existing_mesh_keys():
    from msens.field.cache import canonical, geometry_key

    g = one_sensor()
    assert "skin_size" not in canonical(MeshOptions())
    assert geometry_key(g, MeshOptions()) == geometry_key(g)
    assert geometry_key(g, MeshOptions(skin_size=20e-6)) != geometry_key(g)
    with pytest.raises(InputError, match="skin_size"):
        MeshOptions(skin_size=-1.0)


def test_screening_split_by_part(model, report):
    """Item 4 of issue 33: the screening with every conductor equals the response's own; with
    the pole pieces non-conducting the approach is screened less and the coil loses less; a
    model whose poles already do not conduct puts none of its screening on them."""
    from msens.magnetics.dynamic import screening_split

    g, m = model
    split = frequency_responses(m, g, FREQS, screening=True).responses[13].screening
    r = report.responses[13]
    k = [int(np.flatnonzero(r.contacts == c)[0]) for c in (12, 13)]
    rows = [FREQS.index(f) for f in split["frequencies_Hz"]]
    ratio = r.approach[rows][:, k] / r.approach[0, k]
    np.testing.assert_allclose(split["all"]["approach_ratio_magnitude"], np.abs(ratio),
                               rtol=1e-9)
    np.testing.assert_allclose(split["all"]["eddy_resistance_ohm"],
                               r.impedance[rows].real - r.resistance_ohm, rtol=1e-9)
    beads, full = (np.asarray(split[k]["approach_ratio_magnitude"]) for k in ("beads", "all"))
    assert np.all(beads > full)
    assert np.all(np.asarray(split["beads"]["eddy_resistance_ohm"])
                  < np.asarray(split["all"]["eddy_resistance_ohm"]))
    share = np.asarray(split["magnet_share_of_screening"])
    assert share.shape == (3, 2) and np.all((share > 0) & (share < 1))
    json.dumps(split)  # JSON-ready
    # round trip through the stored form
    back = report_from_json(json.loads(json.dumps(report_to_json(
        frequency_responses(m, g, FREQS, screening=True)))))
    assert back.responses[13].screening == split

    from msens.field.eddy import HarmonicOperator
    from msens.magnetics.dynamic import equivalent_magnet_elements

    mesh = m.solution.problem.mesh
    sigma = np.where(equivalent_magnet_elements(mesh), 0.0, sensor_conductivity(mesh, g))
    op = HarmonicOperator(m.solution, sigma)
    coil = g.sensors[0].coil
    from msens.field.sensor_model import coil_current_density

    loads = np.array([op.winding_load("coil_13", coil_current_density(coil))])
    none = screening_split(m, g, op, sigma, loads)[13]
    np.testing.assert_allclose(none["magnet_share_of_screening"], 0.0, atol=1e-9)


def _surface_edges(axi, names):
    """Lengths (m) of the mesh edges between the named parts and the rest (not the axis)."""
    m = axi.mesh
    inside = np.zeros(m.t.shape[1], dtype=bool)
    for n in names:
        inside[axi.subdomains[n]] = True
    f2t = m.f2t
    two = f2t[1] >= 0
    on = two & (inside[f2t[0]] != inside[np.where(two, f2t[1], 0)])
    pts = m.p[:, m.facets[:, on]]
    return np.hypot(*(pts[:, 0] - pts[:, 1]))


@pytest.mark.parametrize("rule", ["conducting", "beads"])
def test_skin_grading_reaches_every_conducting_surface(tmp_path, rule):
    """Issue 33: the skin rule grades the pole pieces as it grades the beads (the mesh before
    it left the poles at the part size, 1.2 mm, with a skin depth of ~70 µm at 10 kHz)."""
    g = one_sensor()
    skin = 150e-6  # coarse, so the mesh takes a second; the rule does not depend on it
    opts = MeshOptions(bead_size=0.6e-3, centre_size=0.3e-3, flat_fraction=0.8,
                       wedge_factor=4.0, skin_size=skin, skin_parts=rule)
    axi, _ = load_mesh(g, opts, store=Store.at(tmp_path))
    poles = _surface_edges(axi, ["pole_13_lower", "pole_13_upper"])
    beads = _surface_edges(axi, ["bead_12", "bead_13", "bead_14"])
    assert np.median(beads) <= 1.01 * skin and np.max(beads) <= 1.5 * skin
    if rule == "conducting":
        assert np.median(poles) <= 1.01 * skin and np.max(poles) <= 1.5 * skin
    else:  # the old rule: the poles at the part size
        assert np.median(poles) > 4 * skin


def test_skin_rule_is_in_the_mesh_key():
    from msens.field.build import skin_surface_size
    from msens.field.cache import canonical, geometry_key

    g = one_sensor()
    opts = MeshOptions(skin_size=40e-6)
    assert opts.skin_parts == "conducting" and canonical(opts)["skin_parts"] == "conducting"
    assert geometry_key(g, opts) != geometry_key(g, MeshOptions(skin_size=40e-6,
                                                                skin_parts="beads"))
    assert MeshOptions().skin_parts is None
    # steel: the skin size governs; an NdFeB magnet (δ ~ 1.3 mm at 200 kHz): half its δ
    assert skin_surface_size(opts, sigma=6e6, mu_r=1000.0, pole=True) == 40e-6
    assert skin_surface_size(MeshOptions(skin_size=40e-6, pole_skin_size=10e-6), sigma=6e6,
                             mu_r=1000.0, pole=True) == 10e-6
    assert 0.6e-3 < skin_surface_size(opts, sigma=0.667e6, mu_r=1.05, pole=True) < 0.7e-3
    with pytest.raises(InputError, match="skin_parts"):
        MeshOptions(skin_parts="conducting")
    with pytest.raises(InputError, match="skin_parts"):
        MeshOptions(skin_size=40e-6, skin_parts="poles")


def _same_report(a, b, rtol=1e-10):
    for p, ra in a.responses.items():
        rb = b.responses[p]
        np.testing.assert_array_equal(ra.frequencies, rb.frequencies)
        for name in ("villari", "approach", "impedance"):
            x, y = getattr(ra, name), getattr(rb, name)
            np.testing.assert_allclose(x, y, rtol=0, atol=rtol * np.max(np.abs(x)))


def test_frequency_chunks_join_to_the_whole(model, report):
    """Frequencies solved in chunks (each from 0 Hz, as cluster tasks do) join to the whole."""
    g, m = model
    parts = [frequency_responses(m, g, (0.0, *chunk), direct=True)
             for chunk in ((1e3, 1e4), (3e4, 1e5))]
    joined = join_reports(parts)
    _same_report(report, joined, rtol=1e-12)
    assert joined.details["tasks"] == 2
    assert len(joined.details["coils"]["13"]["power_balance_rel_error"]) == len(FREQS)


def test_offset_profiles_join_and_round_trip(model, report):
    """Coil-offset profiles: at no offset they read the coil as reciprocity does (to the
    table's quadrature, 1e-4); chunks join to the whole; the JSON form reads back equal."""
    from msens.magnetics.dynamic import report_from_json, report_to_json

    g, m = model
    offs = (-1e-3, 0.0, 1e-3)
    whole = frequency_responses(m, g, FREQS, offsets=offs)
    r = whole.responses[13]
    assert r.villari_by_offset.shape == (3, len(FREQS), r.contacts.size)
    for name in ("villari", "approach"):
        at0, exact = getattr(r, f"{name}_by_offset")[1], getattr(report.responses[13], name)
        assert np.max(np.abs(at0 - exact)) <= 1e-4 * np.max(np.abs(exact))
    parts = [frequency_responses(m, g, (0.0, *chunk), offsets=offs)
             for chunk in ((1e3, 1e4), (3e4, 1e5))]
    joined = join_reports(parts).responses[13]
    back = report_from_json(report_to_json(whole)).responses[13]
    for other in (joined, back):
        np.testing.assert_array_equal(other.offsets, r.offsets)
        for name in ("villari_by_offset", "approach_by_offset"):
            x, y = getattr(other, name), getattr(r, name)
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12 * np.max(np.abs(y)))


def test_frequency_solves_through_any_map_like(tmp_path):
    """workers as a plain map-like callable (scipy's convention; no length): one task per
    non-zero frequency, each from 0 Hz, joined into the one-task report."""
    g = one_sensor()
    local = dynamic_report(g, options=COARSE, store=Store.at(tmp_path / "local"),
                           frequencies=FREQS)
    calls = []

    def serial_map(fn, iterable):
        calls.append(1)
        return list(map(fn, iterable))

    mapped = dynamic_report(g, options=COARSE, store=Store.at(tmp_path / "mapped"),
                            frequencies=FREQS, workers=serial_map)
    assert calls == [1] and mapped.details["tasks"] == len(FREQS) - 1
    _same_report(local, mapped)


@pytest.mark.slow
def test_frequency_solves_on_a_dask_cluster(tmp_path):
    """dynamic_report with a map over a Dask cluster (msens.parallel.TaskMap, as the run
    workflow makes it): the tasks run on the cluster and give the local report
    (each task meshes through the shared cache and re-solves bias and sources: round-off)."""
    distributed = pytest.importorskip("distributed")
    g = one_sensor()
    local = dynamic_report(g, options=COARSE, store=Store.at(tmp_path / "local"),
                           frequencies=FREQS)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:
        remote = dynamic_report(g, options=COARSE, store=Store.at(tmp_path / "dask"),
                                frequencies=FREQS,
                                workers=TaskMap(scheduler=cluster.scheduler_address))
        seen = {str(entry[0]) for entry in cluster.scheduler.transition_log}
    assert remote.details["tasks"] == 2 and len(seen) >= 2
    _same_report(local, remote)


def test_harmonic_tables_read_the_coil_as_reciprocity_does(model, report):
    """Coil design with eddy currents: every source solved per frequency and tabulated reads
    the coil's S_c(ω), D_c(ω) as the coil's own harmonic field does (reciprocity), to the
    table's quadrature error; the 0 Hz table is the static one."""
    from msens.magnetics.harmonic_tables import harmonic_tables
    from msens.magnetics.potentials import linkage_table

    g, m = model
    coil = g.sensors[0].coil
    rect = g.coil_rect(g.sensors[0])
    r_rng, z_rng = (rect.r0 - 2e-4, rect.r1 + 2e-4), (rect.z0 - 2e-4, rect.z1 + 2e-4)
    tables = harmonic_tables(m, g, FREQS, r_rng, z_rng, 0.1e-3)
    static = linkage_table(m.solution, m.potentials, r_rng, z_rng, 0.1e-3)
    np.testing.assert_allclose(tables.cumulative[0], static.cumulative, rtol=0,
                               atol=1e-9 * np.max(np.abs(static.cumulative)))
    link = tables.linkage(np.array([coil.turns]), np.array([rect.r0]), np.array([rect.r1]),
                          np.array([rect.z0]), np.array([rect.z1]))[0]
    _, vr, ar = m.contact_profiles(link.real)
    _, vi, ai = m.contact_profiles(link.imag)
    r = report.responses[13]
    for table, exact in ((vr + 1j * vi, r.villari), (ar + 1j * ai, r.approach)):
        scale = np.max(np.abs(exact), axis=1, keepdims=True)
        assert np.max(np.abs(table - exact) / scale) < 1e-4  # measured 1.4e-5


def test_eddy_mesh_newton_starts_from_the_plain_mesh_bias(tmp_path):
    """The eddy-current mesh's bias starts from the plain mesh's solution, interpolated:
    handed over (as a magnet design does) or solved first, the report is the same to the
    last bit; the start saves Newton iterations and lands on the cold start's solution."""
    g = one_sensor()
    meshes = Store.at(tmp_path / "meshes")
    plain, _ = bias_solution(g, store=meshes)
    kw = {"options": COARSE, "frequencies": FREQS[:3]}
    given = dynamic_report(g, store=Store.at(tmp_path / "given", committed=[meshes.directory]),
                           start=plain, **kw)
    own = dynamic_report(g, store=Store.at(tmp_path / "own", committed=[meshes.directory]),
                         **kw)
    for p, r in own.responses.items():
        for name in ("villari", "approach", "impedance"):
            assert np.array_equal(getattr(given.responses[p], name), getattr(r, name))
    cold, _ = bias_solution(g, options=COARSE, store=meshes)
    warm, _ = bias_solution(g, options=COARSE, store=meshes, start=plain)
    assert warm.iterations < cold.iterations
    axi, _ = load_mesh(g, COARSE, meshes)
    tight = solve(bias_problem(g, axi), max_iter=60, tol=1e-13)
    np.testing.assert_allclose(warm.a, tight.a, rtol=0, atol=1e-6 * np.max(np.abs(tight.a)))

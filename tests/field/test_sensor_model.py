"""Sensor field model: physics checks on small models (fast) and the default model."""

from __future__ import annotations

import json
import math

import meshio
import numpy as np
import pytest

from msens.field import sensor_model as sm
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.field.regions import CurrentRegion
from msens.field_outputs import write_field_outputs
from msens.params.units import MU0, RHO_COPPER
from msens.store import Store


def one_sensor(**beads) -> SensorGeometry:
    return SensorGeometry(beads=BeadChain(first=10, last=16, **beads),
                          sensors=(SensorUnit(Coil(13), BiasMagnet(13)),),
                          air=AirBox(0.06, 0.05))


@pytest.fixture(scope="module")
def mesh_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("meshes")


@pytest.fixture(scope="module")
def small(mesh_dir):
    g = one_sensor()
    axi, _ = sm.load_mesh(g, store=Store.at(mesh_dir))
    return g, sm.solve(sm.bias_problem(g, axi))


@pytest.fixture(scope="module")
def symmetric_report(mesh_dir):
    """Both paper sensors, beads 3..28: mirror-symmetric about the contact 15-16."""
    return sm.run_field_model(SensorGeometry(beads=BeadChain(first=3, last=28)),
                              store=Store.at(mesh_dir))


def test_coil_resistance_from_the_wire():
    c = Coil()
    r_mean = c.inner_radius + c.thickness / 2
    expected = RHO_COPPER * c.turns * 2 * math.pi * r_mean / (math.pi * (0.127e-3 / 2) ** 2)
    assert sm.coil_resistance(c) == pytest.approx(expected, rel=1e-12)
    assert 85 < sm.coil_resistance(c) < 100  # ~92 Ohm for 1100 turns of AWG36


def wheeler_multilayer(coil: Coil) -> float:
    """Wheeler (1928) multilayer coil, H: 31.6e-6 N^2 a^2 / (6a + 9b + 10c), SI metres
    (a mean radius, b length, c depth); quoted accuracy about 1 %."""
    a = coil.inner_radius + coil.thickness / 2
    return 31.6e-6 * coil.turns**2 * a**2 / (6 * a + 9 * coil.length + 10 * coil.thickness)


def test_air_core_inductance_matches_wheeler(small):
    g, sol = small
    (res,) = sm.coil_results(sol, g)
    assert res.air_core_inductance_H == pytest.approx(wheeler_multilayer(g.sensors[0].coil),
                                                      rel=0.015)
    # steel beads and pole pieces raise the (incremental) inductance, but not by much: the
    # beads fill only (2.38/7.95)^2 = 9 % of the bore
    assert 1.0 < res.inductance_H / res.air_core_inductance_H < 2.0


def thick_solenoid_bz(z: np.ndarray, coil: Coil) -> np.ndarray:
    """On-axis B_z of a uniform thick solenoid at 1 A (thin-shell formula integrated over r)."""
    n_per_m2 = coil.turns / coil.area
    r = np.linspace(coil.inner_radius, coil.outer_radius, 401)
    h = coil.length / 2
    zz = z[:, None]
    thin = ((zz + h) / np.sqrt(r**2 + (zz + h) ** 2) - (zz - h) / np.sqrt(r**2 + (zz - h) ** 2))
    return MU0 * n_per_m2 / 2 * np.trapezoid(thin, r, axis=1)


def test_point_evaluation_on_axis_matches_the_air_core_solenoid(small):
    g, sol = small
    axi = sol.problem.mesh
    regions = sm.regions_for(g, list(axi.subdomains), magnets=False, steel=False)
    coil = g.sensors[0].coil
    regions["coil_13"] = CurrentRegion(sm.coil_current_density(coil))
    air = sm.solve(sm.MagnetostaticProblem(axi, regions))
    zc = g.beads.center(13)
    z = zc + np.linspace(-0.02, 0.02, 21)
    got = sm.flux_density_at(air, np.zeros_like(z), z)
    ref = thick_solenoid_bz(z - zc, coil)
    assert np.max(np.abs(got[:, 1] - ref)) < 5e-3 * ref.max()
    assert np.max(np.abs(got[:, 0])) < 1e-9  # B_r = 0 on the axis


def test_contact_force_independent_of_shell_width(small):
    _, sol = small
    group = [f"bead_{p}" for p in range(10, 13)]
    f0 = sm.group_force(sol, group, ["contact_12_13"], layers=0)
    f2 = sm.group_force(sol, group, ["contact_12_13"], layers=2)
    assert f0 < 0  # the magnet pulls the beads above the sensor down: contact compressed
    assert f2 == pytest.approx(f0, rel=5e-3)


def test_contact_force_flat_term_is_small_but_counted(small):
    g, sol = small
    group = [f"bead_{p}" for p in range(10, 13)]
    with_flat = sm.group_force(sol, group, ["contact_12_13"])
    without = sm.group_force(sol, group)
    flat = with_flat - without
    # the neck is deeply saturated (B_z ~ 3.1 T, uniform over the flat); the flat term is
    # about B_z^2/(2 mu0) pi a^2 (~7 mN), a fraction of a per cent of the contact force
    a = g.beads.flat_radius
    z = g.beads.contact_z(12)
    b_flat = sm.flux_density_at(sol, np.linspace(0, 0.9 * a, 5), z)[:, 1]
    assert np.all(np.abs(b_flat) > 2.43)  # beyond the last B-H table point
    expected = -np.mean(b_flat**2) / (2 * MU0) * math.pi * a**2
    assert flat == pytest.approx(expected, rel=0.05)
    assert abs(flat) < 0.01 * abs(with_flat)


def test_virtual_work_agrees_with_eggshell_in_a_gapped_model(mesh_dir):
    g = one_sensor(contact_gap=2e-6)
    axi, _ = sm.load_mesh(g, store=Store.at(mesh_dir))
    sol = sm.solve(sm.bias_problem(g, axi))
    group = [f"bead_{p}" for p in range(10, 13)]
    egg = sm.group_force(sol, group, layers=0)
    vw = sm.virtual_work_force(sol, group, delta=1e-8, layers=3)
    assert vw == pytest.approx(egg, rel=5e-3)


def test_two_sensor_model_is_mirror_symmetric_and_plausible(symmetric_report):
    rep = symmetric_report
    bz = {b.particle: b.B_center_T[1] for b in rep.beads}
    f = {(c.upper, c.lower): c.magnetic_force_N for c in rep.contacts}
    # beads 3..28 and sensors 13, 18 are symmetric about the contact 15-16
    for p in range(3, 16):
        assert bz[p] == pytest.approx(bz[31 - p], rel=5e-3, abs=1e-3)
    for u in range(3, 15):
        assert f[(u, u + 1)] == pytest.approx(f[(30 - u, 31 - u)], rel=5e-3, abs=5e-3)
    # sensor beads biased to a few tenths of a tesla; the four sensor contacts compressed by
    # newtons (the paper inferred 1.8 N from wave speeds)
    assert 0.2 < abs(bz[13]) < 1.5
    mean13 = next(b.Bz_mean_T for b in rep.beads if b.particle == 13)
    assert mean13 == pytest.approx(bz[13], rel=0.1)  # the field is fairly uniform mid-bead
    four = [f[(11, 12)], f[(12, 13)], f[(13, 14)], f[(14, 15)]]
    assert all(x > 0 for x in four)
    assert 0.5 < np.mean(four) < 6.0
    assert rep.newton_iterations <= 15
    assert rep.coils[0].inductance_H > rep.coils[0].air_core_inductance_H > 0


def test_outputs_written(symmetric_report, tmp_path):
    written = write_field_outputs(symmetric_report, tmp_path)
    data = json.loads((tmp_path / "field.json").read_text())
    assert [c["particle"] for c in data["coils"]] == [13, 18]
    assert {"particle", "turns", "resistance_ohm", "inductance_H"} <= set(data["coils"][0])
    assert len(data["beads"]) == 26 and len(data["beads"][0]["B_center_T"]) == 2
    assert {"upper", "lower", "magnetic_force_N"} <= set(data["contacts"][0])
    assert len(data["axis"]["z_m"]) == len(data["axis"]["Bz_T"]) > 100
    assert data["dofs"] == symmetric_report.dofs and data["newton_iterations"] >= 1
    assert "EQUIVALENT" in data["note"]
    # the B-H table the solve used is recorded (provenance of every number in the file)
    steel = data["model"]["steel_bh"]
    assert steel["name"] == symmetric_report.geometry.steel.name
    np.testing.assert_array_equal(steel["B_T"], symmetric_report.geometry.steel.b)
    np.testing.assert_array_equal(steel["H_A_per_m"], symmetric_report.geometry.steel.h)
    vtu = meshio.read(tmp_path / "field.vtu")
    assert vtu.point_data["A_phi"].shape == (len(vtu.points),)
    assert (tmp_path / "field_B.png").stat().st_size > 10_000
    assert written["field_3d.png"].startswith("skipped") or (
        (tmp_path / "field_3d.png").stat().st_size > 10_000)
    assert not [q for q in tmp_path.iterdir() if q.name.startswith(".")]

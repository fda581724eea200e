"""The field model on a user B–H curve (``SensorGeometry.steel``): small one-sensor model."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from msens.field import sensor_model as sm
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.field.regions import NonlinearSoft
from msens.params.materials import STEEL_1018_BH, BHCurve
from msens.store import Store

SMALL = SensorGeometry(beads=BeadChain(first=10, last=16),
                       sensors=(SensorUnit(Coil(13), BiasMagnet(13)),), air=AirBox(0.06, 0.05))


def scaled(k: float) -> BHCurve:
    """1018 with H scaled by ``k`` (same B): k < 1 is magnetically softer, k > 1 harder."""
    return BHCurve("user table", STEEL_1018_BH.b.copy(), STEEL_1018_BH.h * k, "test")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Bead fields and contact forces for 1018, a copy of it, and H x 0.5 / x 2 tables."""
    mesh_dir = tmp_path_factory.mktemp("meshes")
    out = {}
    for name, k in [("1018", None), ("copy", 1.0), ("soft", 0.5), ("hard", 2.0)]:
        g = SMALL if k is None else dataclasses.replace(SMALL, steel=scaled(k))
        axi, path = sm.load_mesh(g, store=Store.at(mesh_dir))
        sol = sm.solve(sm.bias_problem(g, axi))
        bz = np.array([b.B_center_T[1] for b in sm.bead_fields(sol, g)])
        force = np.array([c.magnetic_force_N for c in sm.magnetic_contact_forces(sol, g)])
        out[name] = (bz, force, path, sol)
    return out


def test_beads_and_pole_pieces_get_the_geometry_curve(runs):
    sol = runs["soft"][3]
    steel = {n: r for n, r in sol.problem.regions.items() if n.startswith(("bead_", "pole_"))}
    assert {n.split("_")[0] for n in steel} == {"bead", "pole"}
    for region in steel.values():
        assert isinstance(region, NonlinearSoft)
        np.testing.assert_array_equal(region.curve.h, STEEL_1018_BH.h * 0.5)


def test_user_copy_of_1018_gives_the_default_field(runs):
    bz, force, path, _ = runs["1018"]
    bz_copy, force_copy, path_copy, _ = runs["copy"]
    assert path_copy == path  # one mesh for every material
    np.testing.assert_allclose(bz_copy, bz, rtol=1e-12, atol=0)
    np.testing.assert_allclose(force_copy, force, rtol=1e-12, atol=0)


def test_softer_steel_carries_more_bias_flux(runs):
    """Halving H(B) (doubling the secant permeability) must raise |B| in every bead and the
    magnetic compression of every contact; doubling H(B) must lower both. The bead column is
    in series with air (the magnet's and the coil's gaps), so the change stays modest: on this
    model +1.7 % / -2.2 % in the sensor bead's B_z and about +/-10 % in the contact forces."""
    bz, force, *_ = runs["1018"]
    for k, sign in (("soft", 1), ("hard", -1)):
        bz_k, force_k, *_ = runs[k]
        assert np.all(sign * (np.abs(bz_k) - np.abs(bz)) > 0)
        assert np.all(sign * (force_k - force) > 0)
        rel = abs(bz_k[3] / bz[3] - 1)  # bead 13, the sensor's bead
        assert 0.005 < rel < 0.05
    assert abs(runs["soft"][0][3]) > 0.5  # the sensor bead sits well in the bias field

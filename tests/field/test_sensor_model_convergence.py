"""Convergence of the sensor field model (slow): beads, air box, contact flats, mesh.

Compared: B_z at the centres of beads 11..20 and the magnetic compression of contacts
11-12 .. 19-20 (the beads and contacts the two paper sensors see).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from msens.field import sensor_model as sm
from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, SensorGeometry
from msens.store import Store

pytestmark = pytest.mark.slow

CONTACTS = [(p, p + 1) for p in range(11, 20)]


def quantities(geometry, mesh_dir, options=None):
    axi, _ = sm.load_mesh(geometry, options, Store.at(mesh_dir))
    sol = sm.solve(sm.bias_problem(geometry, axi), max_iter=40)
    bz = np.array([b.B_center_T[1] for b in sm.bead_fields(sol, geometry)
                   if 11 <= b.particle <= 20])
    f = np.array([c.magnetic_force_N for c in sm.magnetic_contact_forces(sol, geometry, CONTACTS)])
    return bz, f


def rel_change(a, b):
    return max(float(np.max(np.abs(x - y)) / np.max(np.abs(y))) for x, y in zip(a, b,
                                                                                strict=True))


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("meshes")
    return d, quantities(SensorGeometry(), d)


def test_more_beads_change_sensor_fields_little(reference):
    d, ref = reference
    g = SensorGeometry()
    cut = quantities(replace(g, beads=replace(g.beads, first=4, last=27)), d)
    assert rel_change(cut, ref) < 5e-3  # nine beads beyond each sensor: < 0.5 %


def test_air_box_truncation(reference):
    d, ref = reference
    big = quantities(replace(SensorGeometry(), air=AirBox(0.64, 0.48)), d)
    assert rel_change(big, ref) < 7e-3  # at the remeshing-noise level


def test_flat_radius_convergence(reference):
    d, _ = reference
    g = SensorGeometry()
    res = [quantities(replace(g, beads=replace(g.beads, contact_load=1e-9,
                                               min_flat_radius=a)), d)
           for a in (25e-6, 12.5e-6)]
    # below the remeshing noise of the model (~0.3-0.5 %, see test_mesh_refinement)
    assert rel_change(res[0], res[1]) < 5e-3


def test_mesh_refinement(reference):
    d, ref = reference
    fine = quantities(SensorGeometry(), d, MeshOptions().scaled(0.5))
    assert rel_change(ref, fine) < 7e-3

"""Tests of mesh reading and refinement (msens.field.mesh)."""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.field.mesh import axis_facets, from_arrays, read_gmsh, refined
from msens.field.verification_geometry import Part, build_mesh


@pytest.fixture(scope="module")
def msh_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("mesh") / "coil.msh"
    build_mesh([Part("coil", "rect", (0.01, 0.02, -0.01, 0.01), 2e-3)], 0.1, 0.02, path=path)
    return path


def _areas(m):
    p, t = m.p, m.t
    d1, d2 = p[:, t[1]] - p[:, t[0]], p[:, t[2]] - p[:, t[0]]
    return 0.5 * np.abs(d1[0] * d2[1] - d1[1] * d2[0])


def test_read_gmsh_names_parts_and_boundary(msh_file):
    axi = read_gmsh(msh_file)
    assert set(axi.subdomains) == {"coil", "air"}
    assert set(axi.boundaries) == {"outer"}
    area = _areas(axi.mesh)
    assert np.all(area > 0)
    assert area[axi.subdomains["coil"]].sum() == pytest.approx(0.01 * 0.02, rel=1e-12)
    mid = axi.mesh.p[:, axi.mesh.facets[:, axi.boundaries["outer"]]].mean(axis=1)
    # the outer half circle of radius 0.1 m (chords: midpoints slightly inside)
    assert np.all(np.abs(np.hypot(*mid) - 0.1) < 1e-3)
    on_axis = axis_facets(axi.mesh)
    assert np.all(axi.mesh.p[0, axi.mesh.facets[:, on_axis]] == 0.0)
    assert np.ptp(axi.mesh.p[1, axi.mesh.facets[:, on_axis]]) == pytest.approx(0.2)


def test_refined_keeps_subdomain_areas_and_boundaries(msh_file):
    axi = read_gmsh(msh_file)
    fine = refined(axi, 2)
    assert fine.n_elements == 16 * axi.n_elements
    for name, el in axi.subdomains.items():
        assert _areas(fine.mesh)[fine.subdomains[name]].sum() == pytest.approx(
            _areas(axi.mesh)[el].sum(), rel=1e-12)
    assert fine.boundaries["outer"].size == 4 * axi.boundaries["outer"].size


def test_missing_file_is_input_error(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        read_gmsh(tmp_path / "nope.msh")


def test_unreadable_file_is_input_error(tmp_path):
    bad = tmp_path / "bad.msh"
    bad.write_text("not a mesh")
    with pytest.raises(InputError, match="could not be read"):
        read_gmsh(bad)


def test_subdomains_must_partition_the_triangles():
    p = np.array([[0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]])
    t = np.array([[0, 1], [1, 3], [2, 2]])
    with pytest.raises(InputError, match="exactly once"):
        from_arrays(p, t, {"a": np.array([0]), "b": np.array([0])})


def test_negative_radius_is_rejected():
    p = np.array([[-0.5, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(InputError, match="r < 0"):
        from_arrays(p, np.array([[0], [1], [2]]), {"a": np.array([0])})

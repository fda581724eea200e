"""Sensor geometry: dimensions, validation, study input, meshing and the mesh cache."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from msens.errors import InputError
from msens.field.build import MeshOptions, build_mesh
from msens.field.cache import cached_mesh, geometry_key
from msens.field.geometry import AirBox, BeadChain, SensorGeometry, hertz_flat_radius
from msens.field.mesh import read_gmsh
from msens.field.parts import WIRES, BiasMagnet, Coil, SensorUnit
from msens.params.materials import BEAD_STEEL
from msens.store import Store


def small_geometry(**beads) -> SensorGeometry:
    """One sensor at particle 13 and beads 12..14: meshes in a fraction of a second."""
    return SensorGeometry(beads=BeadChain(first=12, last=14, **beads),
                          sensors=(SensorUnit(Coil(13), BiasMagnet(13)),),
                          air=AirBox(0.05, 0.03))


def test_hertz_flat_radius_matches_the_chain_contact_law():
    # Hertz: a^2 = R* delta and F = (4/3) E* sqrt(R*) delta^(3/2) (design.md §5)
    r, e, nu = 2.38e-3, BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio
    e_star, r_star = e / (2 * (1 - nu**2)), r / 2
    for load in (0.01, 1.8, 20.0):
        a = hertz_flat_radius(load, r, e, nu)
        delta = a**2 / r_star
        assert 4 / 3 * e_star * math.sqrt(r_star) * delta**1.5 == pytest.approx(load,
                                                                                  rel=1e-12)
    with pytest.raises(InputError, match="contact load"):
        hertz_flat_radius(0.0)


def test_default_dimensions_follow_the_paper():
    g = SensorGeometry()
    coil = g.sensors[0].coil
    # 1100 turns of 0.152 mm wire, square packing, 7 mm long: depth N d^2 / L = 3.63 mm
    assert coil.thickness == pytest.approx(1100 * 0.152e-3**2 / 7e-3, rel=1e-12)
    assert coil.inner_radius == pytest.approx(6.35e-3 + 1.6e-3)
    b = g.beads
    assert 20e-6 < b.flat_radius < 30e-6  # ~1.85 N on a steel-steel contact
    assert b.pitch == pytest.approx(2 * math.sqrt(b.radius**2 - b.flat_radius**2))
    assert b.center(30) == pytest.approx(b.half_height)  # bead 30 rests on the wall z = 0
    assert b.center(13) - b.center(18) == pytest.approx(5 * b.pitch)
    assert b.contact_z(12) == pytest.approx(0.5 * (b.center(12) + b.center(13)))
    m = g.sensors[0].magnet
    # pole pieces 19 mm apart (centre to centre): four bead diameters
    assert m.length + m.pole_thickness == pytest.approx(19e-3)
    assert WIRES["AWG36"].bare_diameter == pytest.approx(0.127e-3)


@pytest.mark.parametrize(("make", "match"), [
    (lambda: SensorGeometry(sensors=(SensorUnit(Coil(13), BiasMagnet(13, inner_radius=10e-3)),)),
     "overlap"),
    (lambda: SensorGeometry(sensors=(SensorUnit(Coil(13), BiasMagnet(13,
                                                                     pole_inner_radius=5e-3)),)),
     "inside the tube"),
    (lambda: SensorGeometry(sensors=(SensorUnit(Coil(13, inner_radius=5e-3)),)),
     "inside the tube"),
    (lambda: Coil(13, turns=0), "turns"),
    (lambda: SensorGeometry(beads=BeadChain(first=8, last=23), sensors=(SensorUnit(Coil(25)),)),
     "outside the modelled chain"),
    (lambda: SensorGeometry(sensors=(SensorUnit(Coil(13), BiasMagnet(13)),
                                     SensorUnit(Coil(15), BiasMagnet(15)))), "overlap"),
    (lambda: SensorGeometry(beads=BeadChain(diameter=6e-3)), "do not fit"),
    (lambda: SensorGeometry(air=AirBox(0.02, 0.05)), "air box"),
    (lambda: BeadChain(first=1), "striker"),
    (lambda: BeadChain(min_flat_radius=1e-3), "flat radius"),
    (lambda: SensorUnit(Coil(13), BiasMagnet(14)), "differs"),
    (lambda: BiasMagnet(remanence=5.0), "remanence"),
])
def test_invalid_geometry_raises_input_error(make, match):
    with pytest.raises(InputError, match=match):
        make()


def test_mesh_regions_and_contact_flats(tmp_path):
    g = small_geometry()
    axi = read_gmsh(build_mesh(g, tmp_path / "m.msh"))
    names = set(axi.subdomains)
    assert {"bead_12", "bead_13", "bead_14", "coil_13", "magnet_13", "pole_13_lower",
            "pole_13_upper", "air"} == names
    assert {"axis", "outer", "contact_12_13", "contact_13_14"} <= set(axi.boundaries)
    mesh = axi.mesh
    p, t = mesh.p, mesh.t
    tri_area = 0.5 * np.abs((p[0, t[1]] - p[0, t[0]]) * (p[1, t[2]] - p[1, t[0]])
                            - (p[0, t[2]] - p[0, t[0]]) * (p[1, t[1]] - p[1, t[0]]))
    c = g.sensors[0].coil
    assert tri_area[axi.subdomains["coil_13"]].sum() == pytest.approx(c.area, rel=1e-9)
    # truncated half disc: pi R^2 / 2 (the flats' caps are < 1e-7 of it); straight-sided
    # triangles inscribe the arc, losing ~ theta^2/6 = 0.5 % at 0.4 mm edges on R = 2.38 mm
    r = g.beads.radius
    bead = tri_area[axi.subdomains["bead_13"]].sum()
    assert 0.993 * math.pi * r**2 / 2 < bead < math.pi * r**2 / 2
    # each contact flat is the segment 0 <= r <= a at the contact plane
    f = axi.boundaries["contact_12_13"]
    pts = p[:, mesh.facets[:, f]]
    assert pts[1] == pytest.approx(g.beads.contact_z(12), abs=1e-12)
    assert pts[0].max() == pytest.approx(g.beads.flat_radius, rel=1e-9)
    assert pts[0].min() == pytest.approx(0.0, abs=1e-15)


def test_gap_geometry_isolates_beads(tmp_path):
    g = small_geometry(contact_gap=2e-6)
    axi = read_gmsh(build_mesh(g, tmp_path / "g.msh"))
    assert not any(n.startswith("contact_") for n in axi.boundaries)
    t = axi.mesh.t
    v12 = set(np.unique(t[:, axi.subdomains["bead_12"]]).tolist())
    v13 = set(np.unique(t[:, axi.subdomains["bead_13"]]).tolist())
    assert not v12 & v13


def test_cache_reuses_and_regenerates(tmp_path):
    g = small_geometry()
    assert geometry_key(g) == geometry_key(small_geometry())
    assert geometry_key(g) != geometry_key(g, MeshOptions(bead_size=0.3e-3))
    store = Store.at(tmp_path)
    path = cached_mesh(g, store=store)
    stamp = path.stat().st_mtime_ns
    assert cached_mesh(small_geometry(), store=store) == path
    assert path.stat().st_mtime_ns == stamp  # reused, not rebuilt
    c = g.sensors[0].coil
    g2 = replace(g, sensors=(SensorUnit(replace(c, turns=1000), g.sensors[0].magnet),))
    path2 = cached_mesh(g2, store=store)
    assert path2 != path and path2.is_file() and path2.with_suffix(".json").is_file()
    leftovers = [q for q in tmp_path.iterdir() if q.name.startswith(".")]
    assert leftovers == []

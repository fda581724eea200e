"""A changed coil read from another coil's field model (msens.magnetics.coil_read) against
the field model of the changed geometry itself."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from msens.magnetics.coil_read import coil_window, fits
from msens.magnetics.transducer import compute_transducers
from msens.magnetics.transducer_cache import solved_for, transducer_report
from msens.store import Store

from .test_transducer import COARSE, one_sensor


def with_coil(geometry, **changes):
    u = geometry.sensors[0]
    return replace(geometry, sensors=(replace(u, coil=replace(u.coil, **changes)),))


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    """A store that has computed the reference geometry (its coil tables are kept)."""
    warm = Store.at(tmp_path_factory.mktemp("warm"))
    reference = transducer_report(one_sensor(), options=COARSE, store=warm)
    return warm, reference


def _rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_the_solved_coil_read_from_its_tables_is_its_transducer(stores, tmp_path):
    warm, reference = stores
    g = one_sensor()
    # computing a transducer set records its coils; tables come with the first change
    assert [p.name.split("-")[1] for p in warm.directory.glob("coil-*")] == ["model"]
    # the same geometry is read from the transducer artifact, not the tables
    assert transducer_report(g, options=COARSE, store=warm).read_from is None
    from msens.magnetics.coil_read import read_coil, read_model, read_tables
    from msens.magnetics.steel_law import law_for_steel
    from msens.magnetics.transducer_cache import free_key

    free = free_key(g, COARSE)
    coils, inductance = read_model(warm, free)
    tables = read_tables(warm, free, coils, inductance, [13])
    assert 13 not in tables.tables  # no coil has changed yet: nothing built
    from msens.magnetics.coil_read import build_tables, write_tables
    from msens.magnetics.mechanisms import mechanism_potentials
    from msens.magnetics.transducer import bias_solution

    sol, _ = bias_solution(g, options=COARSE, store=warm)
    model = mechanism_potentials(sol, g, stress_force=g.beads.contact_load,
                                 law=law_for_steel(g.steel))
    write_tables(warm, free, build_tables(sol, model, g, inductance, [13]))
    tables = read_tables(warm, free, coils, inductance, [13])
    tr = reference.transducers[13]
    read = read_coil(tables, tr, g.sensors[0].coil, g)
    # table quadrature (0.1 mm summed-area table) against the exact mesh quadrature
    assert _rel(read.dlambda_dapproach, tr.dlambda_dapproach) < 1e-3
    assert _rel(read.sensitivity_villari, tr.sensitivity_villari) < 1e-3
    assert _rel(read.approach_by_offset, tr.approach_by_offset) < 1e-3
    assert read.inductance_H == pytest.approx(tr.inductance_H, rel=1e-12)
    assert read.resistance_ohm == pytest.approx(tr.resistance_ohm, rel=1e-12)


@pytest.mark.parametrize("change", [{"turns": 800}, {"length": 9e-3},
                                    {"inner_radius": 8.4e-3}, {"axial_offset": 0.8e-3}])
def test_a_changed_coil_is_read_and_matches_its_own_field_model(stores, tmp_path, change,
                                                                 caplog):
    warm, reference = stores
    g = with_coil(one_sensor(), **change)
    def made():  # what the store holds besides the coil tables a first change builds
        return sorted(p.name for p in warm.directory.iterdir() if "coil-table" not in p.name)

    before = made()
    with caplog.at_level("INFO", logger="msens.magnetics.transducer_cache"):
        read = transducer_report(g, options=COARSE, store=warm)
    assert "read from the field model" in caplog.text
    assert read.read_from is not None and "coil_read" in read.details
    # no mesh, solve or transducer artifact of the changed geometry was written
    assert made() == before
    assert solved_for(g, options=COARSE, store=warm) == read.read_from
    own = compute_transducers(g, options=COARSE, store=Store.at(tmp_path)).transducers[13]
    tr = read.transducers[13]
    assert tr.turns == own.turns and tr.resistance_ohm == pytest.approx(own.resistance_ohm)
    # the changed geometry's own (coarse) mesh differs: a few per mille of the sensitivities
    assert _rel(tr.dlambda_dapproach, own.dlambda_dapproach) < 0.01
    assert _rel(tr.sensitivity_villari, own.sensitivity_villari) < 0.02
    # L: the solved coil's incremental L times the ratio of the inductance-grid quadratures
    assert tr.inductance_H == pytest.approx(own.inductance_H, rel=2e-3)
    assert np.array_equal(tr.magnetic_particle_force, reference.transducers[13]
                          .magnetic_particle_force)


def test_a_coil_outside_its_window_gets_its_own_field_model(stores):
    warm, _ = stores
    # with a magnet every valid coil lies between its ring and pole pieces: all fit
    g = one_sensor()
    assert fits(with_coil(g, length=14e-3).sensors[0].coil, g, g)
    # without one the window is twice the coil's outer radius and length
    bare = one_sensor(magnet=False)
    wide = with_coil(bare, turns=6 * bare.sensors[0].coil.turns)
    assert wide.coil_rect(wide.sensors[0]).r1 > coil_window(bare, bare.sensors[0])[0][1]
    assert not fits(wide.sensors[0].coil, wide, bare)
    assert fits(with_coil(bare, turns=900).sensors[0].coil, bare, bare)
    # nothing stored for it: its own field model
    assert solved_for(wide, options=COARSE, store=warm) == wide


def test_window_is_between_tube_magnet_and_poles():
    g = one_sensor()
    u = g.sensors[0]
    (r0, r1), (z0, z1) = coil_window(g, u)
    assert r0 == g.tube.outer_radius and r1 == u.magnet.inner_radius
    zc = g.beads.center(13)
    assert z0 == pytest.approx(zc - u.magnet.length / 2)
    assert z1 == pytest.approx(zc + u.magnet.length / 2)
    bare = replace(u, magnet=None)
    (_, r1), (z0, z1) = coil_window(g, bare)
    assert r1 == pytest.approx(2 * u.coil.outer_radius)
    assert z1 - z0 == pytest.approx(2 * u.coil.length)


def test_inductance_quadratic_equals_the_full_form():
    """The grouped contraction of InductanceGrid.quadratic is vᵀ K v."""
    from msens.magnetics.coil_read import InductanceGrid

    rng = np.random.default_rng(1)
    r, z = np.linspace(6.5e-3, 12e-3, 7), np.linspace(0.07, 0.09, 9)
    a = rng.normal(size=(r.size * z.size,) * 2)
    grid = InductanceGrid(r, z, (a @ a.T).astype(np.float32))
    r0, r1 = np.array([7e-3, 7e-3, 8e-3]), np.array([10e-3, 11.3e-3, 9.1e-3])
    z0, z1 = np.array([0.072, 0.072, 0.075]), np.array([0.081, 0.081, 0.0888])
    hr, hz = r[1] - r[0], z[1] - z[0]
    for k in range(3):
        cr = np.clip(np.minimum(r + hr / 2, r1[k]) - np.maximum(r - hr / 2, r0[k]), 0, None)
        cz = np.clip(np.minimum(z + hz / 2, z1[k]) - np.maximum(z - hz / 2, z0[k]), 0, None)
        v = np.outer(cr * r, cz).ravel()
        want = v @ grid.kernel.astype(float) @ v
        assert grid.quadratic(r0, r1, z0, z1)[k] == pytest.approx(want, rel=1e-12)
    # a winding reaching past the grid's cells would be cut silently: refused
    from msens.errors import InternalError

    with pytest.raises(InternalError, match="outside its inductance grid"):
        grid.quadratic(7e-3, 13e-3, 0.072, 0.081)

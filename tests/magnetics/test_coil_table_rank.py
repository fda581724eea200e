"""Static coil tables stored truncated (msens.magnetics.low_rank, coil_read.write_tables with
rank_tol), and the main study's committed tables: its first coil change builds nothing."""

from __future__ import annotations

import numpy as np
import pytest

from msens import api
from msens.config.fieldsetup import geometry_from_study
from msens.magnetics import coil_read, transducer_cache
from msens.magnetics.coil_read import (
    CoilTables,
    InductanceGrid,
    read_tables,
    table_name,
    write_tables,
)
from msens.magnetics.low_rank import expand_symmetric, rows_svd, symmetric_eig
from msens.magnetics.potentials import LinkageTable
from msens.readout.coil import Coil
from msens.store import Store, committed_dirs


def _low_rank(rng, m, n, rank, dtype=float):
    a = rng.normal(size=(m, rank)) * 0.3 ** np.arange(rank)
    if dtype is complex:
        a = a + 1j * rng.normal(size=(m, rank))
    return a @ rng.normal(size=(rank, n))


@pytest.mark.parametrize("dtype", [float, complex])
def test_rows_svd_keeps_the_rank_and_every_rows_relative_accuracy(dtype):
    rng = np.random.default_rng(0)
    m = _low_rank(rng, 12, 40, 5, dtype)
    m[3] *= 1e-6  # a weak row (a far source) keeps its own relative accuracy
    u, v = rows_svd(m, 1e-9)
    assert u.shape == (12, 5) and v.shape == (5, 40)
    assert v.dtype == (np.complex64 if dtype is complex else np.float32)
    back = u @ v.astype(u.dtype)
    rel = np.linalg.norm(back - m, axis=1) / np.linalg.norm(m, axis=1)
    assert np.max(rel) < 1e-6  # single-precision v
    assert rows_svd(m + 1e-3 * rng.normal(size=m.shape), 1e-2)[0].shape[1] < 12


def test_symmetric_eig_keeps_the_leading_eigenpairs():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(30, 6))
    k = a @ np.diag([5.0, 2.0, 1.0, 0.1, 1e-3, 1e-5]) @ a.T
    q, lam = symmetric_eig(k, 1e-9)
    assert lam.size == 6 and q.dtype == np.float32
    back = expand_symmetric(q, lam, float)
    assert np.max(np.abs(back - k)) < 1e-6 * np.max(np.abs(k))
    assert np.max(np.abs(back - back.T)) < 1e-12 * np.max(np.abs(k))
    assert symmetric_eig(k, 1e-3)[1].size == 4  # |λ| > 1e-3 of the largest eigenvalue


def _tables(rng):
    nr, nz, n_s = 9, 14, 4
    r, z = np.linspace(4e-3, 6e-3, nr), np.linspace(-5e-3, 5e-3, nz)
    f = _low_rank(rng, n_s, nr * nz, 3).reshape(n_s, nr, nz)
    cumulative = np.cumsum(np.cumsum(f, axis=1), axis=2)
    gr, gz = np.linspace(4.1e-3, 5.9e-3, 4), np.linspace(-4.5e-3, 4.5e-3, 5)
    a = rng.normal(size=(20, 20))
    kernel = (a @ a.T).astype(np.float32)
    coil = Coil(particle=13, turns=500, length=6e-3, inner_radius=4.2e-3)
    return CoilTables(tables={13: LinkageTable(r, z, cumulative)},
                      particles=np.arange(2), approach_contacts=np.arange(2), count=10,
                      coils={13: coil}, inductance_H={13: 1e-3},
                      grids={13: InductanceGrid(gr, gz, kernel)})


def test_truncated_tables_read_back_as_the_full_ones(tmp_path):
    tables = _tables(np.random.default_rng(2))
    full, small = Store.at(tmp_path / "full"), Store.at(tmp_path / "small")
    write_tables(full, "k", tables)
    write_tables(small, "k", tables, rank_tol=1e-9)
    a = read_tables(full, "k", tables.coils, tables.inductance_H, [13])
    b = read_tables(small, "k", tables.coils, tables.inductance_H, [13])
    assert np.array_equal(a.tables[13].cumulative, tables.tables[13].cumulative)
    assert np.array_equal(a.grids[13].kernel, tables.grids[13].kernel)
    big = np.max(np.abs(a.tables[13].cumulative))
    np.testing.assert_allclose(b.tables[13].cumulative, a.tables[13].cumulative, rtol=0,
                               atol=1e-6 * big)
    assert b.grids[13].kernel.dtype == np.float32
    np.testing.assert_allclose(b.grids[13].kernel, a.grids[13].kernel, rtol=0,
                               atol=1e-5 * np.max(np.abs(a.grids[13].kernel)))
    assert np.array_equal(b.particles, a.particles) and b.count == a.count
    with np.load(small.find_file(table_name("k", 13))) as f:
        assert "cumulative" not in f and "kernel" not in f


def test_the_main_studys_coil_tables_are_committed():
    study = api.load_default()
    geometry = geometry_from_study(study)
    key = transducer_cache.free_key(geometry)
    committed = Store(committed_dirs()[0], committed_dirs())
    coils = {u.coil.particle: u.coil for u in geometry.sensors}
    tables = read_tables(committed, key, coils, {p: 1.0 for p in coils}, list(coils))
    assert sorted(tables.tables) == [13, 18]
    for p, t in tables.tables.items():
        sources = tables.particles.size + tables.approach_contacts.size  # Villari, approach
        assert t.cumulative.shape[0] == sources
        g = tables.grids[p]
        assert g.kernel.shape == (g.r.size * g.z.size,) * 2
        # the kernel is a sum of positive-definite inverse stiffnesses: a winding's
        # quadratic form is positive
        rect = geometry.coil_rect(next(u for u in geometry.sensors if u.coil.particle == p))
        assert g.quadratic(rect.r0, rect.r1, rect.z0, rect.z1)[0] > 0


def _refuse(*args, **kwargs):
    raise AssertionError("the coil tables were built, not read")


def test_the_first_coil_change_of_the_main_study_reads_the_committed_tables(
        tmp_path, monkeypatch):
    """Issue 33: after the default run (empty user cache), a changed coil is read from the
    committed field model and coil tables: no mesh, solve or table is made."""
    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp_path / "cache"))
    study = api.load_default()
    base = api.run(study)
    monkeypatch.setattr(transducer_cache, "build_tables", _refuse)
    monkeypatch.setattr(coil_read, "build_tables", _refuse)
    changed = api.run(study.replace({"sensor[1].coil.turns": 1000,
                                     "sensor[2].coil.length_m": 8e-3}))
    assert not list((tmp_path / "cache").glob("coil-table-*"))
    assert not list((tmp_path / "cache").glob("sensor-*"))
    v = [np.max(np.abs(s.mss.voltage)) for s in changed.setups[0].sensors]
    v0 = [np.max(np.abs(s.mss.voltage)) for s in base.setups[0].sensors]
    assert v[0] != v0[0] and v[1] != v0[1]

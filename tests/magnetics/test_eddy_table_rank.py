"""Eddy-current coil tables stored as truncated SVDs (msens.magnetics.eddy_coil_read.low_rank),
and the main study's committed tables: a changed coil on the main study with eddy currents is
read without building them."""

from __future__ import annotations

import numpy as np
import pytest

from msens import api
from msens.config.fieldsetup import eddy_settings, geometry_from_study
from msens.magnetics import eddy_coil_read
from msens.magnetics.dynamic import DEFAULT_FREQUENCIES
from msens.magnetics.eddy_coil_read import (
    EddyCoilTable,
    low_rank,
    read_table,
    tables_key,
    write_table,
)
from msens.magnetics.harmonic_tables import HarmonicTables
from msens.store import Store, committed_dirs


def _table(rng, rank=6, noise=0.0):
    # smooth, alike "potentials" of rank `rank` (plus noise), cumulative along both axes
    n_f, n_s, nr, nz = 3, 5, 7, 11
    left = rng.normal(size=(n_f * n_s, rank)) + 1j * rng.normal(size=(n_f * n_s, rank))
    right = rng.normal(size=(rank, nr * nz)) * 0.5 ** np.arange(rank)[:, None]
    m = left @ right + noise * rng.normal(size=(n_f * n_s, nr * nz))
    cum = np.cumsum(np.cumsum(m.reshape(n_f, n_s, nr, nz), axis=2), axis=3)
    h = HarmonicTables(np.array([0.0, 1e3, 1e4]), np.linspace(0, 1e-3, nr),
                       np.linspace(0, 2e-3, nz), cum)
    return EddyCoilTable(h, np.arange(n_s), np.arange(n_s), n_s)


def test_low_rank_keeps_the_singular_values_above_the_tolerance():
    cum = _table(np.random.default_rng(0)).harmonic.cumulative
    arrays = low_rank(cum, 1e-9)
    assert arrays["u"].shape[1] == 6 and tuple(arrays["shape"]) == cum.shape
    back = (arrays["u"] @ arrays["v"].astype(complex)).reshape(cum.shape)
    # v is stored in single precision: about 1e-7 of the largest entry
    assert np.max(np.abs(back - cum)) < 1e-6 * np.max(np.abs(cum))
    noisy = _table(np.random.default_rng(1), noise=1e-3).harmonic.cumulative
    assert low_rank(noisy, 1e-9)["u"].shape[1] > low_rank(noisy, 1e-2)["u"].shape[1] >= 1


def test_a_compressed_table_reads_back_as_the_full_one(tmp_path):
    table = _table(np.random.default_rng(2))
    full, small = Store.at(tmp_path / "full"), Store.at(tmp_path / "small")
    write_table(full, "k", 13, table)
    write_table(small, "k", 13, table, rank_tol=1e-9)
    a, b = read_table(full, "k", 13), read_table(small, "k", 13)
    assert np.array_equal(a.harmonic.cumulative, table.harmonic.cumulative)
    np.testing.assert_allclose(b.harmonic.cumulative, a.harmonic.cumulative, rtol=0,
                               atol=1e-6 * np.max(np.abs(a.harmonic.cumulative)))
    assert np.array_equal(b.particles, a.particles) and b.count == a.count
    with np.load(small.find_file(eddy_coil_read.table_name("k", 13))) as f:
        assert "cumulative" not in f


@pytest.fixture(scope="module")
def eddy_study():
    return api.load_default().replace({"field.eddy_currents": True})


def test_the_main_studys_tables_are_committed(eddy_study):
    geometry = geometry_from_study(eddy_study)
    eddy = eddy_settings(eddy_study)
    key = tables_key(geometry, {u.coil.particle: u.coil for u in geometry.sensors},
                     eddy.options, DEFAULT_FREQUENCIES, eddy.steel, None)
    committed = Store(committed_dirs()[0], committed_dirs())
    for p in (13, 18):
        assert (committed_dirs()[0] / eddy_coil_read.table_name(key, p)).is_file()
        table = read_table(committed, key, p)
        sources = table.particles.size + table.approach_contacts.size  # Villari, approach
        assert table.harmonic.cumulative.shape[:2] == (len(DEFAULT_FREQUENCIES), sources)


def test_a_changed_coil_on_the_main_study_with_eddy_currents_builds_no_table(
        eddy_study, tmp_path, monkeypatch):
    """Issue 33: a coil change after the default run is a read: the committed tables serve
    it (nothing solved on the eddy-current mesh or the static one; no table built)."""
    from msens.magnetics import coil_read, transducer_cache

    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp_path / "cache"))
    api.run(eddy_study)
    for module in (eddy_coil_read, coil_read, transducer_cache):
        monkeypatch.setattr(module, "build_tables", _refuse)
    changed = api.run(eddy_study.replace({"sensor[1].coil.turns": 1000}))
    base = api.run(eddy_study)
    v_changed = np.max(np.abs(changed.setups[0].sensors[0].mss.voltage))
    v_base = np.max(np.abs(base.setups[0].sensors[0].mss.voltage))
    assert 0.8 < v_changed / v_base < 0.95  # fewer turns: less EMF, a shifted resonance
    assert not list((tmp_path / "cache").glob("*coil-table-*"))


def _refuse(*args, **kwargs):
    raise AssertionError("the eddy-current coil tables were built, not read")

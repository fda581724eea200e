"""numba's on-disk cache is safe for processes that compile at once
(:mod:`msens.numba_cache_file`): each compiled variant has its own data file named by its key,
so a race between processes can cost a compilation, never file one variant's code under
another's signature."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from numba.core import caching

from msens import numba_cache_file
from msens.numba_cache_file import NUMBA_CACHE_FILE, KeyedCacheFile

SRC = Path(numba_cache_file.__file__).resolve().parents[1]  # the folder holding msens/


def _files(folder: Path, cls=KeyedCacheFile, stamp=(1.0, 10)):
    return cls(cache_path=str(folder), filename_base="f-1.py311", source_stamp=stamp)


def test_numba_makes_keyed_cache_files_once_msens_is_imported():
    assert caching.IndexDataCacheFile is KeyedCacheFile


def test_two_processes_saving_from_one_stale_index_never_mix_variants(tmp_path):
    """The race numba's own class loses: two processes read the index before either has
    written, then each saves its variant. numba's class numbers both 1 (one data file, two
    signatures); here each variant has its own file, the later index may drop the earlier
    entry (compiled once more later), and nothing loads the other variant's data."""
    first, second = _files(tmp_path), _files(tmp_path)
    stale = {}
    first._load_index = second._load_index = lambda: dict(stale)
    first.save(("int64",), "code for int64")
    second.save(("float64",), "code for float64")
    assert first.data_name(("int64",)) != second.data_name(("float64",))
    fresh = _files(tmp_path)
    assert fresh.load(("float64",)) == "code for float64"
    assert fresh.load(("int64",)) in (None, "code for int64")
    # numba's class, same interleaving: both variants are numbered 1
    (tmp_path / "numba").mkdir()
    numbas = [_files(tmp_path / "numba", NUMBA_CACHE_FILE) for _ in range(2)]
    for files in numbas:
        files._load_index = lambda: dict(stale)
    numbas[0].save(("int64",), "code for int64")
    numbas[1].save(("float64",), "code for float64")
    assert sorted(p.name for p in (tmp_path / "numba").glob("*.nbc")) == ["f-1.py311.1.nbc"]


def test_the_data_name_depends_on_the_stamp_and_the_key_only(tmp_path):
    a, b = _files(tmp_path), _files(tmp_path / "elsewhere")
    assert a.data_name(("int64",)) == b.data_name(("int64",))
    assert a.data_name(("int64",)) != a.data_name(("float64",))
    assert a.data_name(("int64",)) != _files(tmp_path, stamp=(2.0, 10)).data_name(("int64",))
    name = a.data_name(("int64",))
    assert name.startswith("f-1.py311.") and name.endswith(".nbc") and len(name) == 30


def test_an_entry_numba_numbered_is_compiled_afresh(tmp_path):
    """An index written by numba's own class (perhaps mis-filed by the race) is not trusted."""
    _files(tmp_path, NUMBA_CACHE_FILE).save(("int64",), "code")
    assert _files(tmp_path, NUMBA_CACHE_FILE).load(("int64",)) == "code"
    assert _files(tmp_path).load(("int64",)) is None
    _files(tmp_path).save(("int64",), "code")
    assert _files(tmp_path).load(("int64",)) == "code"


# A cached msens function (the read-out circuit's state recursion) in two variants: its
# matrix in C and in Fortran order. Code compiled for one order and run on the other reads
# the matrix transposed, so the results tell the variants apart.
_PROBE = """
import json, sys
import numpy as np
from msens.readout import electronics as e
phi = np.array([[0.5, 0.2], [-0.1, 0.3]])
drive = np.arange(12.0).reshape(6, 2)
ref = [np.ones(2)]
for d in drive:
    ref.append(phi @ ref[-1] + d)
out = {}
for order in sys.argv[1:]:
    x = e._linear_recursion(np.asarray(phi, order=order), np.ones(2), drive)
    out[order] = bool(np.allclose(x, ref, rtol=1e-14, atol=0))
out["hits"] = sum(e._linear_recursion.stats.cache_hits.values())
print(json.dumps(out))
"""


def _probe(cache: Path, *orders: str) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(SRC), NUMBA_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_LOCATOR_CLASSES", None)
    return subprocess.Popen([sys.executable, "-c", _PROBE, *orders], env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _result(process: subprocess.Popen) -> dict:
    out, err = process.communicate(timeout=300)
    assert process.returncode == 0, err[-2000:]
    return json.loads(out.splitlines()[-1])


def test_variants_compiled_at_once_by_two_processes_load_right(tmp_path):
    """Two processes compile one variant each into an empty cache folder at the same time;
    a third loads both from the cache and each computes its own result. (Whether the two
    saves overlap is up to the scheduler; the stale-index test above forces the overlap.)"""
    cache = tmp_path / "numba-cache"
    first, second = _probe(cache, "C"), _probe(cache, "F")
    assert _result(first) == {"C": True, "hits": 0}
    assert _result(second) == {"F": True, "hits": 0}
    data = sorted(p.name for p in cache.rglob("electronics._linear_recursion-*.nbc"))
    assert len(data) == 2 and all(len(name.split(".")[-2]) == 16 for name in data), data
    assert _result(_probe(cache, "C", "F")) in ({"C": True, "F": True, "hits": 2},
                                                {"C": True, "F": True, "hits": 1})

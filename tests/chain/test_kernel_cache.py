"""numba's on-disk cache of the chain kernel notices an edit to any file the kernel is compiled
from (:mod:`msens.chain.kernel.cache_guard`)."""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np

from msens.chain import kernel
from msens.chain.kernel import cache_guard

SRC = Path(kernel.__file__).resolve().parents[3]  # the folder holding msens/

# Calls events.update_near (events.py), whose compiled code contains the contact force
# law of forces.py; prints the result and whether it came from the cache.
_PROBE = """
import json, sys
import numpy as np
from msens.chain import kernel
from msens.chain.kernel import events
assert kernel.__file__.startswith(sys.argv[1]), kernel.__file__
n = 3
p = kernel.padded_length(n)
u, v, a, jk = (np.zeros(p + 1) for _ in range(4))
u[:n] = [3e-6, 2e-6, 1e-6]
cA, cg, load, inv_m, drag = (np.zeros(p) for _ in range(5))
cA[:n] = 1e10
inv_m[:n] = 1.0
events.update_near(0, u, v, a, jk, False, cA, cg, kernel.LAW_LINEAR, load, inv_m, drag)
stats = events.update_near.stats
print(json.dumps({"a": a[:2].tolist(), "hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values())}))
"""


def _probe(src: Path, cache: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_LOCATOR_CLASSES", None)
    done = subprocess.run([sys.executable, "-c", _PROBE, str(src)], env=env, text=True,
                          capture_output=True, timeout=300, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def test_an_edit_in_a_callee_file_recompiles_the_caller(tmp_path):
    """A copy of the package in a temporary folder: the first run compiles and caches, the
    second loads from the cache, and after an edit to the force law in forces.py (not the
    file of the cached function) the third compiles afresh and computes with the new law.
    (numba's own stamp covers only the function's file: it would load the stale code.)"""
    src = tmp_path / "src"
    shutil.copytree(SRC / "msens", src / "msens",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nb[ic]"))
    cache = tmp_path / "numba-cache"
    first = _probe(src, cache)
    second = _probe(src, cache)
    assert (first["misses"], first["hits"]) == (1, 0)
    assert (second["misses"], second["hits"]) == (0, 1)
    assert second["a"] == first["a"] and first["a"][0] < 0.0
    forces = src / "msens" / "chain" / "kernel" / "forces.py"
    text = forces.read_text()
    law = "    return cA * dp * w + cg * r * (w if hkk else 1.0)\n"
    assert text.count(law) == 1
    forces.write_text(text.replace(law, law.replace("return ", "return 2.0 * ")))
    third = _probe(src, cache)
    assert (third["misses"], third["hits"]) == (1, 0)
    np.testing.assert_array_equal(third["a"], 2.0 * np.array(first["a"]))


def test_package_digest_follows_every_file_of_the_folder(tmp_path):
    folder = tmp_path / "kernel"
    shutil.copytree(cache_guard.PACKAGE_DIR, folder,
                    ignore=shutil.ignore_patterns("__pycache__"))
    digests = [cache_guard.package_digest(folder)]
    hermite = folder / "hermite.py"
    hermite.write_text(hermite.read_text() + "\n")
    digests.append(cache_guard.package_digest(folder))
    (folder / "extra.py").write_text("X = 1\n")
    digests.append(cache_guard.package_digest(folder))
    (folder / "extra.py").rename(folder / "extra2.py")
    digests.append(cache_guard.package_digest(folder))
    assert len(set(digests)) == 4


def _reachable_dispatchers(*roots):
    """The numba functions that ``roots`` call, directly or not (globals named in their code,
    nested code objects included)."""
    seen = {}
    todo = list(roots)
    while todo:
        disp = todo.pop()
        if disp.py_func in seen:
            continue
        seen[disp.py_func] = disp
        codes = [disp.py_func.__code__]
        while codes:
            code = codes.pop()
            codes.extend(c for c in code.co_consts if hasattr(c, "co_names"))
            for name in code.co_names:
                obj = disp.py_func.__globals__.get(name)
                if isinstance(obj, numba.core.registry.CPUDispatcher):
                    todo.append(obj)
    return list(seen.values())


def test_the_kernel_compiles_only_from_files_of_its_package():
    """What the guard's stamp covers is all the kernel is compiled from: every function the
    integrators call is defined in the package, and its modules import nothing but numpy,
    numba, the standard library's helpers of the guard and each other."""
    found = _reachable_dispatchers(kernel.integrate, kernel.integrate_batch)
    assert len(found) > 20
    for disp in found:
        assert Path(disp.py_func.__code__.co_filename).resolve().parent == \
            cache_guard.PACKAGE_DIR, disp.py_func.__qualname__
    allowed = ("numpy", "numba", "msens.chain.kernel", "__future__", "functools", "hashlib",
               "warnings", "pathlib")
    for path in cache_guard.PACKAGE_DIR.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module] if isinstance(node, ast.ImportFrom) else [])
            for name in names:
                # msens.numba_cache_file only says where numba's cache lives and how its
                # files are named (nothing compiled)
                assert name.split(".")[0] in allowed or name.startswith(allowed[2]) \
                    or name == "msens.numba_cache_file", (path.name, name)

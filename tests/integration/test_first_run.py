"""The first ``msens run`` after installing (an empty numba cache) compiles the chain kernel in
a second process, loads it from the cache, and writes the same summary.json, byte for byte, as
the run after it; the second process is gone when the run ends."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow


def _msens(args: list[str], cache: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(cache), MPLBACKEND="Agg")
    # no wall-clock limit a busy machine could exceed: the compile alone takes minutes there
    return subprocess.run([sys.executable, "-m", "msens", *args], env=env, text=True,
                          capture_output=True, check=True)


def _children_left(cache: Path) -> list[int]:
    """Processes still running with this test's cache folder in their environment."""
    found = []
    for proc in Path("/proc").iterdir():
        if proc.name.isdigit():
            try:
                environ = (proc / "environ").read_bytes()
            except OSError:
                continue
            if f"XDG_CACHE_HOME={cache}".encode() in environ.split(b"\0"):
                found.append(int(proc.name))
    return found


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_first_run_equals_the_second(tmp_path):
    cache = tmp_path / "cache"
    first = _msens(["run", "--out", str(tmp_path / "a"), "--no-figures"], cache)
    assert "compiling the chain kernel in a second process" in first.stderr
    assert "failed" not in first.stderr
    assert _children_left(cache) == []
    assert any((cache / "msens" / "numba").rglob("stepper.integrate-*.nbi"))
    second = _msens(["run", "--out", str(tmp_path / "b"), "--no-figures"], cache)
    assert "second process" not in second.stderr and "compiling" not in second.stderr
    assert ((tmp_path / "a" / "summary.json").read_bytes()
            == (tmp_path / "b" / "summary.json").read_bytes())

"""No silence (issue 37, item 3): a first line before the heavy imports, heartbeats on long
stages, one honest compile estimate, and the compiled kernel kept in the user cache."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import time

import pytest

from msens import numba_cache, progress


def test_heartbeat_logs_while_the_block_runs(caplog):
    log = logging.getLogger("msens.test")
    with caplog.at_level(logging.INFO, logger="msens"):
        with progress.heartbeat(log, "stage x", every=0.05, note=" (why)"):
            time.sleep(0.33)
    beats = [r.getMessage() for r in caplog.records if "stage x" in r.getMessage()]
    assert len(beats) >= 3
    assert all(b.startswith("stage x: still working, ") and b.endswith(" s (why)")
               for b in beats)
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="msens"):
        time.sleep(0.15)  # the thread has stopped
    assert not caplog.records


def test_nested_heartbeats_only_the_inner_one_speaks(caplog):
    log = logging.getLogger("msens.test")
    with caplog.at_level(logging.INFO, logger="msens"):
        with progress.heartbeat(log, "outer", every=0.1):
            with progress.heartbeat(log, "inner", every=0.1):
                time.sleep(0.55)
            time.sleep(0.35)
    said = [r.getMessage().split(":")[0] for r in caplog.records]
    assert said.count("inner") >= 3 and said.count("outer") >= 1
    first_outer = said.index("outer")
    assert "inner" not in said[first_outer:]  # quiet while the inner one runs


def test_heartbeat_is_silent_when_quiet(caplog):
    log = logging.getLogger("msens.test")
    with caplog.at_level(logging.WARNING, logger="msens"):
        with progress.heartbeat(log, "stage y", every=0.02):
            time.sleep(0.1)
    assert not caplog.records


def test_heartbeat_stops_on_an_exception(caplog):
    log = logging.getLogger("msens.test")
    with caplog.at_level(logging.INFO, logger="msens"):
        with pytest.raises(ValueError), progress.heartbeat(log, "stage z", every=0.02):
            raise ValueError("boom")
    assert not any(t.name == "msens-heartbeat" and t.is_alive()
                   for t in __import__("threading").enumerate())


def test_one_compile_estimate():
    """The estimate is one constant; the messages and help quote it."""
    from pathlib import Path

    import msens

    assert progress.COMPILE_ESTIMATE_TEXT == "about 30 s"
    root = Path(msens.__file__).resolve().parent
    text = (root / "pipeline.py").read_text()
    assert "COMPILE_ESTIMATE_TEXT" in text and "about a minute" not in text
    examples = root.parents[1] / "examples" / "run_default.py"
    if examples.exists():
        assert "KERNEL_COMPILE_S" in examples.read_text()  # quoted, not a number of its own
    from msens.cli import _parser

    run = _parser()._subparsers._group_actions[0].choices["run"]
    assert progress.COMPILE_ESTIMATE_TEXT in " ".join(run.description.split())


def test_duration_text():
    assert progress.duration_text(40) == "about 40 s"
    assert progress.duration_text(95) == "about 1.6 min"
    assert progress.duration_text(120) == "about 2 min"


def test_numba_cache_goes_to_the_user_cache(monkeypatch, tmp_path):
    monkeypatch.delenv(numba_cache.CACHE_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(sys, "platform", "linux")
    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    path = numba_cache.use_user_cache()
    assert path == tmp_path / "msens" / "numba" and path.is_dir()
    assert os.environ[numba_cache.CACHE_ENV] == str(path)
    assert numba.config.CACHE_DIR == str(path)


def test_numba_cache_keeps_the_users_setting(monkeypatch, tmp_path):
    monkeypatch.setenv(numba_cache.CACHE_ENV, str(tmp_path / "mine"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert numba_cache.use_user_cache() == tmp_path / "mine"
    assert os.environ[numba_cache.CACHE_ENV] == str(tmp_path / "mine")
    assert not (tmp_path / "xdg").exists()


def test_kernel_cache_folder_in_a_fresh_process(tmp_path):
    """Importing the chain kernel without NUMBA_CACHE_DIR points numba at the user cache."""
    env = {k: v for k, v in os.environ.items() if k != numba_cache.CACHE_ENV}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    code = ("import numba, msens.chain.kernel.cache_guard as g, os; "
            "print(numba.config.CACHE_DIR); print(os.environ['NUMBA_CACHE_DIR'])")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == [str(tmp_path / "msens" / "numba")] * 2


def test_first_line_comes_before_the_numerical_libraries(tmp_path):
    """The command says what it does before numpy/numba load: its first stderr line is
    printed while neither is imported."""
    code = (
        "import sys, logging\n"
        "from msens import cli\n"
        "seen = []\n"
        "class H(logging.Handler):\n"
        "    def emit(self, record):\n"
        "        seen.append((record.getMessage(), 'numba' in sys.modules,\n"
        "                     'numpy' in sys.modules))\n"
        "logging.getLogger('msens').addHandler(H())\n"
        f"cli.main(['run', {str(tmp_path / 'missing.toml')!r}])\n"
        "print(seen[0])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out.startswith("('run: loading study ") and out.endswith("False, False)"), out


def test_verify_reports_each_check_as_it_goes(monkeypatch):
    from msens.field import verify

    order = []

    def check(name):
        def run():
            order.append(f"ran {name}")
            return [verify._row(name, 1.0, 1.0, "-", 0.1)]
        run.__name__ = f"check_{name}"
        return run

    monkeypatch.setattr(verify, "CHECKS", (check("a"), check("b")))
    rows = verify.run_all(progress=lambda row: order.append(f"reported {row.name}"))
    assert order == ["ran a", "reported a", "ran b", "reported b"]
    assert [r.name for r in rows] == ["a", "b"]


def test_a_bar_is_redrawn_while_its_tasks_run():
    """uq's bar stood still for 10 s while a chunk of runs was out on a busy machine."""
    from msens.progress import refreshing

    class Bar:
        calls = 0

        def refresh(self):
            Bar.calls += 1

    with refreshing(Bar(), every=0.05):
        time.sleep(0.4)
    seen = Bar.calls
    assert seen >= 3
    time.sleep(0.2)
    assert Bar.calls == seen  # the thread ended with the block
    with refreshing(None):  # -q: no bar
        pass

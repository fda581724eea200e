"""Compiling in a second process (:func:`msens.numba_cache.compile_in_background`): it says
when each stage is done, reports a failure with its cause, ends when asked and ends by itself
when the process that started it ends, however that ends."""

from __future__ import annotations

import logging
import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from msens import numba_cache, pipeline
from msens.chain import warmup

_MODULES = {
    "bg_ok": """
        def main(argv):
            for name in argv:
                print("compiled " + name, flush=True)
            return 0
    """,
    "bg_fail": """
        def main(argv):
            raise RuntimeError("no compiler today")
    """,
    "bg_where": """
        import msens

        def main(argv):
            print(msens.__file__, flush=True)
            return 0
    """,
    "bg_sleep": """
        import time

        def main(argv):
            print("started", flush=True)
            time.sleep(120)
            return 0
    """,
}


@pytest.fixture
def modules(tmp_path, monkeypatch):
    """The helper modules above, importable by the second process."""
    for name, text in _MODULES.items():
        (tmp_path / f"{name}.py").write_text(textwrap.dedent(text))
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    return tmp_path


def _gone(pid: int) -> bool:
    """Whether process ``pid`` has ended (a zombie not yet reaped counts as ended)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return True
    return "\nState:\tZ" in status or "\nState:\tX" in status


def test_stages_are_reported_in_order(modules):
    job = numba_cache.compile_in_background("bg_ok", "simulate", "batch")
    assert job is not None
    assert job.wait_for("compiled simulate") is None
    assert job.wait_for("compiled simulate") is None  # asked again: already said
    assert job.wait_for("compiled batch") is None
    assert job.wait() is None
    assert job.said == ["compiled simulate", "compiled batch"]
    assert job.process.returncode == 0 and not job.running()


def test_a_failure_names_its_cause(modules):
    job = numba_cache.compile_in_background("bg_fail")
    problem = job.wait_for("compiled simulate")
    assert problem is not None
    assert problem.startswith("exit status 1") and "no compiler today" in problem


def test_a_stage_never_reported_is_a_failure(modules):
    job = numba_cache.compile_in_background("bg_ok", "simulate")
    assert "without saying 'compiled batch'" in job.wait_for("compiled batch")


def test_stop_ends_the_process(modules):
    job = numba_cache.compile_in_background("bg_sleep")
    assert job.wait_for("started") is None
    start = time.monotonic()
    job.stop()
    assert job.process.returncode is not None and time.monotonic() - start < 10


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_the_second_process_ends_with_the_first(modules):
    """The parent ends abruptly (no clean-up: as after kill -9): its compiling child follows
    within seconds instead of running on (it would have slept 120 s)."""
    parent = textwrap.dedent("""
        import os
        from msens import numba_cache
        job = numba_cache.compile_in_background("bg_sleep")
        assert job.wait_for("started") is None
        print(job.process.pid, flush=True)
        os._exit(0)
    """)
    done = subprocess.run([sys.executable, "-c", parent], capture_output=True, text=True,
                          timeout=120, check=True, env=dict(os.environ))
    pid = int(done.stdout.split()[-1])
    deadline = time.monotonic() + 60  # generous: a busy machine schedules late
    while not _gone(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _gone(pid)


def test_await_kernel_falls_back_with_a_warning(modules, caplog):
    """A second process that failed: the run says so and compiles the kernel itself."""
    job = numba_cache.compile_in_background("bg_fail")
    with caplog.at_level(logging.INFO, logger="msens"):
        pipeline.await_kernel(job, warmup.SIMULATE)
    warned = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warned) == 1 and "no compiler today" in warned[0]
    assert "compiling it here instead" in warned[0]


def test_await_kernel_without_a_job_returns_at_once(caplog):
    with caplog.at_level(logging.INFO, logger="msens"):
        pipeline.await_kernel(None, warmup.SIMULATE)
    assert not caplog.records


def test_kernel_not_cached_in_an_empty_cache(tmp_path):
    """A fresh cache folder holds no variant (checked without compiling the kernel)."""
    code = ("from msens.chain import warmup; from msens.chain import kernel; "
            "print([warmup.cached(v) for v in warmup.VARIANTS], "
            "len(kernel.integrate.overloads), len(kernel.integrate_batch.overloads))")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, check=True, env=env)
    assert done.stdout.split("\n")[0] == "[False, False] 0 0"


def test_kernel_cached_once_compiled():
    warmup.compile_variants([warmup.SIMULATE])
    assert warmup.cached(warmup.SIMULATE) is True


def test_unknown_variant():
    with pytest.raises(ValueError, match="unknown kernel variant 'fast'"):
        warmup.cached("fast")
    with pytest.raises(ValueError, match="unknown kernel variant 'fast'"):
        warmup.compile_variants(["fast"])


def test_the_second_process_imports_the_same_msens(modules, tmp_path):
    """A parent that imports msens from a folder it put on its own path (not in the
    environment): the second process imports that msens too, not the installed one."""
    copy = tmp_path / "copy"
    shutil.copytree(Path(numba_cache.__file__).resolve().parent, copy / "msens",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nb[ic]"))
    parent = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(copy)!r})
        from msens import numba_cache
        assert numba_cache.__file__.startswith({str(copy)!r}), numba_cache.__file__
        job = numba_cache.compile_in_background("bg_where")
        assert job.wait() is None, job.said
        print(job.said[-1])
    """)
    done = subprocess.run([sys.executable, "-c", parent], capture_output=True, text=True,
                          timeout=300, check=True, env=dict(os.environ))
    assert done.stdout.strip() == str(copy / "msens" / "__init__.py")


def test_the_readout_recursion_is_compiled_for_the_types_the_readout_passes():
    """What a first run compiles while it waits is the variant the read-out then uses."""
    import numba
    import numpy as np

    from msens.readout import daq, electronics

    electronics.compile_recursion()
    phi, g0, _ = daq._foh_matrices(-np.eye(2), np.ones((2, 1)), 1e-7)
    drive = np.ascontiguousarray(np.outer(np.ones(3), g0[:, 0]))
    sig = tuple(numba.typeof(a) for a in (phi, np.zeros(2), drive))
    assert sig in electronics._linear_recursion.overloads


def test_await_kernel_does_the_meanwhile_work_only_while_waiting(modules):
    done = []
    job = numba_cache.compile_in_background("bg_sleep")
    assert job.wait_for("started") is None
    try:
        job.said.append(warmup.done_line(warmup.SIMULATE))  # as if already compiled
        pipeline.await_kernel(job, warmup.SIMULATE, meanwhile=lambda: done.append(1))
        assert done == []
    finally:
        job.stop()
    job = numba_cache.compile_in_background("bg_ok", warmup.SIMULATE)
    pipeline.await_kernel(job, warmup.SIMULATE, meanwhile=lambda: done.append(1))
    job.stop()
    assert done in ([1], [])  # [] only if the process had ended before the wait began

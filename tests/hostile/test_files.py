"""Files under faults: a folder in use, temporary files of killed runs, SIGKILL and resume,
user files never overwritten (issue 24)."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
from tests.hostile.conftest import TWENTY, assert_input_error, run_cli

from msens.io import dirlock
from msens.io.atomic import TEMP_MARK, atomic_write_text, clean_stale
from msens.io.output import OutputDir

STUDY = TWENTY
DATA = Path(__file__).parents[1] / "data"


def _env() -> dict[str, str]:
    src = str(Path(__file__).parents[2] / "src")
    return {**os.environ, "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", ""),
            "MPLBACKEND": "Agg"}


def _msens(*args: str) -> list[str]:
    return [sys.executable, "-m", "msens.cli", "-q", *args]


def _holder(folder: Path) -> subprocess.Popen:
    """A process holding ``folder``'s lock until killed."""
    code = ("import sys, time; from msens.io.output import OutputDir; d = OutputDir(sys.argv[1]); "
            "print('held', flush=True); time.sleep(120)")
    proc = subprocess.Popen([sys.executable, "-c", code, str(folder)], env=_env(),
                            stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline().strip()
    proc.stdout.close()
    assert line == "held"
    return proc


def test_folder_in_use_is_said_plainly_and_freed_by_sigkill(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    out = tmp_path / "out"
    holder = _holder(out)
    try:
        code, err = run_cli(["run", str(study), "--out", str(out), "--no-figures"], capsys,
                            seconds=10)
        assert_input_error(code, err, "is in use by another msens command",
                           f"process {holder.pid}")
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    # the kernel dropped the lock with the process: no stale lock
    code, err = run_cli(["run", str(study), "--out", str(out), "--no-figures"], capsys)
    assert code == 0, err


def test_concurrent_runs_into_one_folder(tmp_path):
    """Both succeed, or the second says the folder is in use; never a false 'not written by
    msens', and the result is whole."""
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    out = tmp_path / "out"
    cmd = _msens("run", str(study), "--out", str(out), "--no-figures")
    procs = [subprocess.Popen(cmd, env=_env(), stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = []
    for p in procs:
        _, err = p.communicate(timeout=120)
        results.append((p.returncode, err))
    for code, err in results:
        assert code == 0 or (code == 2 and "is in use by another msens command" in err), err
        assert "not written by msens" not in err
    assert any(code == 0 for code, _ in results)
    import json

    json.loads((out / "summary.json").read_text())


def test_lock_is_shared_within_one_process(tmp_path):
    a = OutputDir(tmp_path / "o")
    b = OutputDir(tmp_path / "o")  # the same command writing through two handles
    b.write_text("x.txt", "x")
    del a, b
    assert not dirlock._held  # released with the last handle


def test_stale_temporary_files_are_removed_on_the_next_run(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    stale = out / f".summary.json.{dead.stdout.strip()}.abc123{TEMP_MARK}.json"
    stale.write_bytes(b"")
    live = out / f".summary.json.{os.getpid()}.def456{TEMP_MARK}.json"
    live.write_bytes(b"")  # a concurrent writer's (this process): left alone
    OutputDir(out)
    assert not stale.exists()
    assert live.exists()
    assert clean_stale(out) == []


def test_atomic_write_permissions_follow_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        path = atomic_write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def test_design_never_overwrites_a_user_file(tmp_path, capsys):
    out = tmp_path / "d"
    out.mkdir()
    for name in ("designs.csv", "recommendation.json"):
        (out / name).write_text("mine")
        code, err = run_cli(["design", str(DATA / "tiny-mss.toml"), "--sweep",
                             str(Path(__file__).parents[2] / "studies" / "sweep-coil.toml"),
                             "--out", str(out)], capsys, seconds=20)
        assert_input_error(code, err, "refusing to overwrite", name)
        assert (out / name).read_text() == "mine"
        (out / name).unlink()


# --------------------------------------------------------------------------- kill and resume

def _files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != dirlock.LOCK_NAME}


def _kill_and_resume(cmd: list[str], out: Path, fractions: tuple[float, ...],
                     tmp_path: Path) -> None:
    """Run ``cmd`` (with ``out``) to completion as the reference; then for each fraction of
    its duration, SIGKILL a run there and run again: the outputs must be byte-identical.

    A first run warms numba's cache: code compiled in the process that runs it rounds a few
    results differently in the last bits (about 1e-15 relative) from the same code loaded from
    the cache, and a compile would stretch the reference's duration, so the kill points."""
    subprocess.run([*cmd, str(tmp_path / "warm")], env=_env(), check=True, timeout=600,
                   stdout=subprocess.DEVNULL)
    ref = tmp_path / "ref"
    start = time.monotonic()
    subprocess.run([*cmd, str(ref)], env=_env(), check=True, timeout=300,
                   stdout=subprocess.DEVNULL)
    duration = time.monotonic() - start
    expected = _files(ref)
    for i, fraction in enumerate(fractions):
        run = out.with_name(f"{out.name}-{i}")
        proc = subprocess.Popen([*cmd, str(run)], env=_env(), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            proc.wait(timeout=fraction * duration)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)  # the command and any workers
            proc.wait()
        subprocess.run([*cmd, str(run)], env=_env(), check=True, timeout=300,
                       stdout=subprocess.DEVNULL)
        got = _files(run)
        assert not [n for n in got if TEMP_MARK in n], "temporary files left behind"
        assert got.keys() == expected.keys(), fraction
        for name in expected:
            assert got[name] == expected[name], (fraction, name)


def test_run_killed_then_resumed_is_byte_identical(tmp_path):
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    _kill_and_resume(_msens("run", str(study), "--out"), tmp_path / "run", (0.8,), tmp_path)


@pytest.mark.slow
def test_diagnose_killed_then_resumed_is_byte_identical(tmp_path):
    from msens import api

    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    data = api.synth(api.load(study), tmp_path / "w.csv", noise=0.01, seed=3)
    _kill_and_resume(_msens("diagnose", str(data), "--study", str(study), "--out"),
                     tmp_path / "diag", (0.7,), tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("command", ["run", "diagnose", "design"])
def test_killed_anywhere_then_resumed_is_byte_identical(tmp_path, command):
    """Many kill points through each command (slow: a dozen runs each)."""
    from msens import api

    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    fractions = tuple(f / 10 for f in range(1, 11))
    if command == "run":
        cmd = _msens("run", str(study), "--out")
    elif command == "diagnose":
        data = api.synth(api.load(study), tmp_path / "w.csv", noise=0.01, seed=3)
        cmd = _msens("diagnose", str(data), "--study", str(study), "--out")
    else:
        sweep = tmp_path / "sweep.toml"
        sweep.write_text('schema = "msens.sweep/1"\nname = "s"\nsensor = 6\n[coil]\n'
                         "turns = [400, 800, 1100]\n")
        cmd = _msens("design", str(DATA / "tiny-mss.toml"), "--sweep", str(sweep), "--out")
    _kill_and_resume(cmd, tmp_path / command, fractions, tmp_path)

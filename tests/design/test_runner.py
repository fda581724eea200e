"""Executor, cache and resumable runner with a stand-in design function."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from msens.design.cache import ResultCache, content_key
from msens.design.runner import run_cached
from msens.parallel import run_tasks

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
import standin  # noqa: E402


def _env() -> dict:
    env = dict(os.environ)
    src = str(HERE.parents[1] / "src")
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), src, env.get("PYTHONPATH", "")])
    return env


def test_run_tasks_local_processes_match_serial(tmp_path):
    log = str(tmp_path / "log")
    args = [(i, 0.0, log) for i in (0, 1, 2, 4, 5)]
    serial = dict(run_tasks(standin.square, args, workers=1))
    parallel = dict(run_tasks(standin.square, args, workers=2))
    assert serial == parallel
    assert sorted(serial) == list(range(len(args)))


def test_no_more_worker_processes_than_cpus():
    """--workers 10**21 on a sweep of many designs would start a solver per design."""
    from msens.parallel import default_workers

    tasks = default_workers() + 2
    pids = {pid for _, pid in run_tasks(standin.pid_after, [0.3] * tasks, workers=10**21)}
    assert 1 <= len(pids) <= default_workers()


def test_task_map_is_a_map_in_input_order(tmp_path):
    """TaskMap (what a workflow hands the physics as ``workers``): results in the order of
    the arguments whatever order the tasks finish in; its length is its worker count."""
    from msens.parallel import TaskMap

    log = str(tmp_path / "log")
    args = [(i, 0.05 * (5 - i), log) for i in (0, 1, 2, 4, 5)]  # the first finish last
    expected = [standin.square(a) for a in args]
    assert TaskMap(workers=2)(standin.square, args) == expected
    assert TaskMap(workers=1)(standin.square, iter(args)) == expected
    assert len(TaskMap(workers=3)) == 3
    assert TaskMap(scheduler="tcp://127.0.0.1:1")  # truth asks no cluster


def test_workers_share_the_cores_between_their_blas_threads():
    """Local workers' BLAS gets cores // workers threads each (at least one): several
    workers with a thread per core each ran 1.5x slower on a 2-core machine."""
    from msens.parallel import default_workers

    threads = [t for _, t in run_tasks(standin.blas_threads, [0, 1, 2, 3], workers=2)]
    assert threads == [max(1, default_workers() // 2)] * 4


def test_failed_design_is_recorded_and_sweep_goes_on(tmp_path):
    log = str(tmp_path / "log")
    tasks = [(content_key("t", i), (i, 0.0, log)) for i in range(6)]
    rows, computed = run_cached(standin.square, tasks, ResultCache(tmp_path / "c"),
                                workers=1, progress=False)
    assert computed == 6
    assert [r["status"] for r in rows] == ["ok"] * 3 + ["failed"] + ["ok"] * 2
    assert "does not converge" in rows[3]["reason"] and "ValueError" in rows[3]["reason"]
    assert rows[5]["value"] == 25 + 5**0.5 / 7.0
    # a second run reads everything from the cache
    rows2, computed2 = run_cached(standin.square, tasks, ResultCache(tmp_path / "c"),
                                  workers=1, progress=False)
    assert computed2 == 0 and rows2 == rows


def test_content_key_depends_on_values_not_order():
    assert content_key({"a": 1.0, "b": 2}) == content_key({"b": 2, "a": 1.0})
    assert content_key({"a": 1.0}) != content_key({"a": 1.0000000001})


def test_sigkill_midway_then_resume_is_identical_without_recomputing(tmp_path):
    n, delay = 12, 0.25
    ref = tmp_path / "ref"
    ref.mkdir()
    subprocess.run([sys.executable, str(HERE / "standin.py"), str(ref), str(n), "0", "1"],
                   check=True, env=_env(), timeout=120)
    run = tmp_path / "run"
    run.mkdir()
    cmd = [sys.executable, str(HERE / "standin.py"), str(run), str(n), str(delay), "2"]
    proc = subprocess.Popen(cmd, env=_env(), start_new_session=True)
    cache = run / "cache"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if cache.is_dir() and len(list(cache.glob("*.json"))) >= 5:
            break
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its workers, mid-run
    proc.wait()
    done = {p.name for p in cache.glob("*.json")}
    assert 5 <= len(done) < n, "the kill must land mid-sweep"
    assert not (run / "designs.csv").exists()
    before = (run / "computed.log").read_text().split()
    subprocess.run(cmd, check=True, env=_env(), timeout=120)
    after = (run / "computed.log").read_text().split()[len(before):]
    finished = {i for i in range(n)
                if content_key("standin", i) + ".json" in done}
    assert not finished & {int(i) for i in after}, "finished designs were recomputed"
    assert (run / "designs.csv").read_bytes() == (ref / "designs.csv").read_bytes()


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.filterwarnings("ignore::ResourceWarning")
def test_dask_local_cluster_gives_identical_results(tmp_path):
    distributed = pytest.importorskip("distributed")
    log = str(tmp_path / "log")
    args = [(i, 0.0, log) for i in (0, 1, 2, 4, 5, 6)]
    local = dict(run_tasks(standin.square, args, workers=2))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:
        remote = dict(run_tasks(standin.square, args, scheduler=cluster.scheduler_address))
    assert remote == local


def test_library_pools_only_under_the_msens_command():
    """A library call may start its own pool only inside ``allow_pools`` (the console
    command), and never in a worker: a user's script without a __main__ guard would be run
    again by every worker."""
    from msens.parallel import allow_pools, pools_allowed

    assert not pools_allowed()
    with allow_pools():
        assert pools_allowed()
        with allow_pools(False):
            assert not pools_allowed()
        assert pools_allowed()
    assert not pools_allowed()
    # run_tasks' workers see no permission
    with allow_pools():
        assert [r for _, r in run_tasks(standin.pools_allowed_here, [0, 1], workers=2)] \
            == [False, False]

"""BLAS on one thread where msens's work is many small dense products (msens.parallel)."""

from __future__ import annotations

import threading
import time

import numpy as np
from threadpoolctl import threadpool_info

from msens.diagnose import workflow
from msens.parallel import one_blas_thread, thread_map


def _blas_threads() -> list[int]:
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


def test_one_blas_thread_inside_and_restored_after():
    np.ones((2, 2)) @ np.ones((2, 2))  # BLAS loaded
    before = _blas_threads()
    assert before, "numpy's BLAS is not seen by threadpoolctl"
    with one_blas_thread():
        assert set(_blas_threads()) == {1}
        with one_blas_thread():  # nested: still one, and the outer limit kept
            assert set(_blas_threads()) == {1}
        assert set(_blas_threads()) == {1}
    assert _blas_threads() == before


def test_the_diagnosis_runs_on_one_blas_thread(monkeypatch):
    """The diagnosis workflow's own frame holds the limit (its profiled likelihoods are
    small products: with OpenBLAS's threads on a busy machine a diagnosis took 3x longer)."""
    seen = []

    def baseline(*args, **kwargs):
        seen.append(_blas_threads())
        raise RuntimeError("stop here")

    monkeypatch.setattr(workflow, "waveform_baseline", baseline)
    try:
        workflow.diagnose(None, None)
    except RuntimeError:
        pass
    assert seen and set(seen[0]) == {1}


def test_thread_map_keeps_the_order_and_runs_on_threads_with_one_blas_thread():
    seen: list = []

    def work(k: int) -> int:
        seen.append((threading.get_ident(), _blas_threads()))
        time.sleep(0.05)  # long enough that both threads take items
        return k * k

    items = list(range(9))
    assert thread_map(work, items, threads=2) == [k * k for k in items]
    assert len({ident for ident, _ in seen}) == 2
    assert all(set(b) == {1} for _, b in seen)
    seen.clear()
    assert thread_map(work, items) == [k * k for k in items]  # default: the calling thread
    assert {ident for ident, _ in seen} == {threading.get_ident()}

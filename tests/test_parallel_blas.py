"""BLAS on one thread where msens's work is many small dense products (msens.parallel)."""

from __future__ import annotations

import numpy as np
from threadpoolctl import threadpool_info

from msens.diagnose import workflow
from msens.parallel import one_blas_thread


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

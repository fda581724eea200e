"""Slow checks of the forward propagation (issue 34's acceptance, at a test's scale):
the same seed on a Dask LocalCluster gives the same numbers as local processes, and the
Sobol indices of the dominant inputs agree between N and 4N base samples.

The full-size measurement (the main study's 13 inputs, N = 128 against 512) is
``benchmarks/uq_convergence.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from msens import api
from msens.parallel import allow_pools
from msens.uq.inputs import parse_inputs
from msens.uq.propagate import propagate, sobol_indices, unit_samples

pytestmark = pytest.mark.slow

INPUTS = """schema = "msens.uncertainty/1"
[[input]]
name = "striker.drop_height_m"
distribution = "uniform"
lower = 6.7e-3
upper = 7.7e-3
reason = "test"
[[input]]
name = "electronics.cable_capacitance_F"
distribution = "uniform"
lower = 50e-12
upper = 200e-12
reason = "test"
[[input]]
name = "sensor.magnet.remanence_factor"
distribution = "uniform"
lower = 0.7
upper = 1.3
reason = "test"
"""


@pytest.fixture(scope="module")
def case():
    study = api.load_default()
    return study, parse_inputs(INPUTS, study, source="slow.toml")


def test_dask_local_cluster_gives_the_same_numbers(case):
    distributed = pytest.importorskip("distributed")
    study, inputs = case
    with allow_pools():
        local = propagate(study, inputs, samples=4, seed=7, workers=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        remote = propagate(study, inputs, samples=4, seed=7, scheduler=cluster.scheduler_address)
    # Bit for bit: whichever process compiles a variant of the chain kernel first, and in
    # whatever order, every process computes alike (msens.numba_cache_file: one cache file per
    # variant; the kernel's arithmetic has no fused multiply-adds, which depend on inlining).
    for k in local.features:
        assert np.array_equal(remote.features[k], local.features[k]), k
        assert np.array_equal(remote.indices[k].total, local.indices[k].total,
                              equal_nan=True), k
    for k in local.waveforms:
        assert np.array_equal(remote.waveforms[k], local.waveforms[k]), k


def test_indices_agree_between_n_and_4n(case):
    study, inputs = case
    with allow_pools():
        large = propagate(study, inputs, samples=256, seed=0, workers=2)
    # the seeded scheme of N = 64 is the first 64 (p + 2) rows of that of 256
    rows = 64 * (len(inputs.propagated) + 2)
    assert np.array_equal(unit_samples(inputs, 64, 0), large.unit[:rows])
    for k in ("paper-mss/mss@13/peak_voltage_V", "paper-mss/mss@13/tof_us",
              "paper-mss/mss@18/peak_emf_V"):
        a, b = sobol_indices(inputs, large.features[k][:rows], 0), large.indices[k]
        assert np.max(np.abs(a.total - b.total)) <= 0.05, (k, a.total, b.total)
        assert np.max(np.abs(a.first - b.first)) <= 0.05, (k, a.first, b.first)

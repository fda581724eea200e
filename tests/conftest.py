"""Settings of the whole suite.

Under pytest-xdist (``pytest -n auto``) each worker compiles numba code into its own
folder. numba's cache is not safe for two processes that compile *different* variants of one
function at the same moment (each numbers its new entry from the index it read, so one
variant's code can be filed under the other's signature); a user's ``msens`` and its
background compile always compile the same variant, the suite's workers do not. Set before
numba is imported (this file is read before any test module); a ``NUMBA_CACHE_DIR`` the
caller set is kept.
"""

from __future__ import annotations

import os

from msens import numba_cache

_worker = os.environ.get("PYTEST_XDIST_WORKER")
if _worker and numba_cache.CACHE_ENV not in os.environ:
    os.environ[numba_cache.CACHE_ENV] = str(
        numba_cache.default_dir().with_name(f"numba-test-{_worker}"))

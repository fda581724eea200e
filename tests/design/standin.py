"""Cheap stand-in design function for the runner tests (tests only; no physics).

``square(payload)`` returns a deterministic function of the payload after a short sleep and
appends the design index to a log file, so a test can count how often each design was
computed. ``main`` runs a whole stand-in sweep (used by the kill/resume subprocess test).
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path


def pools_allowed_here(_) -> bool:
    """:func:`msens.parallel.pools_allowed` as a worker sees it."""
    from msens.parallel import pools_allowed

    return pools_allowed()


def blas_threads(_) -> int:
    """The most threads a BLAS library loaded in this process would start."""
    import numpy  # noqa: F401 - loads the BLAS library
    import threadpoolctl

    return max(i["num_threads"] for i in threadpoolctl.threadpool_info()
               if i["user_api"] == "blas")


def pid_after(delay: float) -> int:
    """This worker's process id, after ``delay`` s (so that every worker gets a task)."""
    time.sleep(delay)
    return os.getpid()


def square(payload: tuple[int, float, str]) -> dict:
    index, delay, log = payload
    time.sleep(delay)
    if index == 3:
        raise ValueError("design 3 does not converge (stand-in failure)")
    with open(log, "a") as fh:
        fh.write(f"{index}\n")
    return {"value": index**2 + math.sqrt(index) / 7.0, "pid": 0 * os.getpid()}


def main(out: str, n: int, delay: float, workers: int) -> None:
    from msens.design.cache import ResultCache, atomic_write_bytes, content_key
    from msens.design.runner import run_cached

    out_p = Path(out)
    log = str(out_p / "computed.log")
    tasks = [(content_key("standin", i), (i, delay, log)) for i in range(n)]
    rows, _ = run_cached(square, tasks, ResultCache(out_p / "cache"), workers=workers,
                         progress=False)
    text = "".join(f"{i},{r['status']},{r.get('value', '')!r},{r.get('reason', '')}\n"
                   for i, r in enumerate(rows))
    atomic_write_bytes(out_p / "designs.csv", text.encode())


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]))

"""The suite's one shared preparation: the chain kernel compiled once, before the workers.

With ``pytest -n auto`` every worker starts with the same cold numba cache (a fresh machine,
CI), so each would compile the chain kernel's variants itself (~50 s each on 2 cores) at the
same moment. Here the controlling process compiles the variants the cache lacks, in parallel
second processes (as ``msens run`` does in the background,
:func:`msens.numba_cache.compile_in_background`), before the workers start; they then load
them. A warm cache costs an index read. The kernel's own compile-and-cache behaviour is
tested with cache folders of its own (tests/chain, tests/test_numba_cache_*.py).
"""

from __future__ import annotations

import time


def pytest_configure(config):
    if hasattr(config, "workerinput") or not config.getoption("numprocesses", None):
        return  # a worker, or a run without workers (its first test compiles what it needs)
    from msens.chain import warmup
    from msens.numba_cache import compile_in_background, use_user_cache

    use_user_cache()
    missing = [v for v in warmup.VARIANTS if warmup.cached(v) is not True]
    if not missing:
        return
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    say = reporter.write_line if reporter is not None else print
    say(f"compiling the chain kernel's variants {', '.join(missing)} for the workers "
        "(once per numba cache, about a minute)")
    t0 = time.perf_counter()
    jobs = [compile_in_background("msens.chain.warmup", v) for v in missing]
    said = t0
    while any(j is not None and j.running() for j in jobs):  # a word every 15 s meanwhile
        time.sleep(0.5)
        if time.perf_counter() - said >= 15:
            said = time.perf_counter()
            say(f"  still compiling ({said - t0:.0f} s)")
    outcomes = {v: "not started" if j is None else j.wait()
                for v, j in zip(missing, jobs, strict=True)}
    problems = [f"{v}: {why}" for v, why in outcomes.items() if why is not None]
    # a failed warm-up is not a failure of the suite: the workers compile what they need
    say(f"chain kernel ready in {time.perf_counter() - t0:.0f} s"
        + (f" ({'; '.join(problems)}: the workers compile them)" if problems else ""))

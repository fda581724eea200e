"""The chain kernel's compiled variants: which a run needs, whether numba's cache holds them,
and compiling them ahead of their first use.

numba compiles :func:`msens.chain.kernel.integrate` once per *variant*, the types of its
arguments; :func:`msens.chain.integrate.simulate` uses one (``SIMULATE``),
:func:`msens.chain.integrate.simulate_batch` another, the parallel
:func:`msens.chain.kernel.integrate_batch` (``BATCH``). Each is compiled here exactly as those
functions call it: the arguments come from the same code
(:func:`msens.chain.integrate._integrate_args`, ``_batch_args``), for a chain of three
particles (the types do not depend on the chain's size or its damping law).

:func:`cached` tells whether numba's on-disk cache already holds a variant (without loading
or compiling anything); :func:`compile_variants` compiles what it lacks; :func:`main` is the
entry point of the second process in which ``msens run`` compiles them
(:func:`msens.numba_cache.compile_in_background`) while it reads the study and loads the
field model.

A process that loads the kernel from the cache computes the same bits as every later run;
one that compiled the step loop itself differs from them in the last bits (measured on the
main study: 2e5 of 3e5 force samples, by up to 4e-14 relative; the step loop as it runs right
after compiling is not bit for bit the one numba reloads from its cache). So a first run that
waits for the second process and then loads the kernel from the cache gives the same results
as every run after it.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import numpy as np

from msens.chain import integrate as _integrate
from msens.chain import kernel
from msens.chain.model import DampingLaw, uniform_chain

#: The variant of :func:`msens.chain.integrate.simulate` (one chain).
SIMULATE = "simulate"
#: The variant of :func:`msens.chain.integrate.simulate_batch` (many chains, numba threads).
BATCH = "batch"
VARIANTS = (SIMULATE, BATCH)


def _tiny_chain():
    # Three steel beads of the paper's size on a wall, the linear-loading dashpot.
    return uniform_chain(3, 0.45e-3, 7.2e9, 1.0e10, 4.71, 0.0,
                         damping_law=DampingLaw.LINEAR_LOADING, length=4.76e-3)


def _times() -> np.ndarray:
    return np.linspace(0.0, 2e-5, 5)


def _variant_call(variant: str):
    """The compiled function of ``variant`` and the arguments its workflow passes it."""
    chain = _tiny_chain()
    # a given step, not the default: that would compile its own numba helper here
    if variant == SIMULATE:
        args, _ = _integrate._integrate_args(chain, 0.37, _times(), 1e-7, False)
        return kernel.integrate, args
    if variant == BATCH:
        args, _ = _integrate._batch_args([chain, chain], 0.37, _times(), 1e-7, None)
        return kernel.integrate_batch, args
    raise ValueError(f"unknown kernel variant {variant!r}; known: {', '.join(VARIANTS)}")


def cached(variant: str) -> bool | None:
    """Whether ``variant`` is compiled in this process or held by numba's on-disk cache.

    Reads the cache's index only (nothing is loaded or compiled). None when it cannot tell
    (numba's cache internals, which this reads, have changed).
    """
    disp, args = _variant_call(variant)
    try:
        sig = tuple(disp.typeof_pyval(a) for a in args)
        if sig in disp.overloads:
            return True
        cache = disp._cache
        key = cache._index_key(sig, disp.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # numba internals moved: unknown, never an error
        return None


def compile_variants(variants: Sequence[str]) -> None:
    """Compile (or load from the cache) each of ``variants`` by integrating the three-bead
    chain through it; numba writes what it compiles to its on-disk cache."""
    for variant in variants:
        chain = _tiny_chain()
        if variant == SIMULATE:
            _integrate.simulate(chain, 0.37, _times())
        elif variant == BATCH:
            _integrate.simulate_batch([chain, chain], 0.37, _times())
        else:
            raise ValueError(f"unknown kernel variant {variant!r}; known: "
                             f"{', '.join(VARIANTS)}")


def done_line(variant: str) -> str:
    """What :func:`main` writes to its standard output when ``variant`` is compiled."""
    return f"compiled {variant}"


def main(argv: Sequence[str] | None = None) -> int:
    """Compile the variants named in ``argv`` (default ``sys.argv[1:]``) in this order,
    writing :func:`done_line` after each; exit status 0."""
    for variant in sys.argv[1:] if argv is None else argv:
        compile_variants([variant])
        print(done_line(variant), flush=True)
    return 0

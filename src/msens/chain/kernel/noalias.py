"""``njit_noalias``: numba's ``njit`` for kernels whose array arguments never overlap.

Why: numba passes every array argument as a plain pointer, so LLVM must assume that any two
of them may overlap. Each vectorised loop that writes one array while reading others is then
preceded by run-time overlap checks of every pair (with a scalar fallback loop). In the
chain kernel's loops over 32 padded entries those checks cost more than the loops (measured
figures: docs/chain-performance.md).

The declaration is LLVM's ``noalias`` on the pointer arguments (C's ``restrict``), set through
numba's own ``flags.noalias`` (the flag its parallel backend sets for kernels it has proven
free of aliasing). Contract of a function compiled this way: no memory that it writes
through one array argument is reached through another argument. Read-only arguments may be
the same array, and views of one allocation may be passed as long as they do not overlap.
They are compiled without numba's reference counting (``_nrt=False``): they may not allocate
arrays, and the counts, which live in a header that views of one array share and so would
be written through two "non-overlapping" pointers, are never touched inside them (numba's
pruning of the counting is heuristic and may leave increments of arguments in place).
"""

from __future__ import annotations

import numba as nb
from numba.core.compiler import CompilerBase, DefaultPassBuilder


class _NoAliasCompiler(CompilerBase):
    """numba's default nopython pipeline with ``flags.noalias`` set."""

    def define_pipelines(self):
        self.state.flags.noalias = True
        return [DefaultPassBuilder.define_nopython_pipeline(self.state)]


def njit_noalias(**options):
    """``numba.njit(**options)`` with the array arguments declared free of overlap, and
    without reference counting (the function may not allocate).

    Parameters
    ----------
    **options
        Passed to :func:`numba.njit` (e.g. ``cache=True``, ``fastmath=...``).

    Returns
    -------
    callable
        The decorator.
    """
    return nb.njit(pipeline_class=_NoAliasCompiler, _nrt=False, **options)

"""The one exception type for bad user input.

Every check of user input raises :class:`InputError`; the command line turns it into a
single message on stderr and exit status 2, with no traceback.
"""

from __future__ import annotations


class InputError(ValueError):
    """Invalid user input: a study key, a file, a value.

    Parameters
    ----------
    message : str
        What is wrong and what is allowed, naming the key, file or value.
    """


def require(condition: bool, message: str) -> None:
    """Raise :class:`InputError` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise InputError(message)


class InternalError(RuntimeError):
    """A broken invariant of msens itself (a bug), never the user's input.

    The command line reports it as an internal error (exit status 1) with a pointer to
    report it, not as bad input.
    """


def internal(condition: bool, message: str) -> None:
    """Raise :class:`InternalError` with ``message`` unless ``condition`` holds (for checks
    of msens's own invariants; user input is checked with :func:`require`)."""
    if not condition:
        raise InternalError(message)

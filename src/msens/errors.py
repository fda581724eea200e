"""The one exception type for bad user input.

Every check of user input raises :class:`InputError`; the command line turns it into a
single message on stderr and exit status 2, with no traceback.
"""

from __future__ import annotations

#: Longest echo of a user's value in a message, characters (:func:`shorten`).
ECHO_LIMIT = 80
#: Longest message of an :class:`InputError`, characters: a message that quotes a whole
#: input (a file with CR-only line endings read as one line) is cut in its middle.
MESSAGE_LIMIT = 1000


def shorten(value: object, limit: int = ECHO_LIMIT) -> str:
    """``repr(value)`` (or ``value`` itself if it is a string already quoted by the caller's
    format) cut to ``limit`` characters with an ellipsis and the original length, for
    quoting a user's value in a message.

    Parameters
    ----------
    value : object
        The value to echo; strings are quoted as ``repr`` does.
    limit : int
        Longest result, characters.

    Returns
    -------
    str
        E.g. ``'time=Time:ms,mss@13=CH1…' (2,310 characters)``.
    """
    text = repr(value)
    if len(text) <= limit:
        return text
    size = len(value) if isinstance(value, str | bytes) else len(text)
    return f"{text[:limit]}… ({size:,} characters)"


def _bounded(message: str) -> str:
    """``message`` on one line (line breaks shown as spaces) and at most
    :data:`MESSAGE_LIMIT` characters, cut in the middle with an ellipsis."""
    text = " ".join(str(message).replace("\r", " ").split("\n"))
    if len(text) <= MESSAGE_LIMIT:
        return text
    head, tail = MESSAGE_LIMIT * 2 // 3, MESSAGE_LIMIT // 4
    return f"{text[:head]} … [{len(text) - head - tail:,} characters cut] … {text[-tail:]}"


class InputError(ValueError):
    """Invalid user input: a study key, a file, a value.

    The message is kept to one line of at most :data:`MESSAGE_LIMIT` characters: a message
    that quotes a whole input is cut in its middle, so the key or file named at its start
    and what is allowed at its end stay.

    Parameters
    ----------
    message : str
        What is wrong and what is allowed, naming the key, file or value.
    """

    def __init__(self, message: object = "", *args: object):
        super().__init__(_bounded(str(message)), *args)


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

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

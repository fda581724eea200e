"""Checks of a command's arguments before any work starts.

The entry points (:mod:`msens.api`, and through it the ``msens`` command) call these first,
so a bad argument ends in one :class:`~msens.errors.InputError` naming it in about a second,
never after minutes of field or chain work: the Dask scheduler address and the worker count
(:mod:`msens.parallel`), output files and folders, counts and fractions given from Python
(``shots=2.5``), the study itself (an object that is not a :class:`~msens.config.study.Study`),
and the study's work and resolvability (:func:`msens.budget.check`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from msens.errors import InputError, shorten
from msens.io.read import SUFFIXES as WAVEFORM_SUFFIXES
from msens.parallel import check_scheduler, check_workers

__all__ = ["check_scheduler", "check_workers", "count", "number", "output_dir", "output_file",
           "study"]


def study(value: object, what: str = "study"):
    """``value`` if it is a loaded :class:`~msens.config.study.Study`, else InputError (a
    path given where a study is expected says to load it first)."""
    from msens.config.study import Study

    if isinstance(value, Study):
        return value
    hint = (" (a path: load it first with msens.load(path))"
            if isinstance(value, str | os.PathLike) else "")
    raise InputError(f"{what} must be a Study (msens.load), got {type(value).__name__} "
                     f"{shorten(value)}{hint}")


def _path(value: object, option: str, what: str) -> Path:
    from msens.io._files import check_path

    if isinstance(value, str | os.PathLike) and str(os.fspath(value)).strip() == "":
        raise InputError(f"{option} is empty: give {what}")
    return check_path(value, option)


def output_file(value: object, option: str = "--out",
                suffixes: tuple[str, ...] = WAVEFORM_SUFFIXES, *,
                overwrite: bool = False) -> Path:
    """An output file name checked before any work: a non-empty path whose suffix is one
    of ``suffixes``, not a folder, not an existing file (msens never overwrites a file it did
    not write, unless ``overwrite``), in a folder that exists or can be created.

    Returns
    -------
    Path
    """
    kinds = ", ".join(suffixes)
    p = _path(value, option, f"a file name ending in {kinds}")
    if p.is_dir() or os.fspath(value).endswith(("/", os.sep)):
        raise InputError(f"{option} {shorten(str(p))} is a folder: give a file name ending in "
                         f"{kinds}")
    if p.suffix.lower() not in suffixes:
        raise InputError(f"{option} {shorten(str(p))}: unknown file type "
                         f"{shorten(p.suffix or '(none)')}; use one of {kinds}")
    if not overwrite and (p.exists() or p.is_symlink()):
        raise InputError(f"{option} {shorten(str(p))}: file exists; msens never overwrites a "
                         "file it did not write (choose another name)")
    _creatable(p.parent, option)
    return p


def output_dir(value: object, option: str = "--out") -> Path:
    """An output folder checked before any work: a non-empty path that is not a file and
    whose nearest existing ancestor is a folder."""
    p = _path(value, option, "an output folder")
    if p.exists() and not p.is_dir():
        raise InputError(f"{option} {shorten(str(p))} is a file, not a folder")
    _creatable(p, option)
    return p


def _creatable(folder: Path, option: str) -> None:
    """InputError if ``folder`` neither is a folder nor can be made under its nearest existing
    ancestor (which must be a folder)."""
    probe = folder if str(folder) else Path(".")
    while not probe.exists():
        if probe.is_symlink():
            raise InputError(f"{option}: {shorten(str(probe))} is a broken symbolic link")
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise InputError(f"{option}: {shorten(str(probe))} is a file, so no folder can be made "
                         "under it")


def count(value: object, name: str, low: int, high: int) -> int:
    """An integer option (``--shots``, ``--passes``) within ``[low, high]``: no fractions,
    booleans or strings (``shots=2.5`` is refused, not truncated)."""
    if isinstance(value, bool) or not isinstance(value, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise InputError(f"{name} must be a whole number from {low} to {high}, got "
                             f"{shorten(value)}")
    if not low <= value <= high:
        raise InputError(f"{name} must be from {low} to {high}, got {shorten(value)}")
    return value


def number(value: object, name: str, low: float, high: float, what: str = "") -> float:
    """A real option (``--noise``) within ``[low, high]``, finite, exactly quoted if not."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{name} must be a number from {low:g} to {high:g}{what}, got "
                         f"{shorten(value)}")
    if not (math.isfinite(value) and low <= value <= high):
        raise InputError(f"{name} must be from {low:g} to {high:g}{what}, got {value!r}")
    return float(value) + 0.0  # -0.0 -> 0.0: numpy refuses a negative-signed zero scale

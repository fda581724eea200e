"""Result directories: atomic writes that never overwrite what a user wrote.

msens keeps a manifest (``.msens-manifest.json``) of the files it wrote into a directory.
A later run may replace those, but a file that exists and is not in the manifest is the
user's: writing over it is refused with an :class:`~msens.errors.InputError`. One command
at a time writes into a directory (:mod:`msens.io.dirlock`); every file is written by
:func:`msens.io.atomic.atomic_write`.
"""

from __future__ import annotations

import json
import weakref
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from msens.errors import InputError, shorten
from msens.io import dirlock
from msens.io._files import check_path
from msens.io.atomic import atomic_write, clean_stale

#: Resolution of every raster figure msens writes (PNG; also the raster parts of PDF/SVG).
DPI = 200

MANIFEST = ".msens-manifest.json"


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _finite(obj: Any) -> Any:
    """``obj`` with every non-finite float (NaN, ±inf) replaced by None, by value."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _finite(obj.tolist())
    if isinstance(obj, float | np.floating):
        return float(obj) if np.isfinite(obj) else None
    return obj


def to_json(data: Any, *, sort_keys: bool = False) -> str:
    """Strict JSON text of ``data`` (numpy arrays and scalars allowed): non-finite numbers
    become null by value, so text such as "NaN" inside a string is kept as it is."""
    return json.dumps(_finite(data), indent=2, default=_json_default, allow_nan=False,
                      sort_keys=sort_keys)


class OutputDir:
    """A directory msens writes results into.

    Parameters
    ----------
    path : str or Path
        Created if missing. Must not be an existing file.
    """

    def __init__(self, path: str | Path):
        self.path = check_path(path, "--out")  # type, empty, name too long, ...
        if self.path.exists() and not self.path.is_dir():
            raise InputError(f"--out '{self.path}' is a file, expected a directory")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"--out {shorten(str(self.path))} cannot be created "
                             f"({exc.strerror or exc})") from None
        # one command at a time in a folder: a second one is told the folder is in use
        key = dirlock.acquire(self.path)
        weakref.finalize(self, dirlock.release, key)
        clean_stale(self.path)  # temporary files of a killed run
        self._manifest_path = self.path / MANIFEST
        self._owned = set(self._read_manifest())

    def _read_manifest(self) -> list[str]:
        try:
            return list(json.loads(self._manifest_path.read_text())["files"])
        except (FileNotFoundError, ValueError, KeyError, TypeError):
            return []

    def target(self, name: str) -> Path:
        """Path for ``name``, checked against overwriting a user's file."""
        path = self.path / name
        if path.exists() and name not in self._owned:
            raise InputError(f"refusing to overwrite '{path}': it was not written by msens "
                             f"(choose another --out directory)")
        return path

    def check(self, names: list[str]) -> None:
        """Fail early, before any work, if one of ``names`` would overwrite a user's file."""
        for name in names:
            self.target(name)

    def record(self, name: str) -> None:
        """Note ``name`` as written by msens (for files written by other code)."""
        if name not in self._owned:
            self._owned.add(name)
            text = json.dumps({"files": sorted(self._owned)}, indent=1)
            atomic_write(self._manifest_path, lambda p: p.write_text(text))

    def write(self, name: str, write: Callable[[Path], None]) -> Path:
        """Write ``name`` atomically with ``write(tmp_path)``; returns the final path."""
        path = self.target(name)
        self.record(name)
        atomic_write(path, write)
        return path

    def write_text(self, name: str, text: str) -> Path:
        return self.write(name, lambda p: p.write_text(text))

    def write_json(self, name: str, data: Any) -> Path:
        text = to_json(data)
        return self.write_text(name, text + "\n")

    def savefig(self, name: str, fig: Any, fmt: str | None = None, **kwargs: Any) -> Path:
        """Save a matplotlib figure atomically.

        Parameters
        ----------
        name : str
            File name; with ``fmt`` its suffix is replaced (``"a.png"`` -> ``"a.pdf"``).
        fig : matplotlib.figure.Figure
        fmt : {"png", "pdf", "svg"}, optional
            File format (default: ``name``'s suffix, else PNG).
        **kwargs
            Passed to ``Figure.savefig`` (e.g. ``dpi``).

        Returns
        -------
        Path
        """
        if fmt is not None:
            name = figure_name(name, fmt)
        fmt = Path(name).suffix.lstrip(".") or "png"
        return self.write(name, lambda p: fig.savefig(p, format=fmt, **kwargs))


def figure_name(name: str, fmt: str) -> str:
    """``name`` with the suffix of figure format ``fmt``: ``figure_name("a.png", "svg")`` is
    ``"a.svg"``."""
    return str(Path(name).with_suffix(f".{fmt}"))

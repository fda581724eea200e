"""The installed msens version (from the package metadata), for provenance and ``--version``."""

from __future__ import annotations


def version() -> str:
    """The installed msens version, or ``"unknown"`` when run from a bare source tree."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as _version

    try:
        return _version("msens")
    except PackageNotFoundError:  # pragma: no cover - run from a source tree
        return "unknown"


__all__ = ["version"]

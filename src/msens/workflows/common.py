"""What every workflow shares: figure formats, figure names and provenance
(:func:`msens.results.provenance`: the msens version and the study's content hash)."""

from __future__ import annotations

from collections.abc import Iterable

from msens.errors import InputError
from msens.results import provenance as provenance


def check_format(fig_format: str) -> str:
    """``fig_format`` if msens can write figures in it (:data:`msens.plots.FORMATS`).

    Raises
    ------
    InputError
        Naming ``--format`` and the formats allowed.
    """
    from msens.plots import FORMATS

    if fig_format not in FORMATS:
        raise InputError(f"--format must be one of {', '.join(FORMATS)}, got {fig_format!r}")
    return fig_format


def figure_names(names: Iterable[str], fig_format: str) -> list[str]:
    """Output file names with the figures (listed as ``.png``) in ``fig_format``."""
    from msens.io.output import figure_name

    return [figure_name(n, fig_format) if n.endswith(".png") else n for n in names]

"""Sensor design sweeps: ``msens design STUDY.toml --sweep SWEEP.toml --out DIR``.

- :mod:`.workflow` — :func:`run_design`: the sweep from a checked request to its files and
  its :class:`DesignResult`.
- :mod:`.sweep` — sweep spec (TOML) parsing and validation; design geometries.
- :mod:`.physics` — the study's wave as a design sees it (the run's chain).
- :mod:`.metrics` — EMF, DAQ voltage and circuit figures per design (the transducer core and
  the run's read-out circuit).
- :mod:`.coil_sweep` — coil-only sweeps from one field model (table quadrature of the
  transducer core's source potentials), chunks through :mod:`msens.parallel`.
- :mod:`.magnet_sweep` — the transducer core per design through :mod:`msens.parallel`.
- :mod:`.cache`, :mod:`.runner` — content-hash result cache, resumable runs, progress bar.
- :mod:`.report` — designs.csv, Pareto plot, recommendation.

The names below load on first use (:pep:`562`).
"""

from msens._lazy import attribute, names

_HOMES = {
    "workflow": ("DesignResult", "files", "format_result", "run_design", "write_results"),
    "sweep": ("load_sweep", "parse_sweep"),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)

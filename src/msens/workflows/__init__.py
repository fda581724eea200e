"""Workflows: each owns one use of msens from a study to its result and files.

One module per workflow; :mod:`msens.api` and the command line only delegate to them. Each
returns a typed result with ``to_json()`` (the content of the JSON file it writes),
``table()`` (the text the command prints; the tables themselves are in :mod:`msens.tables`)
and ``figures`` (the figures written): :class:`~msens.results.StudyResult` (run; its files
are written by :func:`~msens.workflows.run.write_outputs`), :class:`FieldResult`,
:class:`SynthResult`, :class:`CompareResult`, :class:`DiagnoseResult`,
:class:`msens.design.DesignResult`, and :class:`msens.uq.UqResult` and
:class:`msens.uq.CalibrateResult` of the uq and calibrate workflows (:mod:`msens.uq`). So
far:

- :mod:`.run` — simulate every setup of a study; ``summary.json``, the figures, the text
  table.
- :mod:`.field` — the field model of the study's MsS sensors: ``field.json``, ``field.vtu``,
  the field maps, the text report.
- :mod:`.common` — what every workflow shares: the figure formats it can write, the names of
  its figures in a format, and the provenance it records (msens version, study hash).
- :mod:`.compare` — a measured waveform against the model of a study: the checks of the
  measurement (also the first step of a diagnosis), ``compare.json``, the overlay figure and
  the text table.
- :mod:`.synth` — synthetic measurements of one setup: the request checked (including the
  memory its shots need) before the study runs, then the rig effects and the file.
- :mod:`.design` — coil or magnet design sweeps: the request checked, then
  :func:`msens.design.run_design` (the sweep, its cache and its files).
- :mod:`.diagnose` — the effect the model misses, from a waveform or a setup's reference
  rows: ``diagnosis.json``, its figure and the text table.

The functions named like their modules (``run``, ``field``, ``synth``, ``compare``,
``design``, ``diagnose``) are not listed here (an attribute of the package cannot be both);
import them from their modules or call them through :mod:`msens`.
"""

from msens._lazy import attribute, names

_HOMES = {
    "common": ("check_format", "figure_names", "provenance"),
    "run": ("FIGURES", "PHYSICS_FIGURES", "figure_makers", "format_summary", "prepare_outputs",
            "summary", "write_outputs"),
    "field": ("FIELD_OUTPUTS", "FieldResult", "format_field"),
    "synth": ("SynthResult",),
    "compare": ("CompareResult", "check_measurement", "format_comparison"),
    "design": ("format_design",),
    "diagnose": ("DiagnoseResult", "format_diagnosis", "reference_passes"),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)

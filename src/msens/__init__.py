"""msens: magnetostrictive sensors on granular chains carrying solitary waves.

msens models a chain of steel beads struck at one end, the highly nonlinear solitary wave
that runs down it, and the voltage a magnetostrictive sensor (a pick-up coil with a bias
magnet around the chain) gives for it: from a study file (TOML) to the coil's voltage, the
pulse features (time of flight, amplitude ratio, speed), and the comparison with measured
waveforms. All quantities are in SI units.

The names below are the public surface; everything else is reached through the
subpackages (each lists its API in ``__all__``). Each workflow lives in its module of
:mod:`msens.workflows`; :mod:`msens.api` offers the same functions with their text formatters,
and the ``msens`` command (also ``python -m msens``) calls them.

Studies
-------
load
    Read and validate a study file (:class:`Study`).
load_default
    The built-in default study (``paper-mss``: the paper's MsS predicted from physics).
load_paper_table2
    The paper's three setups (Table 2) with its Eq. 10 calibration.
replace
    A study with keys changed by their dotted names, validated like a study file.
Study
    A validated study: chain, striker, sensors, field model, read-out, simulation.

Workflows
---------
run
    Simulate every setup of a study; returns a :class:`StudyResult`.
write_outputs
    Write ``summary.json`` and the figures of a :class:`StudyResult`.
summary
    The content of ``summary.json`` of a :class:`StudyResult`.
field
    Solve the field model of the study's MsS sensors; write its files; returns a
    :class:`FieldResult`.
synth
    Write synthetic measurements of one setup of a study; returns a :class:`SynthResult`.
compare
    Compare a measured waveform with the model of a study; returns a :class:`CompareResult`.
diagnose
    Name the effect the model misses from a measurement; returns a :class:`DiagnoseResult`.
design
    Sweep coil or magnet designs; returns a :class:`DesignResult`.

Results and data
----------------
Every workflow's result has ``to_json()`` (the content of the JSON file the workflow
writes), ``table()`` (the text the command prints) and the files it wrote.

StudyResult, SetupResult, SensorResult
    What a run produced: per study, per setup, per sensor.
FieldResult
    The field model of the study's MsS sensors and its files.
SynthResult
    A file of synthetic measurements (path-like).
CompareResult
    A measured waveform against the model: ``compare.json`` and the overlay.
DiagnoseResult
    The passes of a diagnosis: ``diagnosis.json`` and its figure.
Diagnosis
    One pass of the discrepancy workflow.
DesignResult
    Outcome of a design sweep.
Waveform, read_waveform, write_waveform
    Measured or synthetic records (CSV, NPZ, TDMS) and their reader and writer.

Errors
------
InputError
    Bad user input (a study key, a file, a value): the command exits with status 2.
InternalError
    A broken invariant of msens itself (a bug): the command exits with status 1.

Notes
-----
``import msens`` is cheap: the names are loaded on first use (:pep:`562`), so importing
the package does not start the compiled chain kernel, the finite-element code or the
plotting library.

The workflow names ``field``, ``design``, ``diagnose``, ``compare`` and ``synth`` are
functions on this face; the subpackages and modules of the same names are reached with
``from msens.field import solve`` or ``importlib.import_module("msens.field")``, never
as attributes of ``msens``.

Examples
--------
>>> import msens
>>> study = msens.load_default()            # doctest: +SKIP
>>> result = msens.run(study)               # doctest: +SKIP
>>> result.rows()[0]["tof_us"]              # doctest: +SKIP
"""

from __future__ import annotations

import sys
import types
from importlib import import_module

from msens.errors import InputError, InternalError

#: Where each lazily loaded name of the face lives (module, attribute).
_LAZY: dict[str, tuple[str, str]] = {
    "load": ("msens.api", "load"),
    "load_default": ("msens.api", "load_default"),
    "load_paper_table2": ("msens.api", "load_paper_table2"),
    "replace": ("msens.api", "replace"),
    "run": ("msens.api", "run"),
    "write_outputs": ("msens.api", "write_outputs"),
    "summary": ("msens.api", "summary"),
    "field": ("msens.api", "field"),
    "synth": ("msens.api", "synth"),
    "compare": ("msens.api", "compare"),
    "diagnose": ("msens.api", "diagnose"),
    "design": ("msens.api", "design"),
    "Study": ("msens.config.study", "Study"),
    "StudyResult": ("msens.results", "StudyResult"),
    "SetupResult": ("msens.results", "SetupResult"),
    "SensorResult": ("msens.results", "SensorResult"),
    "FieldResult": ("msens.workflows.field", "FieldResult"),
    "SynthResult": ("msens.workflows.synth", "SynthResult"),
    "CompareResult": ("msens.workflows.compare", "CompareResult"),
    "DiagnoseResult": ("msens.workflows.diagnose", "DiagnoseResult"),
    "Diagnosis": ("msens.diagnose.diagnosis", "Diagnosis"),
    "DesignResult": ("msens.design.workflow", "DesignResult"),
    "Waveform": ("msens.io.waveform", "Waveform"),
    "read_waveform": ("msens.io.read", "read_waveform"),
    "write_waveform": ("msens.io.read", "write_waveform"),
}

#: Face names that are also the names of submodules: the face keeps the function.
_SHADOWED = frozenset(("compare", "design", "diagnose", "field", "synth"))

__all__ = [
    "CompareResult",
    "DesignResult",
    "DiagnoseResult",
    "Diagnosis",
    "FieldResult",
    "InputError",
    "InternalError",
    "SensorResult",
    "SetupResult",
    "Study",
    "StudyResult",
    "SynthResult",
    "Waveform",
    "__version__",
    "compare",
    "design",
    "diagnose",
    "field",
    "load",
    "load_default",
    "load_paper_table2",
    "read_waveform",
    "replace",
    "run",
    "summary",
    "synth",
    "write_outputs",
    "write_waveform",
]


def __getattr__(name: str):
    """Load a face name on first use (:pep:`562`) and keep it in the module."""
    if name == "__version__":
        from msens.version import version

        value = version()
    elif name in _LAZY:
        module, attribute = _LAZY[name]
        value = getattr(import_module(module), attribute)
    else:
        raise AttributeError(f"module 'msens' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


class _Face(types.ModuleType):
    """The ``msens`` module: importing a submodule named like a workflow (``msens.field``,
    ``msens.design``, ...) does not replace the workflow function on the face."""

    def __setattr__(self, name: str, value) -> None:
        if name in _SHADOWED and isinstance(value, types.ModuleType):
            return  # the submodule stays in sys.modules; the face keeps the function
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Face

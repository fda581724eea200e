"""Public Python API: load a study, run it, write and print its results.

The ``msens`` command is a thin layer over these functions, so scripts and notebooks get
exactly the numbers the terminal prints. Each workflow lives in its module of
:mod:`msens.workflows`; this module loads studies and re-exports the workflows (the package
itself, :mod:`msens`, offers the same names)::

    import msens.api as ms
    study = ms.load("studies/paper-table2.toml")
    result = ms.run(study)
    result.rows()          # Table-2 rows as dicts
"""

from __future__ import annotations

from pathlib import Path

from msens import results
from msens.config.schema import PAPER_TABLE2
from msens.config.study import Study, builtin_study_path, default_study_path, load_study
from msens.workflows.common import provenance as provenance
from msens.workflows.compare import compare as compare
from msens.workflows.compare import format_comparison as format_comparison
from msens.workflows.design import design as design
from msens.workflows.design import format_design as format_design
from msens.workflows.diagnose import diagnose as diagnose
from msens.workflows.diagnose import format_diagnosis as format_diagnosis
from msens.workflows.field import FIELD_OUTPUTS as FIELD_OUTPUTS
from msens.workflows.field import field as field
from msens.workflows.field import format_field as format_field
from msens.workflows.run import FIGURES as FIGURES
from msens.workflows.run import PHYSICS_FIGURES as PHYSICS_FIGURES
from msens.workflows.run import format_summary as format_summary
from msens.workflows.run import prepare_outputs as prepare_outputs
from msens.workflows.run import run as run
from msens.workflows.run import summary as summary
from msens.workflows.run import write_outputs as write_outputs
from msens.workflows.synth import synth as synth


def load(path: str | Path) -> Study:
    """Read and validate a study file (raises :class:`msens.errors.InputError`)."""
    return load_study(path)


def load_default(*, eddy_currents: bool | None = None) -> Study:
    """The built-in default study (the paper's MsS predicted from physics).

    Parameters
    ----------
    eddy_currents : bool, optional
        None (default) keeps the study's own choice (eddy currents in the steel on); False
        gives the magnetostatic variant, the faster and less exact model that neglects the
        steel's eddy currents (its signal comes out about a quarter larger).
    """
    study = load_study(default_study_path())
    if eddy_currents is None or eddy_currents == study.field.eddy_currents:
        return study
    return study.replace({"field.eddy_currents": bool(eddy_currents)})


def load_paper_table2() -> Study:
    """The paper's three setups (Table 2) with its Eq. 10 calibration."""
    return load_study(builtin_study_path(PAPER_TABLE2))


def replace(study: Study, changes: dict | None = None, /, **more) -> Study:
    """``study`` with keys changed by their dotted names, validated like a study file
    (:meth:`msens.config.study.Study.replace`):
    ``replace(study, {"sensor[1].coil.turns": 900})``."""
    return study.replace(changes, **more)


physics_summary = results.physics_summary
mechanism_share = results.mechanism_share
frequency_summary = results.frequency_summary

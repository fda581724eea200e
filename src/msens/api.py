"""Public Python API: load a study, run it, write and print its results.

The ``msens`` command is a thin layer over these functions, so scripts and notebooks get
exactly the numbers the terminal prints::

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
from msens.pipeline import run_study
from msens.workflows.common import check_format as _check_format
from msens.workflows.common import provenance
from msens.workflows.compare import compare as compare
from msens.workflows.compare import format_comparison as format_comparison
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


def load(path: str | Path) -> Study:
    """Read and validate a study file (raises :class:`msens.errors.InputError`)."""
    return load_study(path)


def load_default() -> Study:
    """The built-in default study (the paper's MsS predicted from physics)."""
    return load_study(default_study_path())


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


def synth(study: Study, out: Path, *, setup: str | None = None, shots: int = 1,
          noise: float = 0.01, seed: int = 0, overwrite: bool = False) -> Path:
    """Write synthetic measurements of one setup of ``study`` to ``out`` (never over an
    existing file unless ``overwrite``)."""
    from msens import preflight
    from msens.errors import InputError
    from msens.io.read import write_waveform
    from msens.synth import RigEffects, synthesize

    preflight.study(study)
    out = preflight.output_file(out, "--out", overwrite=overwrite)
    shots = preflight.count(shots, "--shots", 1, 10000)
    noise = preflight.number(noise, "--noise", 0.0, 1.0, " (fraction of the peak)")
    seed = preflight.count(seed, "--seed", 0, 2**63 - 1)
    if not 0 <= seed < 2**63:  # numpy's generators take non-negative seeds
        raise InputError(f"--seed must be from 0 to 2**63 - 1, got {seed}")
    names = [s.name for s in study.setups]
    name = setup or names[0]
    if name not in names:
        raise InputError(f"--setup must be one of {', '.join(names)}, got {name!r}")
    if out.exists() and not overwrite:
        raise InputError(f"refusing to overwrite '{out}' (the command's --overwrite replaces it)")
    from msens.config import plausible

    chosen_setup = study.setup(name)
    samples = round(study.simulation.t_end_s * study.simulation.sample_rate_hz) + 1
    # the shots' records and the rig effects' working copies (about four) in float64
    need = 4 * 8 * shots * samples * len(chosen_setup.sensors)
    if need > plausible.MEMORY_BUDGET_BYTES:
        raise InputError(f"--shots {shots} of {samples:,} samples x "
                         f"{len(chosen_setup.sensors)} channels need about "
                         f"{need / 2**30:.3g} GiB; the budget is "
                         f"{plausible.MEMORY_BUDGET_BYTES / 2**30:g} GiB: fewer shots, or a "
                         "shorter 'simulation.t_end_s'")
    result = run_study(study)
    chosen = next(s for s in result.setups if s.setup.name == name)
    meta = {"study": study.name}
    if study.striker.drop_height_m is not None:
        meta["drop_height_m"] = repr(study.striker.drop_height_m)
    waveform = synthesize(chosen, RigEffects(shots=shots, noise=noise, seed=seed),
                          metadata=meta)
    write_waveform(waveform, out, overwrite=overwrite)
    return out


def design(study: Study, sweep: str | Path, out: str | Path, *, scheduler: str | None = None,
           workers: int | None = None, progress: bool = True, fig_format: str = "png"):
    """Sweep coil/magnet designs of the study's MsS (:mod:`msens.design`); writes
    ``designs.csv``, ``pareto.<fig_format>`` and ``recommendation.json`` into ``out``."""
    from msens import budget, preflight
    from msens.design import load_sweep, run_design

    preflight.study(study)
    scheduler = preflight.check_scheduler(scheduler)
    workers = preflight.check_workers(workers)
    out = preflight.output_dir(out)
    budget.check(study)
    return run_design(study, load_sweep(sweep), out, scheduler=scheduler, workers=workers,
                      progress=progress, provenance=provenance(study),
                      fig_format=_check_format(fig_format))


def format_design(result) -> str:
    """Plain-text summary of a design sweep."""
    from msens.design import format_result

    return format_result(result)

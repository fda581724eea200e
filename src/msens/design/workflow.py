"""The design workflow's sweep: evaluate every design of a sweep file, write its files.

:func:`run_design` screens the designs (a coil sweep from one field model, a magnet sweep
design by design through :mod:`msens.parallel`), verifies the best ones with their own
contact maps where the sweep asks for it, and :func:`write_results` writes ``designs.csv``,
the Pareto figure and ``recommendation.json``; the outcome is a :class:`DesignResult`. The
request itself (the study, the scheduler's address, the workers, the output folder, the run
budget) is checked by :func:`msens.workflows.design.design` before it calls here.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass
from pathlib import Path

from msens.config.fieldsetup import geometry_from_study
from msens.config.study import Study
from msens.design.cache import ResultCache, atomic_write_bytes, content_key
from msens.design.report import (
    above_verified,
    csv_text,
    pareto_plot,
    ranked,
    recommend,
    verification,
)
from msens.design.sweep import (
    VERIFY_AUTO,
    SweepSpec,
    base_geometry,
    design_geometry,
    sweep_sensor,
    validate_designs,
)
from msens.errors import InputError
from msens.io.output import OutputDir, to_json
from msens.parallel import pools_allowed
from msens.store import Store, committed_dirs, user_cache_dir
from msens.tables import format_design


def files(fig_format: str = "png") -> tuple[str, ...]:
    """The output file names, the Pareto figure in ``fig_format`` ("png", "pdf", "svg")."""
    return ("designs.csv", f"pareto.{fig_format}", "recommendation.json")


_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class DesignResult:
    """Outcome of a sweep: output paths, the recommendation, counts.

    Attributes
    ----------
    out : Path
        The output folder.
    files : tuple of Path
        The files written: ``designs.csv``, the Pareto figure, ``recommendation.json``.
    recommendation : dict
        The content of ``recommendation.json`` (the design chosen and why, or why none);
        read it through :meth:`to_json`, which returns a copy.
    designs, failed, computed : int
        Designs in the sweep, those that failed, those computed (not from the cache).
    kind : {"coil", "magnet"}
        What the sweep varies.
    """

    out: Path
    files: tuple[Path, ...]
    recommendation: dict
    designs: int
    failed: int
    computed: int
    kind: str

    @property
    def figures(self) -> tuple[Path, ...]:
        """The figures written (the Pareto plot)."""
        return tuple(p for p in self.files if p.suffix not in (".csv", ".json"))

    def to_json(self) -> dict:
        """The content of ``recommendation.json`` (a copy, as JSON values)."""
        return json.loads(to_json(self.recommendation, sort_keys=True))

    def table(self) -> str:
        """What ``msens design`` prints (:func:`msens.tables.format_design`): the counts,
        the recommended design and why, the files written."""
        return format_design(self)


def run_design(study: Study, spec: SweepSpec, out: str | Path, *,
               scheduler: str | None = None, workers: int | None = None,
               progress: bool = True, cache_dir: str | Path | None = None,
               provenance: dict | None = None, fig_format: str = "png") -> DesignResult:
    """Run a sweep and write designs.csv, pareto.png and recommendation.json into ``out``.

    Parameters
    ----------
    study : Study
        Study with at least one MsS sensor (its coil and magnet are the base design).
    spec : SweepSpec
    out : str or Path
        Output directory; its ``cache/`` holds per-design results and meshes, so rerunning
        into the same directory resumes an interrupted sweep.
    scheduler : str, optional
        Dask scheduler address; default local processes (magnet sweeps) or this process
        (the chunks of a coil sweep).
    workers : int, optional
        Local worker processes (magnet sweeps), or the threads a coil sweep's chunks run on
        (default: the CPUs available).
    progress : bool
    cache_dir : str or Path, optional
        Cache location (default ``out/cache``).
    provenance : dict, optional
        Recorded in ``recommendation.json`` (msens version, study hash).
    fig_format : {"png", "pdf", "svg"}
        Format of the Pareto figure.
    """
    from msens.design.coil_sweep import run_coil_sweep
    from msens.design.magnet_sweep import MagnetTask, evaluate_design
    from msens.design.runner import run_cached
    from msens.magnetics.contact_map import mapped_contacts

    target = OutputDir(out)
    target.check(list(files(fig_format)))  # before any work: never overwrite a user's file
    sensor = sweep_sensor(study, spec)
    if spec.verify and not study.field.contact_map:
        raise InputError(f"{spec.source}: [model] verify = {spec.verify} evaluates designs "
                         "again with the study's contact maps, but the study has none: set "
                         "[field] contact_map = true in the study, or drop verify")
    own = study  # the study's physics, which verify restores
    if spec.contact_map is not None and spec.contact_map != study.field.contact_map:
        study = study.replace({"field.contact_map": spec.contact_map})
    designs = spec.designs()
    # paths handed to workers are absolute: a Dask worker has its own working folder
    cache = ResultCache((Path(cache_dir) if cache_dir else target.path / "cache").resolve())
    _log.info("%s sweep of the MsS at particle %d: %d designs (results cached in %s)",
              spec.kind, sensor.particle, len(designs), cache.directory)
    screening: dict[int, dict] | None = None  # verified designs' screening rows
    if spec.kind == "coil":
        _log.info("coil sweep: the study's field model and source potentials, then the "
                  "designs in chunks")
        # the run's own field model: a design equal to the study's coil reproduces the run
        full = geometry_from_study(study)
        validate_designs(full, sensor.particle, designs, spec.source)
        rows, computed = run_coil_sweep(study, full, sensor.particle, designs, cache,
                                        scheduler=scheduler, workers=workers,
                                        progress=progress)
        rows = [{**r, "contact_maps": study.field.contact_map} if r["status"] == "ok" else r
                for r in rows]
    else:
        base = (geometry_from_study(study) if spec.bead_padding is None
                else base_geometry(study, spec.bead_padding))
        validate_designs(base, sensor.particle, designs, spec.source)
        # the designs' meshes, transducers, maps and responses live with the sweep (a shared
        # folder for Dask workers); the committed artifacts and the user cache serve too
        artifacts = Store(cache.directory / "meshes",
                          (*committed_dirs(), user_cache_dir().resolve()), max_bytes=None)
        if study.field.contact_map:
            _log.info("contact maps: each design solves its own for the %d contacts around "
                      "coil %d (about 12 s each on a core)",
                      len(mapped_contacts(base, (sensor.particle,))), sensor.particle)
        geometries = [design_geometry(base, sensor.particle, d) for d in designs]

        def tasks(s: Study, which: list[int]) -> list[tuple[str, MagnetTask]]:
            return [(content_key("magnet-design/2", s, geometries[i], sensor.particle),
                     MagnetTask(s, geometries[i], sensor.particle, artifacts)) for i in which]

        rows, computed = run_cached(evaluate_design, tasks(study, list(range(len(designs)))),
                                    cache, scheduler=scheduler, workers=workers,
                                    progress=progress, description="magnet designs")
        # none to verify when no screened design meets the limits: say so from the screening
        auto = spec.verify == VERIFY_AUTO
        first = ranked(rows, spec.recommend)[:1 if auto else spec.verify]
        if first:
            _log.info("verifying %s with their own contact maps (%d contacts each)",
                      "the best screened designs until none unverified screens above the "
                      "best verified one" if auto else f"the {len(first)} best screened designs",
                      len(mapped_contacts(base, (sensor.particle,))))
            # one design at a time with its maps on the local cores where a pool may start
            # (the msens command: no core idles when fewer designs than workers remain);
            # otherwise the designs go to the workers
            local = scheduler is None and pools_allowed()
            screened, rows, screening = rows, list(rows), {}
            which = first
            while which:
                again, _ = run_cached(evaluate_design, tasks(own, which), cache,
                                      scheduler=scheduler, workers=1 if local else workers,
                                      progress=progress, description="verified with contact maps")
                for i, r in zip(which, again, strict=True):
                    screening[i], rows[i] = screened[i], r
                which = above_verified(rows, screening, spec.recommend)[:1] if auto else []
                if which:
                    _log.info("design %d screens above the best verified design: verifying it",
                              designs[which[0]].index)
    _log.info("writing %s", ", ".join(files(fig_format)))
    return write_results(spec, designs, rows, target, computed=computed,
                         provenance=provenance, fig_format=fig_format, screening=screening)


def write_results(spec: SweepSpec, designs, rows, out: OutputDir, *, computed: int,
                  provenance: dict | None = None, fig_format: str = "png",
                  screening: dict[int, dict] | None = None) -> DesignResult:
    """Write the three output files (atomically, only over msens' own) and the summary.

    ``screening``: the screening rows of the designs ``rows`` holds verified (by position);
    the recommendation is then made among those."""
    if screening is None:
        rec = recommend(designs, rows, spec.recommend)
    else:
        rec = recommend(designs, rows, spec.recommend, among=list(screening))
        rec = verification(rec, designs, rows, screening, spec.recommend)
    if provenance:
        rec = {**rec, "provenance": provenance}
    names = files(fig_format)
    paths = [out.target(f) for f in names]
    for f in names:
        out.record(f)
    atomic_write_bytes(paths[0], csv_text(designs, rows).encode())
    pareto_plot(designs, rows, paths[1], rec.get("design"), spec.recommend.objective,
                verified=None if screening is None else list(screening))
    atomic_write_bytes(paths[2], (to_json(rec, sort_keys=True) + "\n").encode())
    failed = sum(r["status"] != "ok" for r in rows)
    return DesignResult(out=out.path, files=tuple(paths), recommendation=rec,
                        designs=len(rows), failed=failed, computed=computed, kind=spec.kind)


def format_result(result: DesignResult) -> str:
    """Short text summary for the terminal (:meth:`DesignResult.table`)."""
    return result.table()

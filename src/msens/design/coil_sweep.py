"""Coil-only sweeps: one field model, then every coil design by table quadrature.

The coil is a passive receiver and (magnetically) air, so the bias state and the incremental
potentials of both mechanisms' sources do not depend on it
(:func:`msens.magnetics.mechanisms.mechanism_potentials`). A coil of N turns on the rectangle
[r_in, r_out] × [z0, z1] links each source by (N/S) ∫∫ 2π r a_s dr dz, read from a
summed-area table of the same potentials the run's transducer integrates exactly
(:mod:`msens.magnetics.potentials`); the per-contact sensitivities, EMF and read-out follow
from the transducer core and :mod:`msens.design.metrics`. The field model and the wave are
the run's own (the study's whole geometry and chain), so a design equal to the study's coil
reproduces ``msens run``.

Electrical data per design: R from the winding (:func:`msens.field.sensor_model.
coil_resistance`); L from the study coil's bias-point incremental inductance (field model)
carried to each design by the steel-aware cell kernel of the coil's window
(:func:`msens.magnetics.coil_read.scaled_inductance`, the same L as ``msens run`` of a changed
coil; magnet sweeps compute L_inc exactly).

With eddy currents (``[field] eddy_currents = true``) the one field model is the run's
eddy-current model (:func:`msens.config.fieldsetup.eddy_settings`: the mesh graded into the bead
surfaces, the steel's conductivity) and the table holds every source's harmonic potential at
each of the run's frequencies (:mod:`msens.magnetics.harmonic_tables`); a design's complex
S_c(ω), D_c(ω) come from it, its impedance from the study coil's L(ω) scaled by the same
ratio as the static L, and the EMF and DAQ voltage from
:func:`msens.design.metrics.dynamic_design_rows`.

Where the tables come from: when every design fits the study coil's window and the run's
field model has stored tables over it (committed for the main study; written by any
``msens run`` whose coil was then changed), the sweep reads those, so each design is read
exactly as ``msens run`` reads that coil (:func:`_window_context`): a design is the run of
that coil, and the sweep's field model is a read of seconds. Otherwise the sweep tabulates
the run's sources over a box around its designs (:data:`TABLE_SPACING`).
"""

from __future__ import annotations

import io
import json
import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from msens.config.fieldsetup import eddy_settings
from msens.config.study import Study
from msens.design.cache import ResultCache, atomic_write_bytes, content_key
from msens.design.metrics import Wave, design_rows, dynamic_design_rows
from msens.design.physics import study_wave
from msens.design.runner import run_cached
from msens.design.sweep import Design, design_unit
from msens.errors import internal
from msens.field.geometry import SensorGeometry
from msens.field.parts import Coil, SensorUnit
from msens.field.sensor_model import coil_resistance
from msens.magnetics.coil_read import (
    InductanceGrid,
    coil_from,
    coil_record,
    fits,
    inductance_grid,
    read_model,
    read_tables,
    scaled_inductance,
    solved_geometry,
)
from msens.magnetics.coil_read import table_name as static_table_name
from msens.magnetics.dynamic import eddy_sources
from msens.magnetics.dynamic_cache import dynamic_report
from msens.magnetics.eddy_coil_read import free_key as eddy_free_key
from msens.magnetics.eddy_coil_read import read_table as read_eddy_table
from msens.magnetics.eddy_coil_read import tables_key
from msens.magnetics.emf import ContactRates
from msens.magnetics.harmonic_tables import HarmonicTables, harmonic_tables
from msens.magnetics.mechanisms import contact_profiles, mechanism_potentials
from msens.magnetics.potentials import (
    LinkageTable,
    TangentOperator,
    linkage_table,
    rect_integral,
)
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import bias_solution
from msens.magnetics.transducer_cache import free_key as static_free_key
from msens.magnetics.transducer_cache import transducers_for
from msens.parallel import default_workers
from msens.readout.electronics import ElectronicsSpec
from msens.store import Store

#: Grid spacing of the linkage table, m (rectangle integrals converge as spacing²; 0.1 mm
#: gives < 1e-4 relative error against exact mesh quadrature for the paper's coil, tests).
TABLE_SPACING = 0.1e-3
#: Designs evaluated (and cached) per task, at most.
CHUNK = 2048
#: Tasks a sweep is cut into at least (when it has that many designs): the progress bar
#: moves, and an interrupted sweep resumes from the last finished task.
MIN_CHUNKS = 8


@dataclass(frozen=True)
class CoilContext:
    """Everything a coil design needs from the one field model (picklable, saved as .npz).

    Attributes
    ----------
    table : LinkageTable
        Over all sources: Villari per bead, then approach per contact.
    particles : ndarray of int, shape (n_b,)
        Beads with a Villari source.
    approach_contacts : ndarray of int, shape (n_a,)
        Contacts with an approach source.
    count : int
        Particles in the chain.
    wave : Wave
    z_center : float
        Axial position of the sensor bead's centre, m.
    inductance : float
        Bias-point incremental inductance of the study's coil, H.
    grid : InductanceGrid or None
        The steel-aware cell kernel of the coil's window (designs' L from the study coil's);
        None in a sweep's tasks, which carry their designs' L instead (the kernel, ~10 MB,
        stays in the process that made it).
    coil : Coil
        The study's coil.
    harmonic : HarmonicTables or None
        With eddy currents: the sources' harmonic tables (same grid as ``table``).
    inductance_w : ndarray of complex, shape (n_f,), or None
        With eddy currents: the study coil's L(ω) at ``harmonic.frequencies``, H.
    correction : ndarray of complex, shape (n_f, 2 n_c), or None
        With eddy currents and the run's window tables (:func:`_window_context`): the study
        coil's exact S_c(ω) then D_c(ω) minus their table quadrature, added to every
        design's (so a design reads as ``msens run`` reads a changed coil).
    """

    table: LinkageTable
    particles: np.ndarray
    approach_contacts: np.ndarray
    count: int
    wave: Wave
    z_center: float
    inductance: float
    grid: InductanceGrid | None
    coil: Coil
    harmonic: HarmonicTables | None = None
    inductance_w: np.ndarray | None = None
    correction: np.ndarray | None = None


def _coil_box(unit: SensorUnit, designs: Sequence[Design], geometry: SensorGeometry
              ) -> tuple[tuple[float, float], tuple[float, float]]:
    rects = [geometry.coil_rect(design_unit(unit, d.values, geometry.tube)) for d in designs]
    pad = 2 * TABLE_SPACING
    return ((geometry.tube.outer_radius, max(q.r1 for q in rects) + pad),
            (min(q.z0 for q in rects) - pad, max(q.z1 for q in rects) + pad))


def build_context(study: Study, geometry: SensorGeometry, particle: int,
                  designs: Sequence[Design]) -> CoilContext:
    """The one field model of a coil sweep (the run's) and everything derived from it."""
    unit = next(u for u in geometry.sensors if u.coil.particle == particle)
    # with contact maps the wave carries the study coil's equivalent approaches, which every
    # designed coil reads (the Hammerstein assumption of Transducer.shifted)
    transducers = transducers_for(geometry, contact_maps=study.field.contact_map)
    tr = transducers[particle]
    wave = study_wave(study, transducers, particle)
    common = {"wave": wave,
              "z_center": geometry.beads.center(particle), "inductance": tr.inductance_H,
              "coil": unit.coil}
    window = _window_context(study, geometry, unit, designs, common)
    if window is not None:
        logging.getLogger(__name__).info(
            "coil sweep: every design lies in the coil's window; reading the run's tables of "
            "it (each design is read as msens run reads that coil)")
        return window
    r_rng, z_rng = _coil_box(unit, designs, geometry)
    logging.getLogger(__name__).info(
        "coil sweep: tabulating the sources over the designs' box (r %.2f-%.2f mm, z "
        "%.2f-%.2f mm, %.2f mm spacing; the run's stored window tables %s)", r_rng[0] * 1e3,
        r_rng[1] * 1e3, z_rng[0] * 1e3, z_rng[1] * 1e3, TABLE_SPACING * 1e3,
        "do not hold every design" if _has_window(geometry, unit) else "are not there")
    if not study.field.eddy_currents:
        sol, _ = bias_solution(geometry)
        model = mechanism_potentials(sol, geometry, stress_force=tr.reference_force,
                                     law=law_for_steel(geometry.steel))
        table = linkage_table(sol, model.potentials, r_rng, z_rng, TABLE_SPACING)
        return CoilContext(table=table, particles=model.particles,
                           approach_contacts=model.contacts, count=model.count,
                           grid=inductance_grid(sol, model.operator, geometry, unit,
                                                (r_rng, z_rng)),
                           **common)
    # the run's eddy-current model (same mesh, sources and frequencies as dynamic_report)
    eddy = eddy_settings(study)
    response = dynamic_report(geometry, options=eddy.options,
                              steel=eddy.steel).responses[particle]
    model = eddy_sources(geometry, eddy.options)
    harmonic = harmonic_tables(model, geometry, response.frequencies, r_rng, z_rng,
                               TABLE_SPACING, steel=eddy.steel)
    static = LinkageTable(harmonic.r, harmonic.z, harmonic.cumulative[0].real)
    # the designs' L ratio is a static quantity: the coil window's kernel on the plain mesh,
    # as msens run's coil read has it (the eddy mesh would take ten times the solves' time)
    plain, _ = bias_solution(geometry)
    return CoilContext(table=static, particles=model.particles,
                       approach_contacts=model.contacts, count=model.count,
                       grid=inductance_grid(plain, TangentOperator(plain), geometry, unit,
                                            (r_rng, z_rng)),
                       **common,
                       harmonic=harmonic, inductance_w=np.asarray(response.inductance))


def _has_window(geometry: SensorGeometry, unit: SensorUnit) -> bool:
    """Whether the store has the run's static tables of ``unit``'s coil window."""
    return Store.default().find_file(
        static_table_name(static_free_key(geometry), unit.coil.particle)) is not None


def _window_context(study: Study, geometry: SensorGeometry, unit: SensorUnit,
                    designs: Sequence[Design], common: dict) -> CoilContext | None:
    """The context read from the stored tables of the run's field model over the study
    coil's window (committed for the main study), or None when there are none or a design
    does not fit the window (:func:`msens.magnetics.coil_read.fits`, as ``msens run``
    decides whether it reads a changed coil).

    A design is then read exactly as ``msens run`` reads that coil: magnetostatic, by the
    window table's quadrature (:func:`msens.magnetics.coil_read.read_coil`); with eddy
    currents, the solved coil's exact S_c(ω), D_c(ω) plus the tables' difference of the two
    windings (:func:`msens.magnetics.eddy_coil_read.read_response`), the difference being
    carried here as the constant ``correction`` added to every design's table quadrature.
    """
    store = Store.default()
    p = unit.coil.particle
    free = static_free_key(geometry)
    model = read_model(store, free)
    if model is None or model[0].get(p) != unit.coil:
        return None
    coils, inductance = model
    solved = solved_geometry(geometry, coils)
    if not all(fits(design_unit(unit, d.values, geometry.tube).coil, geometry, solved)
               for d in designs):
        return None
    static = read_tables(store, free, coils, inductance, [p])
    if p not in static.tables:
        return None
    layout = {"particles": static.particles, "approach_contacts": static.approach_contacts,
              "count": static.count, "grid": static.grids[p]}
    if not study.field.eddy_currents:
        return CoilContext(table=static.tables[p], **layout, **common)
    eddy = eddy_settings(study)
    response = dynamic_report(geometry, options=eddy.options,
                              steel=eddy.steel).responses[p]
    eddy_model = read_model(store, eddy_free_key(geometry, eddy.options,
                                                 response.frequencies, eddy.steel, None, None))
    if eddy_model is None or eddy_model[0] != coils:
        return None
    table = read_eddy_table(store, tables_key(geometry, coils, eddy.options,
                                              response.frequencies, eddy.steel, None), p)
    if table is None:
        return None
    v, a = table.profiles(unit.coil, geometry, np.zeros(1))
    correction = np.concatenate([np.asarray(response.villari) - v[0],
                                 np.asarray(response.approach) - a[0]], axis=1)
    harmonic = table.harmonic
    return CoilContext(table=LinkageTable(harmonic.r, harmonic.z, harmonic.cumulative[0].real),
                       **{**layout, "particles": table.particles,
                          "approach_contacts": table.approach_contacts, "count": table.count},
                       **common, harmonic=harmonic,
                       inductance_w=np.asarray(response.inductance), correction=correction)


def save_context(ctx: CoilContext, path: Path) -> None:
    """Atomic .npz of a context."""
    w = ctx.wave
    buf = io.BytesIO()
    extra = {} if ctx.harmonic is None else {
        "frequencies": ctx.harmonic.frequencies, "harmonic": ctx.harmonic.cumulative,
        "inductance_w": ctx.inductance_w}
    if ctx.correction is not None:
        extra["correction"] = ctx.correction
    np.savez(buf, r=ctx.table.r, z=ctx.table.z, cumulative=ctx.table.cumulative,
             particles=ctx.particles, approach_contacts=ctx.approach_contacts,
             contacts=w.contacts, t=w.rates.t, force_rate=w.rates.force,
             approach_rate=w.rates.approach,
             scalars=np.array([ctx.count, ctx.z_center, ctx.inductance, 0.0,
                               w.precompression_N, w.precompression_max_N,
                               w.wave_speed_change]),
             grid_r=ctx.grid.r, grid_z=ctx.grid.z, grid_kernel=ctx.grid.kernel,
             coil=np.array(json.dumps(coil_record(ctx.coil))), **extra)
    atomic_write_bytes(path, buf.getvalue())


def load_context(path: Path) -> CoilContext:
    """The context :func:`save_context` wrote."""
    with np.load(path) as f:
        s = f["scalars"]
        wave = Wave(contacts=f["contacts"],
                    rates=ContactRates(f["t"], f["force_rate"], f["approach_rate"]),
                    precompression_N=float(s[4]), precompression_max_N=float(s[5]),
                    wave_speed_change=float(s[6]))
        harmonic = (HarmonicTables(f["frequencies"], f["r"], f["z"], f["harmonic"])
                    if "harmonic" in f.files else None)
        return CoilContext(LinkageTable(f["r"], f["z"], f["cumulative"]), f["particles"],
                           f["approach_contacts"], int(s[0]), wave, float(s[1]), float(s[2]),
                           InductanceGrid(f["grid_r"], f["grid_z"], f["grid_kernel"]),
                           coil_from(json.loads(str(f["coil"]))), harmonic,
                           f["inductance_w"] if harmonic is not None else None,
                           f["correction"] if "correction" in f.files else None)


def _windings(ctx: CoilContext, unit: SensorUnit, designs: Sequence[Design],
              geometry: SensorGeometry):
    """The designs' coils and their windings' arrays: coils, zc, half length, r_in, r_out,
    turns (m; shape (n_d,))."""
    coils = [design_unit(unit, d.values, geometry.tube).coil for d in designs]
    return (coils, np.array([ctx.z_center + c.axial_offset for c in coils]),
            np.array([c.length / 2 for c in coils]),
            np.array([c.inner_radius for c in coils]),
            np.array([c.outer_radius for c in coils]),
            np.array([c.turns for c in coils], dtype=float))


def design_inductances(ctx: CoilContext, unit: SensorUnit, designs: Sequence[Design],
                       geometry: SensorGeometry) -> np.ndarray:
    """Bias-point incremental inductance of each design's coil, H, shape (n_d,): the study
    coil's carried by the window kernel (:func:`msens.magnetics.coil_read.scaled_inductance`,
    as ``msens run`` reads a changed coil)."""
    return _inductances(ctx, unit, _windings(ctx, unit, designs, geometry), geometry)


def _inductances(ctx: CoilContext, unit: SensorUnit, windings: tuple,
                 geometry: SensorGeometry) -> np.ndarray:
    internal(ctx.grid is not None, "internal: a coil context without its inductance kernel")
    _, zc, half, r_in, r_out, turns = windings
    return scaled_inductance(ctx.grid, ctx.inductance, ctx.coil,
                             (r_in, r_out, zc - half, zc + half), turns,
                             (r_out - r_in) * 2 * half, geometry.coil_rect(unit))


def evaluate(ctx: CoilContext, unit: SensorUnit, designs: Sequence[Design],
             geometry: SensorGeometry, electronics: ElectronicsSpec,
             inductance: np.ndarray | None = None, *, threads: int = 1) -> list[dict]:
    """Metrics of coil designs (no validation: :func:`msens.design.sweep.validate_designs`);
    ``inductance``: the designs' L (H, shape (n_d,)) if known, else
    :func:`design_inductances`; ``threads``: threads the designs' chunks of spectra run on
    (:func:`msens.parallel.thread_map`; the caller decides)."""
    windings = _windings(ctx, unit, designs, geometry)
    coils, zc, half, r_in, r_out, turns = windings
    resistance = np.array([coil_resistance(c) for c in coils])
    if inductance is None:
        inductance = _inductances(ctx, unit, windings, geometry)
    inductance = np.asarray(inductance, dtype=float)
    scale = inductance / ctx.inductance
    if ctx.harmonic is None:
        area = (r_out - r_in) * 2 * half
        link = (turns / area)[:, None] * rect_integral(ctx.table, r_in, r_out, zc - half,
                                                       zc + half)
        contacts, s_vil, dl = contact_profiles(ctx.particles, ctx.approach_contacts,
                                               ctx.count, link)
        rows = design_rows(coils, resistance, inductance, s_vil, dl, ctx.wave, electronics,
                           threads)
    else:
        link = ctx.harmonic.linkage(turns, r_in, r_out, zc - half, zc + half)
        contacts, vr, ar = contact_profiles(ctx.particles, ctx.approach_contacts, ctx.count,
                                            link.real)
        _, vi, ai = contact_profiles(ctx.particles, ctx.approach_contacts, ctx.count,
                                     link.imag)
        villari, approach = vr + 1j * vi, ar + 1j * ai
        if ctx.correction is not None:
            villari += ctx.correction[None, :, :contacts.size]
            approach += ctx.correction[None, :, contacts.size:]
        rows = dynamic_design_rows(coils, resistance, inductance, ctx.harmonic.frequencies,
                                   villari, approach,
                                   scale[:, None] * ctx.inductance_w[None], ctx.wave,
                                   electronics, threads)
        s_vil, dl = villari[:, 0].real, approach[:, 0].real
    # the run's transducer covers the same contacts
    internal(bool(np.array_equal(contacts, ctx.wave.contacts)),
             "internal: coil-sweep table and the run's transducer cover different contacts")
    for row, sv, d in zip(rows, s_vil, dl, strict=True):
        row["contacts"] = [int(c) for c in contacts]
        row["dLambda_dF_Wb_per_N"] = [float(v) for v in sv]
        row["dLambda_ddelta_Wb_per_m"] = [float(v) for v in d]
    return rows


@dataclass(frozen=True)
class CoilChunk:
    """Payload of one chunk of coil designs (picklable: runs on local workers or Dask)."""

    context: CoilContext
    unit: SensorUnit
    designs: tuple[Design, ...]
    geometry: SensorGeometry
    electronics: ElectronicsSpec
    inductance: tuple[float, ...]
    threads: int = 1


def evaluate_chunk(task: CoilChunk) -> dict:
    """``{"rows": [...]}`` of one chunk (a module-level task function)."""
    return {"rows": evaluate(task.context, task.unit, task.designs, task.geometry,
                             task.electronics, np.array(task.inductance),
                             threads=task.threads)}


def run_coil_sweep(study: Study, geometry: SensorGeometry, particle: int,
                   designs: Sequence[Design], cache: ResultCache, *,
                   scheduler: str | None = None, workers: int | None = None,
                   progress: bool = True) -> tuple[list[dict], int]:
    """All coil designs' rows (with ``status``) and how many were computed afresh.

    The field model runs here, once; the chunks of designs run through
    :func:`msens.design.runner.run_cached` — in this process, each chunk on ``workers``
    threads (default: the CPUs available; :func:`msens.parallel.thread_map`), or on the
    Dask cluster at ``scheduler`` (the context travels inside each task, so workers need no
    shared files).
    """
    unit = next(u for u in geometry.sensors if u.coil.particle == particle)
    ckey = content_key("coil-context/6", study, geometry, particle,
                       _coil_box(unit, designs, geometry))
    cname = f"context-{ckey}.npz"
    cpath = cache.store.find_file(cname)
    if cpath is not None:
        ctx = load_context(cpath)
    else:
        from msens.progress import heartbeat

        with heartbeat(logging.getLogger(__name__),
                       "coil sweep: field model and tables of the source potentials"):
            ctx = build_context(study, geometry, particle, designs)
        cache.store.write_file(cname, lambda tmp: save_context(ctx, tmp))
    size = max(1, min(CHUNK, -(-len(designs) // MIN_CHUNKS)))
    chunks = [tuple(designs[k:k + size]) for k in range(0, len(designs), size)]
    # the designs' L here, once: the tasks travel without the ~10 MB window kernel
    inductance = design_inductances(ctx, unit, designs, geometry)
    lean = replace(ctx, grid=None)
    # the chunks run one after another here, each on this machine's cores (or ``workers``
    # of them) as threads that share the context; on a cluster one thread each, Dask
    # spreading the chunks
    threads = 1 if scheduler is not None else min(workers or default_workers(),
                                                  default_workers())
    tasks = [(content_key("coil-chunk/2", ckey, [d.values for d in c]),
              CoilChunk(lean, unit, c, geometry, study.electronics,
                        tuple(float(x) for x in inductance[k:k + size]), threads))
             for k, c in zip(range(0, len(designs), size), chunks, strict=True)]
    fresh = sum(len(c) for c, (key, _) in zip(chunks, tasks, strict=True)
                if cache.get(key) is None)
    results, _ = run_cached(evaluate_chunk, tasks, cache, scheduler=scheduler, workers=1,
                            progress=progress, description="coil designs",
                            unit="chunk")
    rows: list[dict] = []
    for chunk, res in zip(chunks, results, strict=True):
        if res["status"] == "ok":
            rows.extend({"status": "ok", **r} for r in res["rows"])
        else:
            rows.extend({"status": "failed", "reason": res["reason"]} for _ in chunk)
    return rows, fresh


__all__ = ["CHUNK", "TABLE_SPACING", "CoilChunk", "CoilContext", "build_context",
           "design_inductances",
           "evaluate", "evaluate_chunk", "load_context", "run_coil_sweep", "save_context"]

"""Stored transducers: a JSON artifact of the store (:mod:`msens.store`) keyed by the content
of the geometry, materials and model.

:func:`transducer_report` returns a stored
:class:`~msens.magnetics.transducer.TransducerReport` (committed, or from the user cache;
verified) or computes and stores it; :func:`transducers_for` gives the transducers alone,
keyed by particle.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from msens.errors import InputError, internal
from msens.field.build import MeshOptions
from msens.field.cache import BUILDER_VERSION, canonical
from msens.field.geometry import SensorGeometry
from msens.field.probes import P2Field
from msens.magnetics.coil_read import (
    CoilTables,
    build_tables,
    coil_free_key,
    fits,
    read_coil,
    read_model,
    read_tables,
    solved_geometry,
    table_name,
    write_model,
    write_tables,
)
from msens.magnetics.magnetoelastic import JilesAthertonSablik
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import (
    TRANSDUCER_VERSION,
    Transducer,
    TransducerReport,
    cache_key,
    compute_transducers,
    model_payload,
)
from msens.params.materials import BEAD_STEEL, ElasticMaterial
from msens.store import Store

_log = logging.getLogger(__name__)


def _to_json(report: TransducerReport) -> dict:
    trs = {}
    for p, tr in report.transducers.items():
        trs[str(p)] = {
            "particle": tr.particle, "contacts": np.asarray(tr.contacts).tolist(),
            "sensitivity_villari_Wb_per_N": np.asarray(tr.sensitivity_villari).tolist(),
            "dLambda_dapproach_Wb_per_m": np.asarray(tr.dlambda_dapproach).tolist(),
            "contact_stiffness_N_per_m1.5": tr.contact_stiffness,
            "reference_force_N": tr.reference_force,
            "magnetic_particle_force_N": np.asarray(tr.magnetic_particle_force).tolist(),
            "resistance_ohm": tr.resistance_ohm, "inductance_H": tr.inductance_H,
            "turns": tr.turns, "source": tr.source,
            "offsets_m": _list(tr.offsets),
            "villari_by_offset_Wb_per_N": _list(tr.villari_by_offset),
            "approach_by_offset_Wb_per_m": _list(tr.approach_by_offset)}
    return {"schema": "msens.transducers/3", "transducers": trs, "details": report.details}


def _from_json(data: dict) -> TransducerReport:
    internal(data.get("schema") == "msens.transducers/3",
             f"internal: not a transducer artifact (schema {data.get('schema')!r})")
    out = {}
    for v in data["transducers"].values():
        out[int(v["particle"])] = Transducer(
            particle=int(v["particle"]), contacts=np.array(v["contacts"], dtype=int),
            sensitivity_villari=np.array(v["sensitivity_villari_Wb_per_N"]),
            dlambda_dapproach=np.array(v["dLambda_dapproach_Wb_per_m"]),
            contact_stiffness=float(v["contact_stiffness_N_per_m1.5"]),
            reference_force=float(v["reference_force_N"]),
            magnetic_particle_force=np.array(v["magnetic_particle_force_N"]),
            resistance_ohm=float(v["resistance_ohm"]), inductance_H=float(v["inductance_H"]),
            turns=int(v["turns"]), source=str(v["source"]),
            offsets=_array(v.get("offsets_m")),
            villari_by_offset=_array(v.get("villari_by_offset_Wb_per_N")),
            approach_by_offset=_array(v.get("approach_by_offset_Wb_per_m")))
    return TransducerReport(out, data.get("details", {}))


def _list(a: np.ndarray | None) -> list | None:
    return None if a is None else np.asarray(a).tolist()


def _array(v: list | None) -> np.ndarray | None:
    return None if v is None else np.array(v, dtype=float)


def transducer_report(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                      store: Store | None = None, stress_force: float | None = None,
                      law: JilesAthertonSablik | None = None,
                      material: ElasticMaterial = BEAD_STEEL, approach: bool = True,
                      refresh: bool = False, contact_maps: bool = False,
                      map_particles: Sequence[int] | None = None) -> TransducerReport:
    """Stored :func:`compute_transducers` (artifact ``transducer-<key>.json``).

    With ``contact_maps`` every transducer also gets the nonlinear contact maps of its
    contacts near the coils (:func:`msens.magnetics.contact_map.approach_maps`, stored
    beside it as ``contact-map-<key>.json``); ``map_particles``: only the coils at those
    particles (the others keep the linear sources).

    ``store`` (default :meth:`msens.store.Store.default`) finds the transducers among the
    committed artifacts (the project commits those of its default studies beside their
    meshes) or in the user cache, verified against their checksum; new ones (and any that
    fail the check) are computed and written to the user cache. ``refresh`` recomputes
    (with ``contact_maps`` the maps too).
    """
    store = Store.default() if store is None else store
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    law = law_for_steel(geometry.steel) if law is None else law
    key = cache_key(geometry, options, stress_force=force, law=law, material=material,
                    approach=approach)
    name = f"transducer-{key}.json"
    if contact_maps:
        from msens.magnetics.contact_map import approach_maps

        report = transducer_report(geometry, options=options, store=store,
                                   stress_force=force, law=law, material=material,
                                   approach=approach, refresh=refresh)
        # the maps are full nonlinear solves: the small-signal permeability (the
        # reversibility) does not enter them, so every choice shares one table; coils read
        # from another coil's field model read that coil's maps (Transducer.reading_maps_of)
        solved = report.read_from or geometry
        map_key = cache_key(replace(solved, reversibility=1.0), options, stress_force=force,
                            law=law, material=material, approach=approach)
        maps = approach_maps(solved, map_key, options=options, store=store,
                             particles=map_particles,
                             start=None if report.bias is None else P2Field.of(report.bias),
                             refresh=refresh)
        return replace(report, transducers={p: replace(tr, approach_map=maps.get(p))
                                            for p, tr in report.transducers.items()})
    free = free_key(geometry, options, stress_force=force, law=law, material=material,
                    approach=approach)
    data = None if refresh else store.read_json(name)
    if data is not None:
        _log.info("transducers %s (cached: yes)", key)
        report = _from_json(data)
        write_model(store, free, {u.coil.particle: u.coil for u in geometry.sensors},
                    {p: tr.inductance_H for p, tr in report.transducers.items()})
        return report
    if not refresh:
        read = _read_coils(geometry, free, options=options, store=store, stress_force=force,
                           law=law, material=material, approach=approach)
        if read is not None:
            return read
    _log.info("transducers %s (cached: no): computing them, usually under a minute", key)
    report = compute_transducers(geometry, options=options, store=store,
                                 stress_force=force, law=law, material=material,
                                 approach=approach)
    path = store.write_json(name, _to_json(report), optional=True)
    if path is not None:
        _log.info("transducers %s cached in %s", key, path)
        write_model(store, free, {u.coil.particle: u.coil for u in geometry.sensors},
                    {p: tr.inductance_H for p, tr in report.transducers.items()})
    return report


def _keep_tables(store: Store, free: str, tables: CoilTables) -> None:
    try:
        write_tables(store, free, tables)
    except InputError as exc:  # kept only to serve later coil changes
        _log.warning("%s; coil tables not kept", exc)


def free_key(geometry: SensorGeometry, options: MeshOptions | None = None, *,
             stress_force: float | None = None, law: JilesAthertonSablik | None = None,
             material: ElasticMaterial = BEAD_STEEL, approach: bool = True) -> str:
    """The coil-free key (:func:`~msens.magnetics.coil_read.coil_free_key`) of the field model
    that :func:`transducer_report` solves for ``geometry`` (same arguments and defaults):
    what the transducer set depends on besides its coils."""
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    law = law_for_steel(geometry.steel) if law is None else law
    return coil_free_key({"transducer": TRANSDUCER_VERSION, "builder": BUILDER_VERSION,
                          "options": canonical(options or MeshOptions()),
                          **model_payload(geometry, stress_force=force, law=law,
                                          material=material, approach=approach)}, geometry)


def _read_coils(geometry: SensorGeometry, free: str, *, store: Store,
                options: MeshOptions | None, **kwargs) -> TransducerReport | None:
    """The transducers of ``geometry`` read from the stored field model of the same sensors
    with other coils (:mod:`msens.magnetics.coil_read`), or None when there is none or a
    coil lies outside its table."""
    model = read_model(store, free)
    if model is None:
        return None
    coils, inductance = model
    solved = solved_geometry(geometry, coils)
    misfits = [u.coil.particle for u in geometry.sensors
               if not fits(u.coil, geometry, solved)]
    if misfits:
        _log.info("coils at particles %s lie outside the tables of the stored field model %s:"
                  " a new field model", misfits, free)
        return None
    data = store.read_json(f"transducer-{cache_key(solved, options, **kwargs)}.json")
    if data is None:  # the solved coils' transducers are gone: a new field model
        return None
    reference = _from_json(data)
    changed = [u.coil.particle for u in geometry.sensors if u.coil != coils[u.coil.particle]]
    tables = read_tables(store, free, coils, inductance, changed)
    missing = [p for p in changed if p not in tables.tables]
    if missing:
        from msens.magnetics.mechanisms import mechanism_potentials
        from msens.magnetics.transducer import bias_solution
        from msens.progress import heartbeat

        _log.info("coil tables of the field model %s for the coils at particles %s: its bias "
                  "solve, sources and window kernels, seconds", free, missing)
        with heartbeat(_log, "coil tables"):
            sol, _ = bias_solution(solved, options=options, store=store)
            model = mechanism_potentials(sol, solved, **kwargs)
            built = build_tables(sol, model, solved, inductance, missing)
        _keep_tables(store, free, built)
        tables = replace(built, tables={**tables.tables, **built.tables},
                         grids={**tables.grids, **built.grids}, coils=coils,
                         inductance_H=inductance)
    # an unchanged coil keeps its own transducer (exact mesh quadrature)
    out = {u.coil.particle: reference.transducers[u.coil.particle] if u.coil == coils[
        u.coil.particle] else read_coil(tables, reference.transducers[u.coil.particle],
                                        u.coil, geometry)
           for u in geometry.sensors}
    _log.info("transducers of the coils at particles %s read from the field model of the "
              "solved coils %s (no new mesh or contact maps)", sorted(out), free)
    details = {**reference.details, "coil_read": {
        "tables": [table_name(free, p) for p in changed],
        "inductance": "solved coil's incremental L x ratio of inductance-grid quadratures"}}
    return TransducerReport(out, details, read_from=solved)


def solved_for(geometry: SensorGeometry, *, options: MeshOptions | None = None,
               store: Store | None = None, material: ElasticMaterial = BEAD_STEEL,
               approach: bool = True) -> SensorGeometry:
    """The geometry whose mesh and bias solve serve ``geometry`` in :func:`transducer_report`
    (default load and law): ``geometry`` itself, or, when its coils are read from the stored
    field model of other coils (:mod:`msens.magnetics.coil_read`), that model's geometry. The
    bias field does not depend on the coils, so its maps and figures may come from either."""
    store = Store.default() if store is None else store
    force = geometry.beads.contact_load
    law = law_for_steel(geometry.steel)
    kwargs = {"stress_force": force, "law": law, "material": material, "approach": approach}
    if store.read_json(f"transducer-{cache_key(geometry, options, **kwargs)}.json"):
        return geometry
    model = read_model(store, free_key(geometry, options, **kwargs))
    if model is None:
        return geometry
    solved = solved_geometry(geometry, model[0])
    if not all(fits(u.coil, geometry, solved) for u in geometry.sensors):
        return geometry
    return solved


def transducers_for(geometry: SensorGeometry, **kwargs) -> dict[int, Transducer]:
    """One :class:`Transducer` per coil of ``geometry``, keyed by particle (cached on disk).

    Keyword arguments as :func:`transducer_report`.
    """
    return transducer_report(geometry, **kwargs).transducers


__all__ = [
    "free_key",
    "solved_for",
    "transducer_report",
    "transducers_for",
]

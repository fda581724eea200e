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

from msens.errors import internal
from msens.field.build import MeshOptions
from msens.field.geometry import SensorGeometry
from msens.field.probes import P2Field
from msens.magnetics.magnetoelastic import JilesAthertonSablik
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import (
    Transducer,
    TransducerReport,
    cache_key,
    compute_transducers,
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
        # reversibility) does not enter them, so every choice shares one table
        map_key = cache_key(replace(geometry, reversibility=1.0), options, stress_force=force,
                            law=law, material=material, approach=approach)
        maps = approach_maps(geometry, map_key, options=options, store=store,
                             particles=map_particles,
                             start=None if report.bias is None else P2Field.of(report.bias),
                             refresh=refresh)
        return TransducerReport({p: replace(tr, approach_map=maps.get(p))
                                 for p, tr in report.transducers.items()}, report.details,
                                bias=report.bias)
    data = None if refresh else store.read_json(name)
    if data is not None:
        _log.info("transducers %s (cached: yes)", key)
        return _from_json(data)
    _log.info("transducers %s (cached: no): computing them, usually under a minute", key)
    report = compute_transducers(geometry, options=options, store=store,
                                 stress_force=force, law=law, material=material,
                                 approach=approach)
    path = store.write_json(name, _to_json(report), optional=True)
    if path is not None:
        _log.info("transducers %s cached in %s", key, path)
    return report


def transducers_for(geometry: SensorGeometry, **kwargs) -> dict[int, Transducer]:
    """One :class:`Transducer` per coil of ``geometry``, keyed by particle (cached on disk).

    Keyword arguments as :func:`transducer_report`.
    """
    return transducer_report(geometry, **kwargs).transducers


__all__ = [
    "transducer_report",
    "transducers_for",
]

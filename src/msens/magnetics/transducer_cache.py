"""The on-disk cache of transducers: JSON keyed by a content hash of the geometry.

:func:`transducer_report` returns a cached
:class:`~msens.magnetics.transducer.TransducerReport` (from the user cache or the committed
meshes) or computes and stores it; :func:`transducers_for` gives the transducers alone,
keyed by particle.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from msens.errors import InputError, require
from msens.field.build import MeshOptions
from msens.field.cache import committed_mesh_dirs, default_mesh_dir
from msens.field.geometry import SensorGeometry
from msens.field.probes import P2Field
from msens.io._files import atomic_write_bytes
from msens.magnetics.magnetoelastic import JilesAthertonSablik
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import (
    Transducer,
    TransducerReport,
    cache_key,
    compute_transducers,
)
from msens.params.materials import BEAD_STEEL, ElasticMaterial

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
    require(data.get("schema") == "msens.transducers/3",
            f"not a transducer cache file (schema {data.get('schema')!r})")
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
                      cache_dir: str | Path | None = None, mesh_dir: str | Path | None = None,
                      stress_force: float | None = None,
                      law: JilesAthertonSablik | None = None,
                      material: ElasticMaterial = BEAD_STEEL, approach: bool = True,
                      refresh: bool = False, contact_maps: bool = False,
                      map_particles: Sequence[int] | None = None) -> TransducerReport:
    """Cached :func:`compute_transducers` (``transducer-<key>.json``).

    With ``contact_maps`` every transducer also gets the nonlinear contact maps of its
    contacts near the coils (:func:`msens.magnetics.contact_map.approach_maps`, cached
    beside it as ``contact-map-<key>.json``); ``map_particles``: only the coils at those
    particles (the others keep the linear sources).

    Lookup follows the mesh cache (:mod:`msens.field.cache`): with ``cache_dir`` only that
    folder; otherwise the committed folders (:func:`msens.field.cache.committed_mesh_dirs`,
    where the project commits the transducers of its default studies beside their meshes),
    and new results go to :func:`msens.field.cache.default_mesh_dir` (the user cache, never
    the committed ``meshes/``). ``refresh`` recomputes (with ``contact_maps`` the maps too).
    """
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    law = law_for_steel(geometry.steel) if law is None else law
    key = cache_key(geometry, options, stress_force=force, law=law, material=material,
                    approach=approach)
    name = f"transducer-{key}.json"
    if cache_dir is not None:
        directory = Path(cache_dir)
        search = [directory]
    else:
        directory = default_mesh_dir()
        search = [*committed_mesh_dirs(), directory]
    if contact_maps:
        from msens.magnetics.contact_map import approach_maps

        report = transducer_report(geometry, options=options, cache_dir=cache_dir,
                                   mesh_dir=mesh_dir, stress_force=force, law=law,
                                   material=material, approach=approach, refresh=refresh)
        # the maps are full nonlinear solves: the small-signal permeability (the
        # reversibility) does not enter them, so every choice shares one table
        map_key = cache_key(replace(geometry, reversibility=1.0), options, stress_force=force,
                            law=law, material=material, approach=approach)
        maps = approach_maps(geometry, map_key, options=options, mesh_dir=mesh_dir,
                             cache_dir=cache_dir, particles=map_particles,
                             start=None if report.bias is None else P2Field.of(report.bias),
                             refresh=refresh)
        return TransducerReport({p: replace(tr, approach_map=maps.get(p))
                                 for p, tr in report.transducers.items()}, report.details,
                                bias=report.bias)
    if not refresh:
        for d in search:
            path = d / name
            if path.is_file():
                _log.info("transducers %s (cached: yes, %s)", key, path)
                try:
                    return _from_json(json.loads(path.read_text()))
                except (ValueError, KeyError) as exc:
                    raise InputError(f"transducer cache {path} is unreadable ({exc}); "
                                     "delete it") from exc
    _log.info("transducers %s (cached: no): computing them, usually under a minute", key)
    report = compute_transducers(geometry, options=options, mesh_dir=mesh_dir,
                                 stress_force=force, law=law, material=material,
                                 approach=approach)
    directory.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(directory / name, json.dumps(_to_json(report), indent=1).encode(),
                       overwrite=True)
    _log.info("transducers %s cached in %s", key, directory / name)
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

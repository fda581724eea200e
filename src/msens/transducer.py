"""Physics MsS transducer: the coil's flux linkage per newton of each contact force.

:func:`transducers_for` runs the field model of a :class:`~msens.field.geometry.SensorGeometry`
(cached mesh, nonlinear bias solve), the bead stress per unit force and the Villari reciprocity
integral of :mod:`msens.villari`, plus the contact-reluctance finite difference and the
magnet's static force on every bead, and returns one :class:`Transducer` per coil. Results are
cached on disk as JSON keyed by a content hash of everything they depend on, so the pipeline
gets them in milliseconds after the first run.

Sign conventions
----------------
* Λ is the coil's flux linkage for its current positive along +φ (B_z > 0 inside the coil);
  the open-circuit EMF is V = -dΛ/dt = -Σ_c (∂Λ/∂F_c) dF_c/dt (:func:`emf`).
* Contact c (1-based, the paper's numbering) joins particles c and c + 1; contact N (the last
  particle) is the wall. Contact forces are compressive positive.
* ``magnetic_particle_force`` is indexed by particle - 1 (index 0 the striker), positive
  toward the wall (-z in the field model, +x in :mod:`msens.chain`): the magnet pulls each bead
  with this force; a bead pulled toward the wall compresses every contact below it.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from msens.errors import InputError, require
from msens.field.build import MeshOptions
from msens.field.cache import canonical as _canonical
from msens.field.cache import committed_mesh_dirs, default_mesh_dir, geometry_key
from msens.field.geometry import SensorGeometry
from msens.field.sensor_model import (
    bias_problem,
    coil_resistance,
    contact_forces,
    group_force,
    load_mesh,
)
from msens.field.solve import FieldSolution, solve
from msens.magnetoelastic import JilesAthertonSablik
from msens.materials import BEAD_STEEL, ElasticMaterial
from msens.steel_law import law_for_steel
from msens.villari import (
    StressSampler,
    TangentOperator,
    approach_residuals,
    bead_state,
    bead_stress,
    coil_flux_linkage,
    contact_sensitivity,
    hertz_approach_rate,
    reluctance_sensitivity,
    villari_sensitivities,
)

#: Version of what :func:`transducers_for` computes; part of the cache key.
TRANSDUCER_VERSION = "transducer/1"

Mechanism = Literal["villari", "reluctance", "both"]


@dataclass(frozen=True)
class Transducer:
    """Linear model of one physics MsS: flux linkage per newton of each contact force.

    Attributes
    ----------
    particle : int
        Particle at the coil's centre (paper numbering).
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers covered (contact c joins particles c and c + 1).
    sensitivity_villari : ndarray, shape (n_c,)
        ∂Λ/∂F_c from the Villari effect (reciprocity), Wb/N.
    sensitivity_reluctance : ndarray, shape (n_c,)
        ∂Λ/∂F_c from the growth of the contact flats (estimate, see :mod:`msens.villari`),
        Wb/N.
    magnetic_particle_force : ndarray, shape (n_particles,)
        Static magnetic force on each particle (index particle - 1), N, positive toward the
        wall. Whole-model force (all magnets of the geometry).
    resistance_ohm : float
        DC coil resistance at 20 °C, Ohm.
    inductance_H : float
        Incremental coil inductance at the bias point, H.
    turns : int
    source : str
        Where the numbers come from (model, cache key).
    approach_sensitivity : ndarray, shape (n_c,), optional
        ∂Λ/∂δ_c of the contact approach, Wb/m (``sensitivity_reluctance`` is this times
        dδ/dF at the operating force).
    contact_stiffness : float, optional
        Hertz prefactor A (F = A δ^{3/2}), N/m^1.5. With ``approach_sensitivity`` it lets
        :func:`emf` use the exact Hertz approach δ(F(t)) instead of the linearised one.
    """

    particle: int
    contacts: np.ndarray
    sensitivity_villari: np.ndarray
    sensitivity_reluctance: np.ndarray
    magnetic_particle_force: np.ndarray
    resistance_ohm: float
    inductance_H: float
    turns: int
    source: str
    approach_sensitivity: np.ndarray | None = None
    contact_stiffness: float | None = None

    def __post_init__(self) -> None:
        n = np.asarray(self.contacts).shape
        require(np.asarray(self.sensitivity_villari).shape == n
                and np.asarray(self.sensitivity_reluctance).shape == n,
                "Transducer: sensitivities must have one value per contact")

    def sensitivity(self, mechanism: Mechanism = "both") -> np.ndarray:
        """∂Λ/∂F_c of the chosen mechanism(s), Wb/N, shape (n_c,)."""
        require(mechanism in ("villari", "reluctance", "both"),
                f"mechanism must be 'villari', 'reluctance' or 'both', got {mechanism!r}")
        if mechanism == "villari":
            return np.asarray(self.sensitivity_villari)
        if mechanism == "reluctance":
            return np.asarray(self.sensitivity_reluctance)
        return np.asarray(self.sensitivity_villari) + np.asarray(self.sensitivity_reluctance)


def emf(transducer: Transducer, t: np.ndarray, force: np.ndarray,
        mechanism: Mechanism = "both", hertz: bool = True) -> np.ndarray:
    """Open-circuit coil EMF V(t) = -Σ_c (∂Λ/∂F_c) dF_c/dt, V.

    Parameters
    ----------
    transducer : Transducer
    t : ndarray, shape (nt,)
        Strictly increasing times, s.
    force : ndarray, shape (nt, m)
        Contact forces of the chain, N: column k is contact k + 1 (as in
        :mod:`msens.chain`). Contacts the transducer covers beyond column m - 1 are skipped.
    mechanism : {"villari", "reluctance", "both"}
    hertz : bool
        For the reluctance part, when the transducer has ``approach_sensitivity`` and
        ``contact_stiffness``: V = -Σ_c (∂Λ/∂δ_c) dδ_c/dt with the exact Hertz approach
        δ_c = ([F_c]_+/A)^{2/3} (dδ/dF falls as F^{-1/3}, so the linearised sensitivity at the
        static load overstates large pulses). False uses the linear sensitivity.

    Returns
    -------
    ndarray, shape (nt,)
        V. Rates are :func:`numpy.gradient` (second order, also on non-uniform times). The
        Villari part is exactly linear in the force rate.
    """
    t = np.asarray(t, dtype=float)
    f = np.asarray(force, dtype=float)
    require(t.ndim == 1 and t.size >= 2, "emf: t must be 1-D with at least 2 samples")
    require(bool(np.all(np.diff(t) > 0)), "emf: t must be strictly increasing")
    require(f.ndim == 2 and f.shape[0] == t.size,
            f"emf: force must have shape (nt={t.size}, n_contacts), got {f.shape}")
    require(mechanism in ("villari", "reluctance", "both"),
            f"mechanism must be 'villari', 'reluctance' or 'both', got {mechanism!r}")
    contacts = np.asarray(transducer.contacts, dtype=int)
    use = (contacts >= 1) & (contacts <= f.shape[1])
    require(bool(np.any(use)), f"emf: force has {f.shape[1]} contacts, none of the "
            f"transducer's contacts {contacts.min()}..{contacts.max()}")
    fc = f[:, contacts[use] - 1]
    out = np.zeros(t.size)
    if mechanism in ("villari", "both"):
        out -= np.gradient(fc, t, axis=0) @ np.asarray(transducer.sensitivity_villari)[use]
    if mechanism in ("reluctance", "both"):
        exact = (hertz and transducer.approach_sensitivity is not None
                 and transducer.contact_stiffness is not None)
        if exact:
            delta = (np.clip(fc, 0.0, None) / transducer.contact_stiffness) ** (2.0 / 3.0)
            out -= (np.gradient(delta, t, axis=0)
                    @ np.asarray(transducer.approach_sensitivity)[use])
        else:
            out -= (np.gradient(fc, t, axis=0)
                    @ np.asarray(transducer.sensitivity_reluctance)[use])
    return out


def magnetic_precompression(transducers: Mapping[int, Transducer] | list[Transducer]
                            ) -> np.ndarray:
    """Static magnetic force on each particle for the chain, N, + toward the wall.

    Transducers from the same field model (same ``source``) carry the same whole-model force
    and count once; those from different models are added (independent magnets).

    Returns
    -------
    ndarray, shape (n_particles,)
    """
    items = list(transducers.values()) if isinstance(transducers, Mapping) else list(transducers)
    require(len(items) > 0, "magnetic_precompression: no transducers given")
    seen: dict[str, np.ndarray] = {}
    for tr in items:
        seen.setdefault(tr.source, np.asarray(tr.magnetic_particle_force, dtype=float))
    sizes = {v.size for v in seen.values()}
    require(len(sizes) == 1, f"transducers describe chains of different lengths {sorted(sizes)}")
    return np.sum(list(seen.values()), axis=0)


# ----------------------------------------------------------------------------- computation

def particle_forces(sol: FieldSolution, geometry: SensorGeometry) -> np.ndarray:
    """Static magnetic force on every particle, N, + toward the wall, shape (count,).

    From the eggshell contact compressions C_c of :func:`contact_forces` (minus the force on
    all modelled beads above contact c): the force on bead p is C_p - C_{p-1}; the last
    modelled bead's lower compression is minus the force on all modelled beads.
    """
    b = geometry.beads
    comp = {c.upper: c.magnetic_force_N for c in contact_forces(sol, geometry)}
    comp[b.last] = -group_force(sol, [f"bead_{p}" for p in b.particles])
    out = np.zeros(b.count)
    for p in b.particles:
        out[p - 1] = comp[p] - comp.get(p - 1, 0.0)
    return out


def _hertz_stiffness(radius: float, material: ElasticMaterial) -> float:
    """Hertz prefactor A of two identical spheres, F = A δ^{3/2}, N/m^1.5."""
    return material.youngs_modulus * math.sqrt(2 * radius) / (
        3 * (1 - material.poisson_ratio**2))


@dataclass(frozen=True)
class TransducerReport:
    """Everything :func:`compute_transducers` finds (also what the cache stores).

    Attributes
    ----------
    transducers : dict of int -> Transducer
    details : dict
        JSON-ready diagnostics: per coil the bead sensitivities S_i, reciprocity errors,
        contact-approach derivatives ∂Λ/∂δ_c; timings; mesh size.
    """

    transducers: dict[int, Transducer]
    details: dict


def compute_transducers(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                        mesh_dir: str | Path | None = None, stress_force: float | None = None,
                        law: JilesAthertonSablik | None = None,
                        material: ElasticMaterial = BEAD_STEEL, reluctance: bool = True,
                        direct_beads: int = 2, max_iter: int = 40) -> TransducerReport:
    """Run the field model and build a :class:`Transducer` for every coil (no cache).

    Parameters
    ----------
    geometry : SensorGeometry
    options : MeshOptions, optional
    mesh_dir : str or Path, optional
        Mesh cache directory.
    stress_force : float, optional
        Force at which the bead stress is solved (the secant sensitivity's force), N; default
        the geometry's ``contact_load`` (the static load that sets the model's flats).
    law : JilesAthertonSablik, optional
        Magnetoelastic law of the beads; default :func:`msens.steel_law.law_for_steel` of
        the geometry's B–H table (the stored 1018 fit for the default curve).
    material : ElasticMaterial
        Bead elasticity.
    reluctance : bool
        Compute the contact-approach ("reluctance") mechanism (adjoint, see
        :mod:`msens.villari`); zeros otherwise.
    direct_beads : int
        Beads on each side of a coil's particle whose S_i is re-checked by the direct
        (re-solved) linearised perturbation.
    max_iter : int
        Newton iterations allowed in the bias solves.
    """
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    require(math.isfinite(force) and force > 0, f"stress_force must be > 0 N, got {force}")
    law = law_for_steel(geometry.steel) if law is None else law
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    axi, path = load_mesh(geometry, options, mesh_dir)
    timings["mesh"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    sol = solve(bias_problem(geometry, axi), max_iter=max_iter)
    timings["bias_solve"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    bs = bead_stress(geometry, force, material)
    sampler = StressSampler(bs)
    operator = TangentOperator(sol)
    timings["stress_and_tangent"] = time.perf_counter() - t0

    residuals = {}
    if reluctance:
        t0 = time.perf_counter()
        residuals = approach_residuals(sol, geometry, list(geometry.beads.particles))
        timings["approach_residuals"] = time.perf_counter() - t0
    rate = hertz_approach_rate(force, geometry.beads.radius, material)

    t0 = time.perf_counter()
    pforce = particle_forces(sol, geometry)
    timings["magnetic_forces"] = time.perf_counter() - t0

    key = cache_key(geometry, options, stress_force=force, law=law, material=material,
                    reluctance=reluctance)
    src = (f"msens.transducer {TRANSDUCER_VERSION}: Villari reciprocity (JAS law, stress at "
           f"{force:.4g} N) + contact approach (adjoint); field mesh {path.name}; key {key}")
    out: dict[int, Transducer] = {}
    details: dict = {"key": key, "mesh": path.name, "elements": axi.n_elements,
                     "dofs": sol.dofs, "newton_iterations": sol.iterations,
                     "stress_force_N": force, "coils": {}}
    for unit in geometry.iter_units():
        coil = unit.coil
        t0 = time.perf_counter()
        near = [p for p in range(coil.particle - direct_beads, coil.particle + direct_beads + 1)
                if p in geometry.beads.particles]
        state = bead_state(sol, coil)
        vil = villari_sensitivities(sol, geometry, coil, bs, law=law, direct=near,
                                    operator=operator, sampler=sampler, state=state)
        contacts, s_vil = contact_sensitivity(vil.particles, vil.sensitivity,
                                              geometry.beads.count)
        inductance = coil_flux_linkage(state.incremental, state.incremental.a, coil)
        s_rel = np.zeros_like(s_vil)
        dl_da = np.zeros_like(s_vil)
        rel_detail = None
        if reluctance:
            rel = reluctance_sensitivity(state, residuals, rate)
            index = {int(c): k for k, c in enumerate(contacts)}
            for c, v, w in zip(rel.contacts, rel.sensitivity, rel.dlambda_dapproach,
                               strict=True):
                s_rel[index[int(c)]] = v
                dl_da[index[int(c)]] = w
            rel_detail = {"dLambda_dapproach_Wb_per_m": dl_da.tolist(),
                          "approach_rate_m_per_N": rate}
        timings[f"coil_{coil.particle}"] = time.perf_counter() - t0
        out[coil.particle] = Transducer(
            particle=coil.particle, contacts=contacts, sensitivity_villari=s_vil,
            sensitivity_reluctance=s_rel, magnetic_particle_force=pforce,
            resistance_ohm=coil_resistance(coil), inductance_H=inductance, turns=coil.turns,
            source=src, approach_sensitivity=dl_da,
            contact_stiffness=_hertz_stiffness(geometry.beads.radius, material))
        details["coils"][str(coil.particle)] = {
            "particles": vil.particles.tolist(),
            "bead_sensitivity_Wb_per_N": vil.sensitivity.tolist(),
            "direct_Wb_per_N": [None if not np.isfinite(x) else float(x) for x in vil.direct],
            "reciprocity_vs_direct_rel_error": vil.relative_error,
            "reluctance": rel_detail}
    details["timings_s"] = timings
    return TransducerReport(out, details)


# ----------------------------------------------------------------------------- cache

def cache_key(geometry: SensorGeometry, options: MeshOptions | None = None, *,
              stress_force: float, law: JilesAthertonSablik, material: ElasticMaterial,
              reluctance: bool) -> str:
    """Content hash (16 hex digits) of everything a transducer set depends on.

    The mesh key leaves out the steel's B–H curve (a material, not geometry); a curve other
    than the default 1018 table enters here by its points, so default keys are unchanged.
    """
    payload = {"version": TRANSDUCER_VERSION, "mesh": geometry_key(geometry, options),
               "stress_force": repr(float(stress_force)), "law": _canonical(law),
               "material": _canonical(material), "reluctance": bool(reluctance)}
    if not geometry.default_steel:
        payload["steel_bh"] = {"b": _canonical(geometry.steel.b),
                               "h": _canonical(geometry.steel.h)}
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _to_json(report: TransducerReport) -> dict:
    trs = {}
    for p, tr in report.transducers.items():
        trs[str(p)] = {
            "particle": tr.particle, "contacts": np.asarray(tr.contacts).tolist(),
            "sensitivity_villari_Wb_per_N": np.asarray(tr.sensitivity_villari).tolist(),
            "sensitivity_reluctance_Wb_per_N": np.asarray(tr.sensitivity_reluctance).tolist(),
            "magnetic_particle_force_N": np.asarray(tr.magnetic_particle_force).tolist(),
            "resistance_ohm": tr.resistance_ohm, "inductance_H": tr.inductance_H,
            "turns": tr.turns, "source": tr.source,
            "approach_sensitivity_Wb_per_m": (None if tr.approach_sensitivity is None else
                                              np.asarray(tr.approach_sensitivity).tolist()),
            "contact_stiffness_N_per_m1.5": tr.contact_stiffness}
    return {"schema": "msens.transducers/1", "transducers": trs, "details": report.details}


def _from_json(data: dict) -> TransducerReport:
    require(data.get("schema") == "msens.transducers/1",
            f"not a transducer cache file (schema {data.get('schema')!r})")
    out = {}
    for v in data["transducers"].values():
        out[int(v["particle"])] = Transducer(
            particle=int(v["particle"]), contacts=np.array(v["contacts"], dtype=int),
            sensitivity_villari=np.array(v["sensitivity_villari_Wb_per_N"]),
            sensitivity_reluctance=np.array(v["sensitivity_reluctance_Wb_per_N"]),
            magnetic_particle_force=np.array(v["magnetic_particle_force_N"]),
            resistance_ohm=float(v["resistance_ohm"]), inductance_H=float(v["inductance_H"]),
            turns=int(v["turns"]), source=str(v["source"]),
            approach_sensitivity=(None if v.get("approach_sensitivity_Wb_per_m") is None
                                  else np.array(v["approach_sensitivity_Wb_per_m"])),
            contact_stiffness=v.get("contact_stiffness_N_per_m1.5"))
    return TransducerReport(out, data.get("details", {}))


def _atomic_write_json(path: Path, data: dict) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as fh:
            json.dump(data, fh, indent=1)
        umask = os.umask(0)  # mkstemp makes 0600; give the file the usual permissions
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def transducer_report(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                      cache_dir: str | Path | None = None, mesh_dir: str | Path | None = None,
                      stress_force: float | None = None,
                      law: JilesAthertonSablik | None = None,
                      material: ElasticMaterial = BEAD_STEEL, reluctance: bool = True,
                      refresh: bool = False) -> TransducerReport:
    """Cached :func:`compute_transducers` (``transducer-<key>.json``).

    Lookup follows the mesh cache (:mod:`msens.field.cache`): with ``cache_dir`` only that
    folder; otherwise the committed folders (:func:`msens.field.cache.committed_mesh_dirs`,
    where the project commits the transducers of its default studies beside their meshes),
    and new results go to :func:`msens.field.cache.default_mesh_dir` (the user cache, never
    the committed ``meshes/``). ``refresh`` recomputes.
    """
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    law = law_for_steel(geometry.steel) if law is None else law
    key = cache_key(geometry, options, stress_force=force, law=law, material=material,
                    reluctance=reluctance)
    name = f"transducer-{key}.json"
    if cache_dir is not None:
        directory = Path(cache_dir)
        search = [directory]
    else:
        directory = default_mesh_dir()
        search = [*committed_mesh_dirs(), directory]
    if not refresh:
        for d in search:
            path = d / name
            if path.is_file():
                try:
                    return _from_json(json.loads(path.read_text()))
                except (ValueError, KeyError) as exc:
                    raise InputError(f"transducer cache {path} is unreadable ({exc}); "
                                     "delete it") from exc
    report = compute_transducers(geometry, options=options, mesh_dir=mesh_dir,
                                 stress_force=force, law=law, material=material,
                                 reluctance=reluctance)
    directory.mkdir(parents=True, exist_ok=True)
    _atomic_write_json(directory / name, _to_json(report))
    return report


def transducers_for(geometry: SensorGeometry, **kwargs) -> dict[int, Transducer]:
    """One :class:`Transducer` per coil of ``geometry``, keyed by particle (cached on disk).

    Keyword arguments as :func:`transducer_report`.
    """
    return transducer_report(geometry, **kwargs).transducers


__all__ = [
    "TRANSDUCER_VERSION", "Transducer", "TransducerReport", "cache_key",
    "compute_transducers", "emf", "magnetic_precompression", "particle_forces",
    "transducer_report", "transducers_for",
]

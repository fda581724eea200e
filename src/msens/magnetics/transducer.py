"""Physics MsS transducer: each coil's flux linkage per unit of every contact's state.

:func:`compute_transducers` runs the field model of a
:class:`~msens.field.geometry.SensorGeometry` (cached mesh, nonlinear bias solve), builds the
incremental potentials of both mechanisms' sources
(:func:`msens.magnetics.mechanisms.mechanism_potentials`: the Villari magnetisation of every
bead per newton, and the contact approach of every contact per metre) with one
factorisation, and reads each coil's flux linkage of them by exact quadrature over its
winding (:mod:`msens.magnetics.potentials`). Design sweeps read the same potentials
through a summed-area table (:mod:`msens.design.coil_sweep`), so a design and ``msens run``
share one implementation. Results are cached on disk as JSON keyed by a content hash
(:mod:`msens.magnetics.transducer_cache`); the EMF from the chain's contact states is in
:mod:`msens.magnetics.emf`.

Mechanisms (one name each, everywhere): ``"villari"`` (stress-induced magnetisation of the
beads, :mod:`msens.magnetics.villari`) and ``"approach"`` (the contact approach: the beads
move closer and the saturated contact necks grow, :mod:`msens.magnetics.approach`).

Sign conventions
----------------
* Λ is the coil's flux linkage for its current positive along +φ (B_z > 0 inside the coil);
  the open-circuit EMF is V = -dΛ/dt (:func:`msens.magnetics.emf.emf`).
* Contact c (1-based, the paper's numbering) joins particles c and c + 1; contact N (the last
  particle) is the wall. Contact forces are compressive positive; the approach δ_c is the
  Hertz approach of the contact's force.
* ``magnetic_particle_force`` is indexed by particle - 1 (index 0 the striker), positive
  toward the wall (-z in the field model, +x in :mod:`msens.chain`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

import numpy as np

from msens.errors import internal, require
from msens.field.build import MeshOptions
from msens.field.cache import geometry_key
from msens.field.geometry import SensorGeometry
from msens.field.sensor_model import (
    bias_problem,
    coil_resistance,
    group_force,
    load_mesh,
    magnetic_contact_forces,
)
from msens.field.solve import FieldSolution, solve
from msens.io.hashing import canonical as _canonical
from msens.magnetics.approach import hertz_approach_rate, hertz_stiffness
from msens.magnetics.contact_map import ApproachMap
from msens.magnetics.magnetoelastic import JilesAthertonSablik
from msens.magnetics.mechanisms import (
    adjoint_check,
    coil_linkage,
    mechanism_potentials,
    offset_profiles,
)
from msens.magnetics.steel_law import law_for_steel
from msens.mechanics.hertz import hertz_approach
from msens.params.materials import BEAD_STEEL, ElasticMaterial
from msens.store import Store, content_key

_log = logging.getLogger(__name__)

#: Version of what :func:`transducers_for` computes; part of the cache key.
TRANSDUCER_VERSION = "transducer/3"

Mechanism = Literal["villari", "approach", "both"]

MECHANISMS: tuple[str, ...] = ("villari", "approach", "both")


@dataclass(frozen=True)
class Transducer:
    """Linear model of one physics MsS: flux linkage per unit of each contact's state.

    Attributes
    ----------
    particle : int
        Particle at the coil's centre (paper numbering).
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers covered (contact c joins particles c and c + 1).
    sensitivity_villari : ndarray, shape (n_c,)
        ∂Λ/∂F_c of the Villari effect, Wb/N.
    dlambda_dapproach : ndarray, shape (n_c,)
        ∂Λ/∂δ_c of the contact approach, Wb/m.
    contact_stiffness : float
        Hertz prefactor A (F = A δ^{3/2}), N/m^1.5: δ_c(t) = ([F_c]_+/A)^{2/3}.
    reference_force : float
        Static load at which the bead stress (Villari) and the linearised approach
        sensitivity are evaluated, N.
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
    offsets : ndarray, shape (n_o,), optional
        Axial coil offsets from its position, m (uniform, symmetric about 0).
    villari_by_offset, approach_by_offset : ndarray, shape (n_o, n_c), optional
        ``sensitivity_villari`` and ``dlambda_dapproach`` of the same coil moved by each
        offset (magnets and beads fixed), from the same source potentials
        (:func:`offset_profiles`); :meth:`shifted` interpolates them.
    approach_map : ApproachMap, optional
        Nonlinear contact maps Λ_c(δ) of some contacts
        (:mod:`msens.magnetics.contact_map`): their approaches are read through
        :meth:`equivalent_approach`. None: the linear sources alone.
    """

    particle: int
    contacts: np.ndarray
    sensitivity_villari: np.ndarray
    dlambda_dapproach: np.ndarray
    contact_stiffness: float
    reference_force: float
    magnetic_particle_force: np.ndarray
    resistance_ohm: float
    inductance_H: float
    turns: int
    source: str
    offsets: np.ndarray | None = None
    villari_by_offset: np.ndarray | None = None
    approach_by_offset: np.ndarray | None = None
    approach_map: ApproachMap | None = None

    def __post_init__(self) -> None:
        n = np.asarray(self.contacts).shape
        internal(np.asarray(self.sensitivity_villari).shape == n
                 and np.asarray(self.dlambda_dapproach).shape == n,
                 "internal: Transducer sensitivities must have one value per contact")

    @property
    def sensitivity_approach(self) -> np.ndarray:
        """∂Λ/∂F_c of the contact approach linearised at ``reference_force``, Wb/N."""
        rate = 2.0 / 3.0 * float(hertz_approach(self.reference_force, self.contact_stiffness)) \
            / self.reference_force
        return np.asarray(self.dlambda_dapproach) * rate

    def shifted(self, offset: float) -> Transducer:
        """The same coil moved axially by ``offset`` (m, + toward the striker), magnets and
        beads fixed: sensitivities by cubic interpolation of the offset profiles. R and L are
        kept (the coil's inductance changes little over a few mm).

        Contact maps carry over as the static part of a Hammerstein model: a mapped contact's
        equivalent approach (the map's shape, :meth:`ApproachMap.equivalent`) is read through
        the moved coil's sensitivities. This ASSUMES the shape of Λ_c(δ) does not depend on where
        the coil sits. On the main study (``python benchmarks/contact_map_transfer.py
        --moved``) the maps of contacts 12, 13, 17 and 18 read by their coil moved ±2.5 mm
        keep their shape to 0.5 % of their range (±1 mm: 0.18 %); five beads away it fails
        (coil 13 reads contacts 15–20 with a shape 3.8–105 % off coil 18's).
        """
        internal(self.offsets is not None, "internal: transducer has no offset profiles")
        require(self.offsets[0] <= offset <= self.offsets[-1],
                f"coil offset {offset} m outside the tabulated "
                f"{self.offsets[0]:g}..{self.offsets[-1]:g} m")
        from scipy.interpolate import CubicSpline

        vil = CubicSpline(self.offsets, self.villari_by_offset, axis=0)(offset)
        app = CubicSpline(self.offsets, self.approach_by_offset, axis=0)(offset)
        return replace(self, sensitivity_villari=np.asarray(vil),
                       dlambda_dapproach=np.asarray(app))

    def reading_maps_of(self, source: Transducer) -> Transducer:
        """This coil reading the contact maps of ``source`` (the same coil in the study's
        field model, or the coil they were solved for) through its own sensitivities, as
        :meth:`shifted` carries them; itself if ``source`` has no maps.

        The maps are shapes with unit slope at the static contact
        (:meth:`ApproachMap.equivalent`), so carrying them over ASSUMES the shape of
        Λ_c(δ) does not depend on the coil or magnet that reads it. Measured on the main
        study: the maps of contacts 13 and 18 solved with all remanences × 0.7 and × 1.3
        (the ``magnet_remanence`` variants) keep the study's shape to 0.78 % of their range
        (``python benchmarks/contact_map_transfer.py --remanence --contacts 13,18``). Another
        magnet DESIGN changes the shape (contact 10 by 8–15 % of its range at the magnet
        sweep's corners, ``--magnet``): a magnet sweep solves each design's own maps."""
        if source.approach_map is None:
            return self
        internal(set(source.approach_map.contacts) <= {int(c) for c in self.contacts},
                 "internal: contact maps carried to a transducer without the mapped contacts")
        return replace(self, approach_map=source.approach_map)

    def equivalent_approach(self, delta: np.ndarray) -> np.ndarray:
        """The approaches the linear sources read, m, shape of ``delta`` (..., n_c): the
        contact maps' equivalent approaches (:meth:`ApproachMap.equivalent`) for mapped
        contacts, ``delta`` itself otherwise."""
        if self.approach_map is None:
            return np.asarray(delta, dtype=float)
        return self.approach_map.equivalent(delta, np.asarray(self.contacts))

    def sensitivity(self, mechanism: Mechanism = "both") -> np.ndarray:
        """∂Λ/∂F_c of the chosen mechanism(s) at the reference load, Wb/N, shape (n_c,)."""
        _check_mechanism(mechanism)
        if mechanism == "villari":
            return np.asarray(self.sensitivity_villari)
        if mechanism == "approach":
            return self.sensitivity_approach
        return np.asarray(self.sensitivity_villari) + self.sensitivity_approach


def _check_mechanism(mechanism: str) -> None:
    require(mechanism in MECHANISMS,
            f"mechanism must be one of {', '.join(MECHANISMS)}, got {mechanism!r}")


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


def particle_forces(sol: FieldSolution, geometry: SensorGeometry) -> np.ndarray:
    """Static magnetic force on every particle, N, + toward the wall, shape (count,).

    From the eggshell contact compressions C_c of :func:`magnetic_contact_forces` (minus the
    force on all modelled beads above contact c): the force on bead p is C_p - C_{p-1}; the last
    modelled bead's lower compression is minus the force on all modelled beads.
    """
    b = geometry.beads
    comp = {c.upper: c.magnetic_force_N for c in magnetic_contact_forces(sol, geometry)}
    comp[b.last] = -group_force(sol, [f"bead_{p}" for p in b.particles])
    out = np.zeros(b.count)
    for p in b.particles:
        out[p - 1] = comp[p] - comp.get(p - 1, 0.0)
    return out


@dataclass(frozen=True)
class TransducerReport:
    """Everything :func:`compute_transducers` finds (also what the cache stores).

    Attributes
    ----------
    transducers : dict of int -> Transducer
    details : dict
        JSON-ready diagnostics: per coil the bead Villari sensitivities, the reciprocity
        check; mesh size.
    bias : FieldSolution or None
        The bias solution it was computed from (None when read from the cache): a start
        for the same geometry's bias on another mesh (:func:`bias_solution`).
    read_from : SensorGeometry or None
        When the coils were read from another coil's field model: that model's geometry
        (its contact maps are the ones these coils read).
    """

    transducers: dict[int, Transducer]
    details: dict
    bias: FieldSolution | None = field(default=None, compare=False, repr=False)
    read_from: SensorGeometry | None = field(default=None, compare=False, repr=False)


def bias_solution(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                  store: Store | None = None, max_iter: int = 40,
                  start: FieldSolution | None = None) -> tuple[FieldSolution, Path]:
    """Mesh (from ``store``, default :meth:`msens.store.Store.default`) and nonlinear bias
    solve of a geometry.

    ``start``: the same geometry's bias on another mesh; Newton starts from it, interpolated
    (:func:`msens.magnetics.dynamic.eddy_bias_solution`).
    """
    axi, path = load_mesh(geometry, options, store)
    return solve(bias_problem(geometry, axi), max_iter=max_iter, start=start), path


def compute_transducers(geometry: SensorGeometry, *, options: MeshOptions | None = None,
                        store: Store | None = None, stress_force: float | None = None,
                        law: JilesAthertonSablik | None = None,
                        material: ElasticMaterial = BEAD_STEEL, approach: bool = True,
                        max_iter: int = 40) -> TransducerReport:
    """Run the field model and build a :class:`Transducer` for every coil (no cache).

    Parameters
    ----------
    geometry : SensorGeometry
    options : MeshOptions, optional
    store : Store, optional
        Where the mesh is found or written (default :meth:`msens.store.Store.default`).
    stress_force : float, optional
        Force at which the bead stress is solved (the secant sensitivity's force), N; default
        the geometry's ``contact_load`` (the static load that sets the model's flats).
    law : JilesAthertonSablik, optional
        Magnetoelastic law of the beads; default :func:`msens.magnetics.steel_law.law_for_steel` of
        the geometry's B–H table.
    material : ElasticMaterial
        Bead elasticity.
    approach : bool
        Compute the contact-approach mechanism; zeros otherwise.
    max_iter : int
        Newton iterations allowed in the bias solve.
    """
    force = geometry.beads.contact_load if stress_force is None else float(stress_force)
    require(math.isfinite(force) and force > 0, f"stress_force must be > 0 N, got {force}")
    law = law_for_steel(geometry.steel) if law is None else law
    from msens.progress import heartbeat, stopwatch, timed

    elapsed = stopwatch()
    _log.info("transducers: field mesh and nonlinear bias solve")
    with heartbeat(_log, "transducers: mesh and bias solve"), \
            timed(_log, "transducers: mesh and bias solve"):
        sol, path = bias_solution(geometry, options=options, store=store, max_iter=max_iter)
    _log.info("transducers: bead stress, Villari and contact-approach sources, their "
              "potentials (%d dofs)", sol.dofs)
    with heartbeat(_log, "transducers: sources and their potentials"):
        model = mechanism_potentials(sol, geometry, stress_force=force, law=law,
                                     material=material, approach=approach)
    with timed(_log, "transducers: magnetic forces"):
        pforce = particle_forces(sol, geometry)

    key = cache_key(geometry, options, stress_force=force, law=law, material=material,
                    approach=approach)
    src = (f"msens.magnetics {TRANSDUCER_VERSION}: Villari (JAS law, stress at {force:.4g} N)"
           f" + contact approach, source potentials; field mesh {path.name}; key {key}")
    stiffness = hertz_stiffness(geometry.beads.radius, material)
    out: dict[int, Transducer] = {}
    details: dict = {"key": key, "mesh": path.name, "elements": sol.problem.mesh.n_elements,
                     "dofs": sol.dofs, "newton_iterations": sol.iterations,
                     "stress_force_N": force,
                     "approach_rate_m_per_N": hertz_approach_rate(
                         force, geometry.beads.radius, material), "coils": {}}
    for unit in geometry.iter_units():
        coil = unit.coil
        with timed(_log, f"transducers: coil {coil.particle}"):
            link = coil_linkage(model, coil)
            contacts, s_vil, dl = model.contact_profiles(link)
            inductance, err = adjoint_check(model, coil, link)
            offsets, vil_o, app_o = offset_profiles(model, geometry, coil)
        out[coil.particle] = Transducer(
            particle=coil.particle, contacts=contacts, sensitivity_villari=s_vil,
            dlambda_dapproach=dl, contact_stiffness=stiffness, reference_force=force,
            magnetic_particle_force=pforce, resistance_ohm=coil_resistance(coil),
            inductance_H=inductance, turns=coil.turns, source=src, offsets=offsets,
            villari_by_offset=vil_o, approach_by_offset=app_o)
        details["coils"][str(coil.particle)] = {
            "particles": model.particles.tolist(),
            "bead_sensitivity_Wb_per_N": link[:model.particles.size].tolist(),
            "reciprocity_adjoint_rel_error": err}
    _log.info("transducers: computed in %.1f s", elapsed())
    return TransducerReport(out, details, bias=sol)


def cache_key(geometry: SensorGeometry, options: MeshOptions | None = None, *,
              stress_force: float, law: JilesAthertonSablik, material: ElasticMaterial,
              approach: bool) -> str:
    """Content hash (16 hex digits) of everything a transducer set depends on.

    The mesh key leaves out the materials (the steel's B–H curve, the magnets' grade,
    remanence and recoil permeability); they enter here.
    """
    return content_key({"version": TRANSDUCER_VERSION, "mesh": geometry_key(geometry, options),
                        **model_payload(geometry, stress_force=stress_force, law=law,
                                        material=material, approach=approach)}, 16)


def model_payload(geometry: SensorGeometry, *, stress_force: float,
                  law: JilesAthertonSablik, material: ElasticMaterial, approach: bool) -> dict:
    """What a transducer set depends on besides its mesh (:func:`cache_key`): the loads,
    laws and materials, as canonical JSON values."""
    magnets = [None if u.magnet is None else
               [u.magnet.grade, repr(float(u.magnet.remanence)),
                repr(float(u.magnet.recoil_permeability))] for u in geometry.sensors]
    payload = {"stress_force": repr(float(stress_force)), "law": _canonical(law),
               "material": _canonical(material), "approach": bool(approach),
               "magnets": magnets}
    if not geometry.default_steel:
        payload["steel_bh"] = {"b": _canonical(geometry.steel.b),
                               "h": _canonical(geometry.steel.h)}
    if geometry.reversibility != 1.0:
        payload["reversibility"] = repr(float(geometry.reversibility))
    return payload


__all__ = [
    "MECHANISMS",
    "TRANSDUCER_VERSION",
    "Mechanism",
    "Transducer",
    "TransducerReport",
    "bias_solution",
    "cache_key",
    "compute_transducers",
    "magnetic_precompression",
    "model_payload",
    "particle_forces",
]

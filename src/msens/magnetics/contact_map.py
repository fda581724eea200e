"""Nonlinear contact map Λ_c(δ): a contact's flux linkage from its open gap to peak approach.

The contact-approach sources (:mod:`msens.magnetics.approach`) linearise Λ about the static
contact. Over a pulse a contact's approach δ runs from an open gap (δ < 0) to the peak
approach, and when it opens the steel bridge through its flat is lost: this module tabulates
Λ_c(δ) from full nonlinear solves, on ONE mesh per contact so that states differ by morphing
and material alone (re-meshing noise, ~1e-4 of Λ, would swamp the effect).

The mesh (:attr:`msens.field.geometry.BeadChain.contact_layer`) has a thin disc of height h0
between contact c's flats (radius a, the Hertz flat at the geometry's contact load, approach
δ_s = 2a²/R). Every state moves the beads above c rigidly toward the wall by δ − δ_s (the
uniform wedge closing of :mod:`msens.magnetics.approach`); the disc is

- ``"steel"`` (closed): its height is morphed to :data:`CLOSED_THICKNESS` and bead c+1's flat
  moves with the beads above, exactly as the approach morph of the plain mesh: the closed
  branch IS the existing model (plus a steel disc 1 nm high);
- ``"air"`` (open): bead c+1 stays, so the disc is an air gap of height δ_s − δ between the
  flats.

The model's flat radius is fixed, while a real Hertz contact's flat shrinks to nothing as
δ → 0 (a² = Rδ/2). A saturated bridge carries flux in proportion to its area, i.e. to δ, so
between 0 and δ_s the map blends the branches by that area fraction:

    Λ(δ) = Λ_air(δ)                                   δ ≤ 0
    Λ(δ) = Λ_air(δ) + (δ/δ_s) (Λ_steel(δ) − Λ_air(δ))  0 < δ < δ_s
    Λ(δ) = Λ_steel(δ)                                 δ ≥ δ_s

continuous at 0 and δ_s (an ASSUMPTION of the fixed-flat model, stated wherever the map is
used). The tables hold each branch at a few approaches (a cubic spline in δ for the steel
branch, PCHIP in the gap for the air branch).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Literal

import numpy as np
from scipy.interpolate import CubicSpline, PchipInterpolator

from msens.errors import internal, require
from msens.field.build import MeshOptions
from msens.field.geometry import SensorGeometry
from msens.field.parts import Coil
from msens.field.probes import P2Field
from msens.field.regions import NonlinearSoft
from msens.field.sensor_model import bias_problem, load_mesh, shell_function
from msens.field.solve import FieldSolution, MagnetostaticProblem, solve
from msens.magnetics.approach import _morphed_quadrature
from msens.magnetics.potentials import nonlinear_resolve
from msens.magnetics.villari import dof_flux_linkage
from msens.parallel import default_workers, pools_allowed, run_tasks
from msens.store import Store, content_key

_log = logging.getLogger(__name__)

State = Literal["steel", "air"]

#: Height of the closed (steel) disc after morphing, m: 1 nm, a thousandth of the smallest
#: open gap tabulated; the closed branch is the plain approach model to O(1 nm) of approach.
CLOSED_THICKNESS = 1e-9

#: Height of the disc in the mesh, as a fraction of the flat radius (the states morph it).
LAYER_FRACTION = 0.05

#: Closed-branch table nodes, approach δ in m: 0 to beyond the peak approach of the main
#: study (1.6–2.1 µm at 10–16 N).
STEEL_NODES: tuple[float, ...] = (0.0, 0.5e-6, 1.0e-6, 1.5e-6, 2.0e-6, 2.5e-6)
#: Open-branch table nodes, gap δ_s − δ between the flats in m: up to beyond the main study's
#: most negative approach near a coil (−11.2 µm at contact 10).
AIR_GAPS: tuple[float, ...] = (1e-9, 0.05e-6, 0.2e-6, 0.5e-6, 1e-6, 2e-6, 4e-6, 6e-6, 9e-6,
                               13e-6, 18e-6)
#: Version of the tables' content; part of the cache key.
MAP_VERSION = "contact-map/1"


def static_approach(geometry: SensorGeometry) -> float:
    """δ_s = 2a²/R of the model's flat (Hertz: a² = R*δ with R* = R/2), m."""
    b = geometry.beads
    return 2.0 * b.flat_radius**2 / b.radius


def layer_geometry(geometry: SensorGeometry, contact: int) -> SensorGeometry:
    """``geometry`` with a disc of height :data:`LAYER_FRACTION` × a between contact
    ``contact``'s flats (the beads above it lifted by that height)."""
    b = geometry.beads
    require(b.contact_layer is None, "geometry already has a contact layer")
    return replace(geometry, beads=replace(
        b, contact_layer=(int(contact), LAYER_FRACTION * b.flat_radius)))


@dataclass(frozen=True)
class LayerModel:
    """Bias solutions of one contact's layer mesh with the disc steel and air.

    Attributes
    ----------
    geometry : SensorGeometry
        With the contact layer.
    steel, air : FieldSolution
        Nonlinear bias solutions (the disc filled with the beads' steel / with air).
    """

    geometry: SensorGeometry
    steel: FieldSolution
    air: FieldSolution

    @property
    def contact(self) -> int:
        """The layered contact (its upper particle)."""
        return int(self.geometry.beads.contact_layer[0])

    def solution(self, state: State) -> FieldSolution:
        """The bias solution of ``state``."""
        require(state in ("steel", "air"), f"state must be 'steel' or 'air', got {state!r}")
        return self.steel if state == "steel" else self.air


def layer_model(geometry: SensorGeometry, contact: int, options: MeshOptions | None = None,
                store: Store | None = None, start: P2Field | None = None
                ) -> LayerModel:
    """Mesh ``geometry`` with a layer at ``contact`` and solve its bias with the disc steel
    and with it air; Newton starts from ``start`` (the plain mesh's bias of ``geometry``,
    optional: about half the iterations) and the air disc's from the steel disc's. The
    layer mesh comes from ``store`` (default :meth:`msens.store.Store.default`)."""
    lg = layer_geometry(geometry, contact)
    axi, _ = load_mesh(lg, options, store)
    air = bias_problem(lg, axi)
    name = lg.beads.layer_rect().name
    steel_regions = dict(air.regions)
    steel_regions[name] = NonlinearSoft(lg.steel, reversibility=lg.reversibility)
    steel = solve(MagnetostaticProblem(axi, steel_regions), max_iter=40, tol=1e-11,
                  start=start)
    # the disc (5 % of the flat radius thick) barely moves the field: Newton from steel.a
    return LayerModel(lg, steel, solve(air, max_iter=40, tol=1e-11, initial=steel.a))


def _layer_weights(sol: FieldSolution, geometry: SensorGeometry) -> tuple[np.ndarray,
                                                                          np.ndarray]:
    """(vertices of the disc, their height fraction (z − z_bottom)/h0 in [0, 1])."""
    axi = sol.problem.mesh
    q = geometry.beads.layer_rect()
    v = np.unique(axi.mesh.t[:, axi.subdomains[q.name]])
    w = (axi.mesh.p[1, v] - q.z0) / (q.z1 - q.z0)
    internal(bool(np.all((w > -1e-6) & (w < 1 + 1e-6))), "internal: disc vertex off the disc")
    return v, np.clip(w, 0.0, 1.0)


def state_points(model: LayerModel, state: State, delta: float,
                 others: Mapping[int, float] | None = None) -> np.ndarray:
    """Vertex coordinates of a contact state on the layer mesh, shape (2, n_vertices), m.

    Parameters
    ----------
    model : LayerModel
    state : {"steel", "air"}
    delta : float
        Approach δ of the layered contact, m (air: δ < δ_s).
    others : mapping of int -> float, optional
        Approaches of other contacts, m, as the plain approach morph (the beads above each
        move rigidly; the disc moves with them when it is above).
    """
    sol = model.solution(state)
    g = model.geometry
    b = g.beads
    k = model.contact
    h0 = b.contact_layer[1]
    move = delta - static_approach(g)  # toward the wall, both branches
    if state == "steel":
        top, bottom = h0 - CLOSED_THICKNESS + move, move
    else:
        gap = -move
        require(gap >= 0.5 * CLOSED_THICKNESS,  # half: rounding of δ_s − (δ_s − gap)
                f"open state needs δ < δ_s - {CLOSED_THICKNESS} m, got δ = {delta} m")
        top, bottom = h0 - gap, 0.0
    p = sol.problem.mesh.mesh.p.copy()
    above = shell_function(sol, [f"bead_{q}" for q in range(b.first, k + 1)], layers=0)
    disc, w = _layer_weights(sol, g)
    shift = top * above
    shift[disc] = bottom + w * (top - bottom)
    for c, d in (others or {}).items():
        require(b.first <= c < b.last and c != k,
                f"contact {c} is not a plain modelled contact of this layer mesh")
        bodies = [f"bead_{q}" for q in range(b.first, c + 1)]
        phi = shell_function(sol, bodies, layers=0)
        if c > k:
            phi[disc] = 1.0
        shift += d * phi
    p[1] -= shift
    return p


def state_fluxes(model: LayerModel, state: State, delta: float, coils: Sequence[Coil],
                 others: Mapping[int, float] | None = None, *, tol: float = 1e-12,
                 max_iter: int = 30) -> np.ndarray:
    """Flux linkage Λ of each coil in a contact state by one full nonlinear re-solve, Wb,
    shape (n_coils,)."""
    sol, a = state_potential(model, state, delta, others, tol=tol, max_iter=max_iter)
    return np.array([dof_flux_linkage(sol, a, c) for c in coils])


def state_potential(model: LayerModel, state: State, delta: float,
                    others: Mapping[int, float] | None = None, *, tol: float = 1e-12,
                    max_iter: int = 30, start: np.ndarray | None = None
                    ) -> tuple[FieldSolution, np.ndarray]:
    """The bias potential of a contact state by one full nonlinear re-solve: the layer
    model's solution of ``state`` and the dofs A_φ (T m, shape (n_dofs,)) on its morphed
    mesh (coils, magnets and the air around them are not morphed). Newton starts from the
    bias solution of ``state``, or from ``start`` (a nearby state's dofs)."""
    sol = model.solution(state)
    q = _morphed_quadrature(sol, state_points(model, state, delta, others))
    return sol, nonlinear_resolve(sol, q, tol=tol, max_iter=max_iter, start=start)


def _branch_fluxes(model: LayerModel, state: State, deltas: Sequence[float],
                   coils: Sequence[Coil], **kw) -> np.ndarray:
    """:func:`state_fluxes` of one branch at ``deltas`` in turn, each Newton solve starting
    from the previous state (neighbouring table nodes: about a quarter fewer iterations
    than from the bias solution, the same fluxes to 1e-17 Wb), shape (n, n_coils)."""
    out, a = [], None
    for d in deltas:
        sol, a = state_potential(model, state, d, start=a, **kw)
        out.append([dof_flux_linkage(sol, a, c) for c in coils])
    return np.array(out)


def state_flux(model: LayerModel, state: State, delta: float, coil: Coil,
               others: Mapping[int, float] | None = None, **kw) -> float:
    """Coil flux linkage Λ of a contact state by a full nonlinear re-solve, Wb."""
    return float(state_fluxes(model, state, delta, [coil], others, **kw)[0])


def bridge_share(delta: np.ndarray, delta_static: float) -> np.ndarray:
    """Weight of the steel branch: clip(δ/δ_s, 0, 1) (the Hertz flat's area fraction)."""
    return np.clip(np.asarray(delta, dtype=float) / delta_static, 0.0, 1.0)


def contact_flux(model: LayerModel, delta: float, coil: Coil,
                 others: Mapping[int, float] | None = None, **kw) -> float:
    """Λ(δ) of the blended contact model by full nonlinear solves (one or two), Wb."""
    ds = static_approach(model.geometry)
    s = float(bridge_share(delta, ds))
    steel = state_flux(model, "steel", delta, coil, others, **kw) if s > 0 else 0.0
    # gaps below the closed disc's height take its value, as the table does
    air = (state_flux(model, "air", min(delta, ds - CLOSED_THICKNESS), coil, others, **kw)
           if s < 1 else 0.0)
    return air + s * (steel - air)


@dataclass(frozen=True)
class ContactMap:
    """Tabulated Λ_c(δ) − Λ_c(δ_s) of one contact seen by one coil.

    Attributes
    ----------
    contact : int
    delta_static : float
        δ_s of the model's flat, m.
    steel_delta, steel_flux : ndarray, shape (n_s,)
        Closed-branch approaches (m, increasing, first ≤ 0) and Λ_steel − Λ_steel(δ_s) (Wb).
    air_gap, air_flux : ndarray, shape (n_a,)
        Open-branch gaps δ_s − δ between the flats (m, increasing, first =
        :data:`CLOSED_THICKNESS`) and Λ_air − Λ_steel(δ_s) (Wb).
    """

    contact: int
    delta_static: float
    steel_delta: np.ndarray
    steel_flux: np.ndarray
    air_gap: np.ndarray
    air_flux: np.ndarray

    def __post_init__(self) -> None:
        internal(np.shape(self.steel_delta) == np.shape(self.steel_flux)
                 and np.shape(self.air_gap) == np.shape(self.air_flux)
                 and len(self.steel_delta) >= 2 and len(self.air_gap) >= 2,
                 "internal: contact map tables of unequal or too few points")

    @property
    def delta_range(self) -> tuple[float, float]:
        """(most negative, largest) approach the tables cover, m."""
        return (self.delta_static - float(self.air_gap[-1]), float(self.steel_delta[-1]))

    @cached_property
    def _steel_spline(self) -> CubicSpline:
        return CubicSpline(np.asarray(self.steel_delta), np.asarray(self.steel_flux),
                           bc_type="natural")

    @cached_property
    def _air_pchip(self) -> PchipInterpolator:
        return PchipInterpolator(np.asarray(self.air_gap), np.asarray(self.air_flux))

    @cached_property
    def _end_slopes(self) -> tuple[float, float, float]:
        """The branches' slopes where they are extrapolated linearly: the closed branch's
        at its first and last node, the open branch's at its largest gap."""
        x, g = np.asarray(self.steel_delta), np.asarray(self.air_gap)
        return (float(self._steel_spline(x[0], 1)), float(self._steel_spline(x[-1], 1)),
                float(self._air_pchip(g[-1], 1)))

    def steel(self, delta: np.ndarray) -> np.ndarray:
        """Closed branch, Wb (cubic spline; linear extrapolation beyond the table)."""
        x = np.asarray(self.steel_delta)
        d = np.asarray(delta, dtype=float)
        lo, hi = x[0], x[-1]
        slope_lo, slope_hi, _ = self._end_slopes
        out = self._steel_spline(np.clip(d, lo, hi))
        out = np.where(d > hi, out + slope_hi * (d - hi), out)
        return np.where(d < lo, out + slope_lo * (d - lo), out)

    def air(self, delta: np.ndarray) -> np.ndarray:
        """Open branch, Wb (PCHIP in the gap, exact for linear data; linear extrapolation
        beyond the largest gap, the first node's value below the smallest)."""
        x = np.asarray(self.air_gap)
        gap = np.maximum(self.delta_static - np.asarray(delta, dtype=float), float(x[0]))
        out = self._air_pchip(np.minimum(gap, x[-1]))
        return np.where(gap > x[-1], out + self._end_slopes[2] * (gap - x[-1]), out)

    def __call__(self, delta: np.ndarray) -> np.ndarray:
        """Λ(δ) − Λ(δ_s), Wb, same shape as ``delta`` (m)."""
        s = bridge_share(delta, self.delta_static)
        air = self.air(delta)
        return air + s * (self.steel(delta) - air)

    def slope(self, delta: np.ndarray) -> np.ndarray:
        """dΛ/dδ by a central difference of :meth:`__call__` (1 nm), Wb/m."""
        d = np.asarray(delta, dtype=float)
        h = 1e-9
        return (self(d + h) - self(d - h)) / (2 * h)

    @cached_property
    def static_slope(self) -> float:
        """dΛ_steel/dδ at δ_s, Wb/m: the closed branch's slope at the static contact (the
        map's linearisation, which the plain mesh's approach source also gives)."""
        return float(self._steel_spline(self.delta_static, 1))


@dataclass(frozen=True)
class ApproachMap:
    """The static nonlinearity of one coil's contact approaches (a Hammerstein model's
    static part): the contact maps of some of its contacts.

    The linear transducer reads an approach δ through ∂Λ/∂δ_c (static, or D_c(ω) with eddy
    currents). A mapped contact instead feeds it the equivalent approach

        δ̃_c = δ_s + (Λ_c(δ_c) − Λ_c(δ_s)) / Λ_c'(δ_s),

    the map's shape with unit slope at the field model's static contact (closed side,
    :attr:`ContactMap.static_slope`): there small signals read the linear sources exactly,
    and the maps add the nonlinearity of large ones. Its scale is the reading coil's own
    sensitivity, whatever the coil or the small-signal permeability (the maps come from full
    nonlinear solves, which do not depend on it). On the differential permeability the two
    slopes (two meshes) agree within 1 % at the main study's mapped contacts, except contact
    20 read by coil 13 (3.5 %; ``python benchmarks/contact_map_transfer.py``).

    Attributes
    ----------
    maps : tuple of ContactMap
    """

    maps: tuple[ContactMap, ...]

    @property
    def contacts(self) -> tuple[int, ...]:
        """The mapped contacts."""
        return tuple(m.contact for m in self.maps)

    def equivalent(self, delta: np.ndarray, contacts: np.ndarray) -> np.ndarray:
        """Equivalent approaches δ̃, m, same shape as ``delta``.

        Parameters
        ----------
        delta : ndarray, shape (..., n_c)
            Approaches of ``contacts``, m (unmapped contacts pass through).
        contacts : ndarray of int, shape (n_c,)
        """
        d = np.asarray(delta, dtype=float)
        out = d.copy()
        contacts = np.asarray(contacts)
        for m in self.maps:
            k = np.flatnonzero(contacts == m.contact)
            slope = m.static_slope
            if k.size and slope != 0.0:
                out[..., k[0]] = m.delta_static + m(d[..., k[0]]) / slope
        return out


def contact_maps(model: LayerModel, coils: Sequence[Coil],
                 steel_delta: Sequence[float] = STEEL_NODES,
                 air_gap: Sequence[float] = AIR_GAPS, **kw) -> tuple[ContactMap, ...]:
    """Tabulate one contact's map for each coil by full nonlinear solves on its layer mesh
    (one solve per node serves every coil).

    Parameters
    ----------
    model : LayerModel
    coils : sequence of Coil
    steel_delta : sequence of float
        Approaches of the closed branch, m (increasing; cover 0 to the peak approach).
    air_gap : sequence of float
        Gaps δ_s − δ of the open branch, m (increasing; the first is replaced by
        :data:`CLOSED_THICKNESS`; cover up to δ_s − the most negative δ).

    Returns
    -------
    tuple of ContactMap, one per coil
    """
    sd = np.asarray(steel_delta, dtype=float)
    ag = np.asarray(air_gap, dtype=float).copy()
    require(bool(np.all(np.diff(sd) > 0) and np.all(np.diff(ag) > 0)),
            "contact map nodes must increase")
    ag[0] = CLOSED_THICKNESS
    ds = static_approach(model.geometry)
    steel = _branch_fluxes(model, "steel", [ds, *sd], coils, **kw)
    ref = steel[0]
    steel = steel[1:] - ref
    air = _branch_fluxes(model, "air", ds - ag, coils, **kw) - ref
    return tuple(ContactMap(model.contact, ds, sd, steel[:, i], ag, air[:, i])
                 for i in range(len(coils)))


def contact_map(model: LayerModel, coil: Coil, steel_delta: Sequence[float] = STEEL_NODES,
                air_gap: Sequence[float] = AIR_GAPS, **kw) -> ContactMap:
    """:func:`contact_maps` of one coil."""
    return contact_maps(model, [coil], steel_delta, air_gap, **kw)[0]


# ----------------------------------------------------------------------------- per geometry

def mapped_contacts(geometry: SensorGeometry,
                    particles: Sequence[int] | None = None) -> tuple[int, ...]:
    """Contacts that get a map: the six around each coil's particle p (p − 3 .. p + 2, the
    span of its bias magnet's pole pieces and one beyond), within the modelled chain; of
    the coils at ``particles`` (default: every coil)."""
    b = geometry.beads
    out = {c for u in geometry.sensors for c in range(u.coil.particle - 3, u.coil.particle + 3)
           if b.first <= c < b.last and (particles is None or u.coil.particle in particles)}
    return tuple(sorted(out))


def _map_json(m: ContactMap) -> dict:
    return {"contact": m.contact, "delta_static_m": m.delta_static,
            "steel_delta_m": m.steel_delta.tolist(), "steel_flux_Wb": m.steel_flux.tolist(),
            "air_gap_m": m.air_gap.tolist(), "air_flux_Wb": m.air_flux.tolist()}


def _map_from_json(d: dict) -> ContactMap:
    return ContactMap(int(d["contact"]), float(d["delta_static_m"]),
                      np.array(d["steel_delta_m"]), np.array(d["steel_flux_Wb"]),
                      np.array(d["air_gap_m"]), np.array(d["air_flux_Wb"]))


def _contact_task(args: tuple) -> tuple[ContactMap, ...]:
    """One contact's maps for every coil (a worker task: layer mesh, bias, table solves)."""
    geometry, contact, coils, options, store, start = args
    return contact_maps(layer_model(geometry, contact, options, store, start), coils)


def approach_maps(geometry: SensorGeometry, transducer_key: str, *,
                  options: MeshOptions | None = None, store: Store | None = None,
                  workers: int | Callable | None = None,
                  particles: Sequence[int] | None = None,
                  start: P2Field | None = None, refresh: bool = False
                  ) -> dict[int, ApproachMap]:
    """The contact maps of every coil of ``geometry`` (artifact ``contact-map-<key>.json``).

    The key joins the transducer key (mesh, steel, magnets) and the table nodes. ``store``
    (default :meth:`msens.store.Store.default`) finds and verifies them among the committed
    artifacts, then in the user cache, where new maps (and the layer meshes) are written. Cold:
    one layer mesh and 18 nonlinear solves per contact of :func:`mapped_contacts` (about
    12 s each on a core for the default geometry), the contacts spread over ``workers`` local
    processes (:func:`msens.parallel.run_tasks`; default: one per CPU under the ``msens``
    command, else one, :func:`msens.parallel.pools_allowed`), or over a map-like ``workers``
    callable ``workers(fn, iterable)`` that a workflow hands in (e.g.
    :class:`msens.parallel.TaskMap` on a Dask cluster). ``particles``: the maps of those coils
    only, of their own contacts when solved; a cached table of every coil serves them too
    (then with all its contacts, as ``msens run`` reads them). ``start``: the bias of
    ``geometry`` on its plain mesh, where the layer meshes' Newton solves begin (the same
    maps, about 1 s less per contact). ``refresh`` solves them again (and overwrites the
    user cache's table; a committed table is never written).

    Returns
    -------
    dict of int -> ApproachMap
        Keyed by coil particle.
    """
    store = Store.default() if store is None else store

    def map_key(subset: Sequence[int] | None) -> str:
        payload = {} if subset is None else {"coils": sorted(subset)}
        return content_key(
            {"version": MAP_VERSION, "transducer": transducer_key, **payload,
             "contacts": list(mapped_contacts(geometry, subset)),
             "steel_nodes": list(STEEL_NODES), "air_gaps": list(AIR_GAPS),
             "layer": LAYER_FRACTION, "closed": CLOSED_THICKNESS}, 16)

    if particles is not None and {u.coil.particle for u in geometry.sensors} <= set(particles):
        particles = None  # every coil: the same table as without a selection
    coils = [u.coil for u in geometry.iter_units()
             if particles is None or u.coil.particle in particles]
    contacts = mapped_contacts(geometry, particles)
    key = map_key(None if particles is None else [c.particle for c in coils])
    # the maps of every coil hold those of a few (same contacts, same solves)
    keys = [key] if particles is None else [key, map_key(None)]
    data = None if refresh else store.read_json(*(f"contact-map-{k}.json" for k in keys))
    if data is not None:
        return {int(p): ApproachMap(tuple(_map_from_json(m) for m in maps))
                for p, maps in data["coils"].items()
                if particles is None or int(p) in particles}
    if workers is None:
        # only where a pool is safe: the msens command, not a worker or a user's script
        workers = default_workers() if pools_allowed() else 1
    at_a_time = ("on the caller's workers" if callable(workers)
                 else f"{min(workers, len(contacts))} at a time")
    _log.info("contact maps %s (cached: no): %d contacts, a layer mesh and 18 nonlinear "
              "solves each, %s", key, len(contacts), at_a_time)
    from msens.progress import heartbeat, stopwatch

    elapsed = stopwatch()
    tasks = [(geometry, c, coils, options, store, start) for c in contacts]
    per_contact: dict[int, tuple[ContactMap, ...]] = {}

    with heartbeat(_log, f"contact maps {key}"):  # each map takes a minute or more
        if callable(workers):
            per_contact = dict(zip(contacts, workers(_contact_task, tasks), strict=True))
            _log.info("contact maps: %d after %.0f s", len(per_contact), elapsed())
        else:
            for i, maps in run_tasks(_contact_task, tasks, workers=workers):
                per_contact[contacts[i]] = maps
                _log.info("contact map %d/%d (contact %d) after %.0f s", len(per_contact),
                          len(contacts), contacts[i], elapsed())
    tables = {coil.particle: [per_contact[c][k] for c in contacts]
              for k, coil in enumerate(coils)}
    data = {"key": key, "version": MAP_VERSION, "transducer": transducer_key,
            "coils": {str(p): [_map_json(m) for m in ms] for p, ms in tables.items()}}
    store.write_json(f"contact-map-{key}.json", data, optional=True)
    return {p: ApproachMap(tuple(ms)) for p, ms in tables.items()}


__all__ = ["AIR_GAPS", "CLOSED_THICKNESS", "LAYER_FRACTION", "MAP_VERSION", "STEEL_NODES",
           "ApproachMap", "ContactMap", "LayerModel", "approach_maps", "bridge_share",
           "contact_flux", "contact_map", "contact_maps", "layer_geometry", "layer_model",
           "mapped_contacts", "state_flux", "state_fluxes", "state_points", "state_potential",
           "static_approach"]

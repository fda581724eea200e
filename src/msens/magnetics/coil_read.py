"""A changed coil read from the field model of another coil: no new mesh, solve or maps.

The pick-up coil is copper in air. It does not change the bias state, the magnets' pull, the
incremental potentials of the Villari and contact-approach sources, or the shape of the
nonlinear contact maps; only which part of those potentials the winding links. So a sensor's
field model is keyed on everything but its coils (:func:`coil_free_key`). Two artifacts of
the store serve a changed coil:

- ``coil-model-<key>.json`` (:func:`write_model`): which coils the field model of that key
  was solved with, and their incremental inductances; written whenever a transducer set is
  computed or read, so a default run leaves it behind;
- ``coil-table-<key>-<particle>.npz`` (:func:`write_tables`, :class:`CoilTables`): for one
  coil, a summed-area table (:mod:`msens.magnetics.potentials`) of every source's flux per
  unit area over the coil's window (:func:`coil_window`: the air between the tube and the
  magnet's ring, between its pole pieces, plus the offset span) and the window's
  :class:`InductanceGrid`; built the first time that coil changes, from the solved coils'
  mesh (a bias solve, the sources and about 1,600 tangent solves: half a minute), then kept
  in the user cache. The main study's are committed, truncated (:func:`write_tables` with
  ``rank_tol``), so its first coil change reads them too.

A geometry that differs from a stored one only in its coils is then read
(:func:`read_coil`), the way a coil sweep reads its designs (:mod:`msens.design.coil_sweep`):

- sensitivities ∂Λ/∂F_c, ∂Λ/∂δ_c and the offset profiles: table quadrature over the new
  winding (bilinear summed-area table, 0.1 mm grid: < 1e-4 of exact mesh quadrature);
- R: the new winding's DC resistance (:func:`msens.field.sensor_model.coil_resistance`);
- L: the solved coil's incremental inductance (field model, steel at its small-signal
  permeability) times the ratio of the two windings' inductance-grid quadratures
  (:meth:`CoilTables.inductance`);
- the magnets' pull, contact stiffness and contact maps: the solved coil's (the maps read
  through the new coil's sensitivities, as
  :meth:`~msens.magnetics.transducer.Transducer.reading_maps_of` carries them).

A full rebuild differs by the new mesh's discretisation; ``python benchmarks/coil_read.py``
measures by how much on the main study.
"""

from __future__ import annotations

import io
import logging
from dataclasses import asdict, dataclass, replace

import numpy as np

from msens.errors import internal
from msens.field.cache import canonical
from msens.field.geometry import SensorGeometry
from msens.field.parts import SensorUnit
from msens.field.sensor_model import coil_resistance
from msens.field.solve import FieldSolution
from msens.magnetics.low_rank import expand_symmetric, rows_svd, symmetric_eig
from msens.magnetics.mechanisms import (
    OFFSET_SPAN,
    OFFSET_STEP,
    MechanismPotentials,
    contact_profiles,
    offset_grid,
)
from msens.magnetics.potentials import LinkageTable, linkage_table, rect_integral
from msens.readout.coil import Coil, Wire
from msens.store import Store, content_key

_log = logging.getLogger(__name__)

#: Version of the coil-table artifacts; part of their key.
COIL_TABLE_VERSION = "coil-table/1"
#: Grid spacing of the tables, m (rectangle integrals converge as spacing²).
SPACING = 0.1e-3
#: Cell size of the inductance grid, m (a winding's L from it is used as a ratio to the
#: solved coil's; 0.25 mm: within 8e-4 of the changed geometry's own field model in
#: tests/magnetics/test_coil_read.py, 0.5 mm: 2.5e-3).
L_CELL = 0.25e-3
#: Grid points solved per block (bounds the memory of the block's potentials).
L_BLOCK = 200


def coil_free_key(transducer_payload: dict, geometry: SensorGeometry) -> str:
    """Content key of a transducer set's inputs with the coils left out (their particles
    stay: they decide which beads and contacts carry sources and where the mesh is graded).

    Parameters
    ----------
    transducer_payload : dict
        What :func:`msens.magnetics.transducer.cache_key` hashes, without its ``mesh`` entry.
    geometry : SensorGeometry
    """
    geo = canonical(geometry)
    internal(isinstance(geo, dict) and "sensors" in geo,
             "internal: canonical geometry without sensors")
    sensors = [{**s, "coil": {"particle": u.coil.particle}}
               for s, u in zip(geo["sensors"], geometry.sensors, strict=True)]
    return content_key({"version": COIL_TABLE_VERSION, **transducer_payload,
                        "geometry": {**geo, "sensors": sensors}}, 16)


def table_name(key: str, particle: int) -> str:
    """The file name of the table artifact of the coil at ``particle``."""
    return f"coil-table-{key}-{int(particle)}.npz"


def coil_window(geometry: SensorGeometry, unit: SensorUnit) -> tuple[tuple[float, float],
                                                                        tuple[float, float]]:
    """Where a coil of ``unit`` may sit, m: radially from the tube to the magnet's ring (no
    magnet: twice the coil's outer radius), axially between the pole pieces (no magnet: the
    coil's centre ± its length).

    Returns
    -------
    (r0, r1), (z0, z1) : tuple of (float, float)
    """
    r0 = geometry.tube.outer_radius
    m = unit.magnet
    if m is not None:
        zc = geometry.beads.center(m.particle) + m.axial_offset
        return (r0, m.inner_radius), (zc - m.length / 2, zc + m.length / 2)
    c = unit.coil
    zc = geometry.beads.center(c.particle) + c.axial_offset
    return (r0, 2 * c.outer_radius), (zc - c.length, zc + c.length)


@dataclass(frozen=True)
class InductanceGrid:
    """The incremental mutual inductances of the cells of a coil's window.

    The window (:func:`coil_window`) is cut into cells of about :data:`L_CELL`; a unit
    azimuthal current in cell l (as a ring at its centre) gives the potential whose flux
    through cell k's centre ring is ``kernel[k, l]``: K = P K_t⁻¹ Pᵀ, with P the field
    model's P2 values at the cell centres and K_t its tangent stiffness at the bias point
    (steel at its small-signal reluctivity, magnets at their recoil permeability). A winding
    of N turns on cross-section S has L ≈ 2π (N/S)² vᵀ K v with v_k = r_k × (its overlap
    with cell k); :meth:`CoilTables.inductance` uses it as a ratio to the solved coil's.

    Attributes
    ----------
    r, z : ndarray, shapes (nr,), (nz,)
        Cell centres, m.
    kernel : ndarray, shape (nr * nz, nr * nz)
        K (r-major cell order), float32, m/H per radian.
    """

    r: np.ndarray
    z: np.ndarray
    kernel: np.ndarray

    def quadratic(self, r0, r1, z0, z1) -> np.ndarray:
        """vᵀ K v of windings [r0, r1] × [z0, z1] (m; scalars or arrays of shape (n,)),
        shape (n,): times 2π (N/S)² it is the winding's L in H. Every winding must lie in
        the grid's cells (a part outside would be left out silently).

        The weights are separable (v = a(r) ⊗ b(z)), so windings of one axial extent share
        the contraction over z: cost nr²·nz² per distinct (z0, z1), nr² per winding.
        """
        r0, r1, z0, z1 = np.broadcast_arrays(*(np.atleast_1d(np.asarray(x, dtype=float))
                                              for x in (r0, r1, z0, z1)))
        nr, nz = self.r.size, self.z.size
        k4 = self.kernel.reshape(nr, nz, nr, nz)
        hr, hz = self.r[1] - self.r[0], self.z[1] - self.z[0]
        tol = 1e-9
        internal(bool(np.all(r0 >= self.r[0] - hr / 2 - tol) and np.all(r1 <= self.r[-1]
                 + hr / 2 + tol) and np.all(z0 >= self.z[0] - hz / 2 - tol)
                      and np.all(z1 <= self.z[-1] + hz / 2 + tol)),
                 "internal: a winding outside its inductance grid")
        a = np.clip(np.minimum(self.r + hr / 2, r1[:, None])
                    - np.maximum(self.r - hr / 2, r0[:, None]), 0.0, None) * self.r
        out = np.empty(r0.size)
        spans, inverse = np.unique(np.stack([z0, z1], axis=1), axis=0, return_inverse=True)
        for k, (lo, hi) in enumerate(spans):
            b = np.clip(np.minimum(self.z + hz / 2, hi) - np.maximum(self.z - hz / 2, lo),
                        0.0, None)
            m = np.einsum("j,ijkl,l->ik", b, k4, b, optimize=True)
            rows = np.flatnonzero(inverse.ravel() == k)
            out[rows] = np.einsum("ni,ik,nk->n", a[rows], m, a[rows])
        return out


def scaled_inductance(grid: InductanceGrid, inductance_H: float, solved: Coil, rects,
                      turns, area, solved_rect) -> np.ndarray:
    """Incremental inductances of windings from a solved coil's, H, shape (n,).

    L = L_solved × [q (N/S)²] / [q_solved (N_solved/S_solved)²] with q the windings'
    :meth:`InductanceGrid.quadratic`: the field model's L of the solved coil (exact mesh
    quadrature) carried to the others by the steel-aware cell kernel; the grid's own
    quadrature error cancels to first order in the ratio.

    Parameters
    ----------
    grid : InductanceGrid
    inductance_H : float
        The solved coil's incremental inductance, H.
    solved : Coil
        The solved coil.
    rects : tuple of ndarray
        (r0, r1, z0, z1) of the windings, m, each shape (n,).
    turns, area : ndarray, shape (n,)
        Their turns and cross-sections, m².
    solved_rect : Rect
        The solved coil's winding rectangle.
    """
    q = grid.quadratic(*rects) * (np.asarray(turns, dtype=float) / np.asarray(area)) ** 2
    q0 = float(grid.quadratic(solved_rect.r0, solved_rect.r1, solved_rect.z0,
                              solved_rect.z1)[0]) * (solved.turns / solved.area) ** 2
    return inductance_H * q / q0


def inductance_grid(sol: FieldSolution, operator, geometry: SensorGeometry,
                    unit: SensorUnit, extent=None) -> InductanceGrid:
    """The :class:`InductanceGrid` of a unit's coil window on a field model.

    Parameters
    ----------
    sol : FieldSolution
        The bias solution.
    operator : TangentOperator
        Its factorised tangent stiffness (:class:`msens.magnetics.potentials.TangentOperator`).
    geometry : SensorGeometry
    unit : SensorUnit
    extent : ((float, float), (float, float)), optional
        (r, z) ranges, m, that the grid must cover besides the window and the unit's coil
        (a sweep's designs).
    """
    from msens.field.probes import p2_probes

    (r0, r1), (z0, z1) = coil_window(geometry, unit)
    rect = geometry.coil_rect(unit)
    r1, z0, z1 = max(r1, rect.r1), min(z0, rect.z0), max(z1, rect.z1)
    if extent is not None:
        (er0, er1), (ez0, ez1) = extent
        r0, r1, z0, z1 = min(r0, er0), max(r1, er1), min(z0, ez0), max(z1, ez1)
    nr, nz = (max(2, int(np.ceil((b - a) / L_CELL))) for a, b in ((r0, r1), (z0, z1)))
    r = r0 + (np.arange(nr) + 0.5) * (r1 - r0) / nr
    z = z0 + (np.arange(nz) + 0.5) * (z1 - z0) / nz
    rr, zz = np.meshgrid(r, z, indexing="ij")
    kernel = operator.probe_kernel(p2_probes(sol.basis, rr.ravel(), zz.ravel()),
                                   block=L_BLOCK, dtype=np.float32)
    return InductanceGrid(r=r, z=z, kernel=kernel)


@dataclass(frozen=True)
class CoilTables:
    """What changed coils need from one field model (some or all of its coils).

    Attributes
    ----------
    tables : dict of int -> LinkageTable
        Per coil particle: every source's flux per unit area, summed over its window (plus
        the offset span), Wb per unit source.
    particles : ndarray of int, shape (n_b,)
        Beads with a Villari source.
    approach_contacts : ndarray of int, shape (n_a,)
        Contacts with an approach source.
    count : int
        Particles in the chain.
    coils : dict of int -> Coil
        The coils the tables' field model was solved with (their transducers are stored).
    inductance_H : dict of int -> float
        Those coils' incremental inductances at the bias point, H.
    grids : dict of int -> InductanceGrid
        Per coil particle: the mutual inductances of its window's cells.
    """

    tables: dict[int, LinkageTable]
    particles: np.ndarray
    approach_contacts: np.ndarray
    count: int
    coils: dict[int, Coil]
    inductance_H: dict[int, float]
    grids: dict[int, InductanceGrid]

    def inductance(self, coil: Coil, geometry: SensorGeometry) -> float:
        """Incremental inductance of ``coil`` (in ``geometry``) at the bias point, H
        (:func:`scaled_inductance` from the solved coil's)."""
        old = self.coils[coil.particle]
        rect = geometry.coil_rect(SensorUnit(coil))
        return float(scaled_inductance(
            self.grids[coil.particle], self.inductance_H[coil.particle], old,
            (rect.r0, rect.r1, rect.z0, rect.z1), coil.turns, coil.area,
            geometry.coil_rect(SensorUnit(old)))[0])

    def linkage(self, coil: Coil, geometry: SensorGeometry,
                offsets: np.ndarray | None = None) -> np.ndarray:
        """Flux linkage of every source with ``coil`` moved by each offset, Wb per unit
        source, shape (n_o, n_s) (offsets default: none, shape (1, n_s))."""
        rect = geometry.coil_rect(SensorUnit(coil))
        shift = np.zeros(1) if offsets is None else np.asarray(offsets, dtype=float)
        ones = np.ones(shift.size)
        return coil.turns / coil.area * rect_integral(
            self.tables[coil.particle], rect.r0 * ones, rect.r1 * ones,
            rect.z0 + shift, rect.z1 + shift)

    def profiles(self, coil: Coil, geometry: SensorGeometry,
                 offsets: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`~msens.magnetics.mechanisms.contact_profiles` of ``coil`` (and moved by
        ``offsets``): contacts, ∂Λ/∂F_c (Wb/N) and ∂Λ/∂δ_c (Wb/m), shapes (n_c,) and
        (n_o, n_c)."""
        return contact_profiles(self.particles, self.approach_contacts, self.count,
                                self.linkage(coil, geometry, offsets))


def table_ranges(geometry: SensorGeometry, unit: SensorUnit
                 ) -> tuple[tuple[float, float], tuple[float, float]]:
    """The (r, z) extent of a coil's table, m: its window (:func:`coil_window`, widened to
    hold the coil itself), plus the offset span axially and two grid steps outward."""
    (r0, r1), (z0, z1) = coil_window(geometry, unit)
    rect = geometry.coil_rect(unit)
    pad = OFFSET_SPAN + 2 * SPACING
    return ((r0, max(r1, rect.r1) + 2 * SPACING),
            (min(z0, rect.z0) - pad, max(z1, rect.z1) + pad))


def build_tables(sol: FieldSolution, model: MechanismPotentials, geometry: SensorGeometry,
                 inductance_H: dict[int, float], particles) -> CoilTables:
    """The coil tables of a field model (its bias solution and sources) for the coils at
    ``particles``.

    Parameters
    ----------
    sol : FieldSolution
        The bias solution.
    model : MechanismPotentials
        Its sources' potentials.
    geometry : SensorGeometry
    inductance_H : dict of int -> float
        The coils' incremental inductances, H (from the set's transducers).
    particles : iterable of int
        Which coils.
    """
    wanted = {int(p) for p in particles}
    units = [u for u in geometry.iter_units() if u.coil.particle in wanted]
    tables = {u.coil.particle: linkage_table(sol, model.potentials,
                                             *table_ranges(geometry, u), SPACING)
              for u in units}
    grids = {u.coil.particle: inductance_grid(sol, model.operator, geometry, u)
             for u in units}
    return CoilTables(tables=tables, particles=np.asarray(model.particles),
                      approach_contacts=np.asarray(model.contacts), count=int(model.count),
                      coils={u.coil.particle: u.coil for u in units},
                      inductance_H={u.coil.particle: float(inductance_H[u.coil.particle])
                                    for u in units},
                      grids=grids)


def fits(coil: Coil, geometry: SensorGeometry, solved: SensorGeometry) -> bool:
    """Whether ``coil`` (of ``geometry``), moved over the offset span, lies in the table
    that the same sensor of ``solved`` (the tables' geometry) has."""
    unit = next((u for u in solved.sensors if u.coil.particle == coil.particle), None)
    if unit is None:
        return False
    (r0, r1), (z0, z1) = table_ranges(solved, unit)
    rect = geometry.coil_rect(SensorUnit(coil))
    tol = 1e-9
    return bool(r0 - tol <= rect.r0 and rect.r1 <= r1 + tol
                and z0 - tol <= rect.z0 - OFFSET_SPAN and rect.z1 + OFFSET_SPAN <= z1 + tol)


def coil_record(coil: Coil) -> dict:
    """A coil as JSON values (:func:`coil_from` reads it back)."""
    return {**asdict(coil), "wire": asdict(coil.wire)}


def coil_from(record: dict) -> Coil:
    """The coil :func:`coil_record` wrote."""
    return Coil(**{**record, "wire": Wire(**record["wire"])})


def model_name(key: str) -> str:
    """The name of the JSON artifact naming a coil-free key's solved coils."""
    return f"coil-model-{key}.json"


def write_model(store: Store, key: str, coils: dict[int, Coil],
                inductance_H: dict[int, float]) -> None:
    """Record which coils the field model of coil-free ``key`` was solved with, and their
    inductances (JSON artifact :func:`model_name`; tiny, written once)."""
    if store.read_json(model_name(key)) is not None:
        return
    from msens.errors import InputError

    try:
        store.write_json(model_name(key), {
            "schema": COIL_TABLE_VERSION, "key": key,
            "coils": {str(p): coil_record(c) for p, c in sorted(coils.items())},
            "inductance_H": {str(p): float(v) for p, v in sorted(inductance_H.items())}})
    except InputError as exc:  # only a later coil change would have read it: say nothing
        _log.debug("%s; coil record not kept", exc)


def read_model(store: Store, key: str) -> tuple[dict[int, Coil], dict[int, float]] | None:
    """The solved coils and their inductances of coil-free ``key`` (H), or None."""
    data = store.read_json(model_name(key))
    if data is None or data.get("schema") != COIL_TABLE_VERSION:
        return None
    return ({int(p): coil_from(c) for p, c in data["coils"].items()},
            {int(p): float(v) for p, v in data["inductance_H"].items()})


def write_tables(store: Store, key: str, tables: CoilTables, *,
                 rank_tol: float | None = None) -> None:
    """Store each coil of ``tables`` as artifact :func:`table_name` (atomic .npz with its
    checksum).

    ``rank_tol``: store the summed-area tables as a truncated SVD over sources
    (:func:`msens.magnetics.low_rank.rows_svd`) and the inductance kernel as its leading
    eigenpairs (:func:`msens.magnetics.low_rank.symmetric_eig`) instead: how the main study's
    tables are committed (about 3 MB per coil instead of 17;
    ``python benchmarks/coil_table_rank.py`` makes them and measures what a read loses).
    """
    for p, t in sorted(tables.tables.items()):
        g = tables.grids[p]
        arrays = {"particles": tables.particles, "approach_contacts": tables.approach_contacts,
                  "count": np.array(tables.count), "r": t.r, "z": t.z,
                  "grid_r": g.r, "grid_z": g.z}
        if rank_tol is None:
            arrays.update(cumulative=t.cumulative, kernel=g.kernel)
        else:
            u, v = rows_svd(t.cumulative.reshape(t.cumulative.shape[0], -1), rank_tol)
            q, lam = symmetric_eig(g.kernel, rank_tol)
            arrays.update(cumulative_u=u, cumulative_v=v,
                          cumulative_shape=np.array(t.cumulative.shape), kernel_q=q,
                          kernel_lam=lam)

        def write(tmp, arrays=arrays):
            buf = io.BytesIO()
            np.savez(buf, **arrays)
            tmp.write_bytes(buf.getvalue())

        store.write_file(table_name(key, p), write,
                         {"schema": COIL_TABLE_VERSION, "key": key, "particle": p})


def read_tables(store: Store, key: str, coils: dict[int, Coil],
                inductance_H: dict[int, float], particles) -> CoilTables:
    """The stored tables of the coils at ``particles`` that the store has (verified; maybe
    none; full or truncated, :func:`write_tables`), with ``coils`` and ``inductance_H`` from
    :func:`read_model`."""
    tables, grids, common = {}, {}, None
    for p in sorted({int(q) for q in particles}):
        path = store.find_file(table_name(key, p))
        if path is None:
            continue
        with np.load(path) as f:
            if "cumulative" in f:
                cumulative, kernel = f["cumulative"], f["kernel"]
            else:
                cumulative = (f["cumulative_u"] @ f["cumulative_v"].astype(float)).reshape(
                    tuple(f["cumulative_shape"]))
                kernel = expand_symmetric(f["kernel_q"], f["kernel_lam"])
            tables[p] = LinkageTable(f["r"], f["z"], cumulative)
            grids[p] = InductanceGrid(f["grid_r"], f["grid_z"], kernel)
            common = (f["particles"], f["approach_contacts"], int(f["count"]))
    if common is None:
        common = (np.zeros(0, dtype=int), np.zeros(0, dtype=int), 0)
    return CoilTables(tables=tables, particles=common[0], approach_contacts=common[1],
                      count=common[2], coils=coils, inductance_H=inductance_H, grids=grids)


def solved_geometry(geometry: SensorGeometry, coils: dict[int, Coil]) -> SensorGeometry:
    """``geometry`` with the coils its field model was solved with (``coils`` by particle,
    from :func:`read_model`)."""
    return replace(geometry, sensors=tuple(replace(u, coil=coils[u.coil.particle])
                                           for u in geometry.sensors))


def read_coil(tables: CoilTables, reference, coil: Coil, geometry: SensorGeometry):
    """The transducer of ``coil`` from the table coil's ``reference`` transducer.

    Parameters
    ----------
    tables : CoilTables
    reference : Transducer
        The table coil's transducer (same particle); its magnets' pull, contact stiffness,
        reference force and contact maps carry over.
    coil : Coil
        The new coil (must :meth:`~CoilTables.fits`).
    geometry : SensorGeometry
        The geometry ``coil`` belongs to.

    Returns
    -------
    Transducer
        Its ``source`` is the reference's: the same field model (so the magnets' pull counts
        once, :func:`~msens.magnetics.transducer.magnetic_precompression`).
    """
    internal(reference.particle == coil.particle and coil.particle in tables.tables,
             "internal: a coil read without its table")
    offsets = offset_grid(OFFSET_STEP)
    contacts, vil, app = tables.profiles(coil, geometry, np.concatenate([[0.0], offsets]))
    internal(bool(np.array_equal(contacts, reference.contacts)),
             "internal: coil table and transducer cover different contacts")
    inductance = tables.inductance(coil, geometry)
    return replace(reference, sensitivity_villari=vil[0], dlambda_dapproach=app[0],
                   resistance_ohm=coil_resistance(coil), inductance_H=inductance,
                   turns=coil.turns, offsets=offsets, villari_by_offset=vil[1:],
                   approach_by_offset=app[1:])


__all__ = [
    "COIL_TABLE_VERSION",
    "L_CELL",
    "SPACING",
    "CoilTables",
    "InductanceGrid",
    "build_tables",
    "coil_free_key",
    "coil_from",
    "coil_record",
    "coil_window",
    "fits",
    "inductance_grid",
    "model_name",
    "read_coil",
    "read_model",
    "read_tables",
    "scaled_inductance",
    "solved_geometry",
    "table_name",
    "table_ranges",
    "write_model",
    "write_tables",
]

"""A changed coil of an eddy-current model read from the model of another coil.

The eddy currents flow in the steel (beads, pole pieces) and the magnets, never in the
winding: a pick-up coil is copper in air that carries no current while it reads. Changing it
changes neither the bias state nor the harmonic potentials a_s(ω) of the Villari and
contact-approach sources, only which part of them the winding links — the eddy-current
counterpart of :mod:`msens.magnetics.coil_read`. So :func:`msens.magnetics.dynamic_cache.
dynamic_report` keys its model also on everything but the coils (:func:`free_key`) and serves
a geometry that differs from a solved one only in its coils from two artifacts:

- ``coil-model-<key>.json`` (:func:`msens.magnetics.coil_read.write_model`): which coils the
  eddy-current model of that key was solved with; written whenever the model is computed or
  read, so a default run of an eddy-current study leaves it behind;
- ``eddy-coil-table-<key>-<particle>.npz``: the sources' harmonic summed-area tables over
  the coil's window and offset span (:class:`~msens.magnetics.harmonic_tables.HarmonicTables`,
  :data:`SPACING`), built the first time that coil changes (the eddy mesh's bias solve and
  every source solved at every frequency: minutes; then kept in the user cache). The main
  study's are committed as truncated singular value decompositions (:func:`low_rank`;
  ``benchmarks/eddy_table_rank.py`` makes them and measures their error).

A changed coil's :class:`~msens.magnetics.frequency_response.FrequencyResponse`:

- S_c(ω), D_c(ω) and the offset profiles: the solved coil's exact values plus the table
  quadrature of (new winding − solved winding). The table's quadrature error cancels to
  first order in the difference, and a coil that did not change is read exactly;
- Z(ω) = R_dc + jω L(ω): R_dc of the new winding
  (:func:`msens.field.sensor_model.coil_resistance`); L(ω) the solved coil's times the ratio
  of the two windings' static incremental inductances, as the static coil read has them
  (:meth:`msens.magnetics.coil_read.CoilTables.inductance`: the steel-aware window kernel).
  That the ratio holds at every frequency is the assumption a coil sweep with eddy currents
  makes too (:mod:`msens.design.coil_sweep`);
- the screening split (:attr:`FrequencyResponse.screening`) is the solved coil's and is not
  carried over (None).

``python benchmarks/coil_read.py --eddy`` measures a read against a full rebuild.
"""

from __future__ import annotations

import io
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from msens.errors import internal
from msens.field.build import MeshOptions
from msens.field.geometry import SensorGeometry
from msens.field.parts import SensorUnit
from msens.field.sensor_model import coil_resistance
from msens.magnetics.coil_read import (
    COIL_TABLE_VERSION,
    coil_record,
    fits,
    read_model,
    solved_geometry,
    table_ranges,
    write_model,
)
from msens.magnetics.dynamic import (
    DynamicReport,
    dynamic_key,
    eddy_sources,
    report_from_json,
    report_name,
)
from msens.magnetics.frequency_response import FrequencyResponse
from msens.magnetics.harmonic_tables import HarmonicTables, harmonic_tables_over
from msens.magnetics.low_rank import rows_svd
from msens.magnetics.mechanisms import contact_profiles
from msens.magnetics.transducer_cache import free_key as static_free_key
from msens.magnetics.transducer_cache import transducer_report
from msens.params.units import TWO_PI
from msens.readout.coil import Coil
from msens.store import Store, content_key

_log = logging.getLogger(__name__)

#: Version of the eddy-current coil tables; part of their metadata.
EDDY_TABLE_VERSION = "eddy-coil-table/1"
#: Grid spacing of the harmonic tables, m. Coarser than the static tables'
#: (:data:`msens.magnetics.coil_read.SPACING`, 0.1 mm): a coil's window holds 57 sources at
#: 17 frequencies (0.2 mm: ~55 MB per coil), and the read uses only the difference of two
#: windings' quadratures, whose error cancels to first order.
SPACING = 0.2e-3


def free_key(geometry: SensorGeometry, options: MeshOptions | None,
             frequencies: Sequence[float], steel: float,
             magnets: Mapping[str, float] | None, offsets: Sequence[float] | None) -> str:
    """The key of :func:`msens.magnetics.dynamic_cache.dynamic_report`'s model of ``geometry``
    with the coils left out (the static field model's coil-free key,
    :func:`msens.magnetics.transducer_cache.free_key`, with the frequencies, conductivities
    and offset grid)."""

    return dynamic_key(static_free_key(geometry, options), frequencies, steel, magnets, offsets)


def tables_key(geometry: SensorGeometry, solved: Mapping[int, Coil],
               options: MeshOptions | None, frequencies: Sequence[float], steel: float,
               magnets: Mapping[str, float] | None) -> str:
    """The key of the harmonic tables of the model solved with coils ``solved`` (by
    particle): :func:`free_key` without the offset grid (the tables do not depend on it, so
    the models with and without offset profiles — run's and diagnose's — share them) and the
    solved coils (the mesh the tables come from is graded around them)."""
    return content_key({"version": EDDY_TABLE_VERSION,
                        "model": free_key(geometry, options, frequencies, steel, magnets, None),
                        "solved": {str(p): coil_record(c) for p, c in sorted(solved.items())}},
                       16)


def record_model(store: Store, key: str, geometry: SensorGeometry, report) -> None:
    """Record the coils ``report`` (a :class:`~msens.magnetics.dynamic.DynamicReport` of
    ``geometry``) was solved with under coil-free ``key`` (once; see
    :func:`msens.magnetics.coil_read.write_model`)."""
    write_model(store, key, {u.coil.particle: u.coil for u in geometry.sensors},
                {p: r.static_inductance_H for p, r in report.responses.items()})


def table_name(key: str, particle: int) -> str:
    """The file name of the harmonic table artifact of the coil at ``particle``."""
    return f"eddy-coil-table-{key}-{int(particle)}.npz"


@dataclass(frozen=True)
class EddyCoilTable:
    """What a changed coil of one eddy-current model needs: the sources' harmonic tables over
    its window and how its sources map to contacts.

    Attributes
    ----------
    harmonic : HarmonicTables
        Over the coil's window plus the offset span (:func:`~msens.magnetics.coil_read.
        table_ranges`), at the model's frequencies.
    particles, approach_contacts, count
        The sources' layout, as :class:`~msens.magnetics.coil_read.CoilTables` has it.
    """

    harmonic: HarmonicTables
    particles: np.ndarray
    approach_contacts: np.ndarray
    count: int

    def profiles(self, coil: Coil, geometry: SensorGeometry, shifts: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
        """S_c(ω) and D_c(ω) of ``coil`` (of ``geometry``) moved by each of ``shifts`` (m),
        by table quadrature: Wb/N and Wb/m, each of shape (n_shift, n_f, n_c)."""
        rect = geometry.coil_rect(SensorUnit(coil))
        ones = np.ones(shifts.size)
        link = self.harmonic.linkage(coil.turns * ones, rect.r0 * ones, rect.r1 * ones,
                                     rect.z0 + shifts, rect.z1 + shifts)
        _, vr, ar = contact_profiles(self.particles, self.approach_contacts, self.count,
                                     link.real)
        _, vi, ai = contact_profiles(self.particles, self.approach_contacts, self.count,
                                     link.imag)
        return vr + 1j * vi, ar + 1j * ai


def write_table(store: Store, key: str, particle: int, table: EddyCoilTable, *,
                rank_tol: float | None = None) -> None:
    """Store ``table`` as artifact :func:`table_name` (atomic .npz with its checksum); a
    failed write is a warning (the table only serves later coil changes).

    ``rank_tol``: store the tables as a truncated singular value decomposition instead
    (:func:`low_rank`; how the main study's tables are committed, a few MB instead of 59).
    """
    from msens.errors import InputError

    h = table.harmonic
    arrays = {"frequencies": h.frequencies, "r": h.r, "z": h.z,
              "particles": table.particles, "approach_contacts": table.approach_contacts,
              "count": np.array(table.count)}
    if rank_tol is None:
        arrays["cumulative"] = h.cumulative
    else:
        arrays.update(low_rank(h.cumulative, rank_tol))

    def write(tmp):
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        tmp.write_bytes(buf.getvalue())

    try:
        store.write_file(table_name(key, particle), write,
                         {"schema": EDDY_TABLE_VERSION, "key": key, "particle": int(particle)})
    except InputError as exc:
        _log.warning("%s; eddy-current coil table not kept", exc)


def low_rank(cumulative: np.ndarray, rank_tol: float) -> dict[str, np.ndarray]:
    """The tables of every frequency and source as one matrix (rows: frequency × source,
    columns: grid nodes), each row scaled to unit 2-norm, truncated to the singular values
    above ``rank_tol`` × the largest (:func:`msens.magnetics.low_rank.rows_svd`).

    The sources' potentials over a coil's window are smooth and alike (the window is air
    and copper, away from every source), so a few dozen singular vectors carry them:
    ``u`` = U_k Σ_k (complex128, rows × k) and ``v`` = V_k^H (complex64, k × nodes);
    ``shape`` restores (n_f, n_sources, nr, nz).
    """
    n_f, n_s, nr, nz = cumulative.shape
    u, v = rows_svd(cumulative.reshape(n_f * n_s, nr * nz), rank_tol)
    return {"u": u, "v": v, "shape": np.array(cumulative.shape)}


def read_table(store: Store, key: str, particle: int) -> EddyCoilTable | None:
    """The stored (verified) table of the coil at ``particle``, or None (full or
    :func:`low_rank` tables)."""
    path = store.find_file(table_name(key, particle))
    if path is None:
        return None
    with np.load(path) as f:
        if "cumulative" in f:
            cumulative = f["cumulative"]
        else:
            cumulative = (f["u"] @ f["v"].astype(complex)).reshape(tuple(f["shape"]))
        return EddyCoilTable(HarmonicTables(f["frequencies"], f["r"], f["z"], cumulative),
                             f["particles"], f["approach_contacts"], int(f["count"]))


def build_tables(solved: SensorGeometry, particles: Sequence[int], *,
                 options: MeshOptions | None, store: Store, frequencies: Sequence[float],
                 steel: float, magnets: Mapping[str, float] | None
                 ) -> dict[int, EddyCoilTable]:
    """The harmonic tables of the coils at ``particles`` of ``solved`` (the geometry the
    eddy-current model was solved with): its eddy mesh's bias solve and sources
    (:func:`msens.magnetics.dynamic.eddy_sources`), every source solved once per frequency
    for all the coils (:func:`msens.magnetics.harmonic_tables.harmonic_tables_over`)."""

    units = [u for u in solved.sensors if u.coil.particle in {int(p) for p in particles}]
    model = eddy_sources(solved, options, store=store)
    tabs = harmonic_tables_over(model, solved, frequencies,
                                [table_ranges(solved, u) for u in units], SPACING,
                                steel=steel, magnets=magnets)
    return {u.coil.particle: EddyCoilTable(t, np.asarray(model.particles),
                                           np.asarray(model.contacts), int(model.count))
            for u, t in zip(units, tabs, strict=True)}


def read_response(table: EddyCoilTable, reference: FrequencyResponse, solved: Coil,
                  solved_geometry_: SensorGeometry, coil: Coil, geometry: SensorGeometry,
                  inductance_ratio: float) -> FrequencyResponse:
    """The frequency response of ``coil`` from the solved coil's ``reference``.

    Parameters
    ----------
    table : EddyCoilTable
        The solved coil's harmonic tables (same frequencies as ``reference``).
    reference : FrequencyResponse
        The solved coil's response (exact mesh quadrature).
    solved : Coil
        The solved coil (of ``solved_geometry_``).
    solved_geometry_ : SensorGeometry
    coil : Coil
        The new coil (same particle; must fit the table, :func:`~msens.magnetics.coil_read.
        fits`).
    geometry : SensorGeometry
        The geometry ``coil`` belongs to.
    inductance_ratio : float
        The new winding's static incremental inductance over the solved one's.

    Returns
    -------
    FrequencyResponse
        S_c, D_c (and their offset profiles, if the reference has them) the reference's plus
        the tables' difference of the two windings; Z(ω) = R_dc + jω L_ref(ω) × ratio; no
        screening split.
    """
    freqs = np.asarray(reference.frequencies, dtype=float)
    internal(np.allclose(table.harmonic.frequencies, freqs, rtol=1e-12, atol=0),
             "internal: an eddy-current coil table at other frequencies than its model")
    offsets = (np.zeros(0) if reference.offsets is None
               else np.asarray(reference.offsets, dtype=float))
    shifts = np.concatenate([[0.0], offsets])
    v_new, a_new = table.profiles(coil, geometry, shifts)
    v_old, a_old = table.profiles(solved, solved_geometry_, shifts)
    dv, da = v_new - v_old, a_new - a_old
    inductance = np.asarray(reference.inductance) * inductance_ratio
    resistance = coil_resistance(coil)
    impedance = resistance + 1j * TWO_PI * freqs * inductance
    profiles = {} if reference.offsets is None else {
        "villari_by_offset": np.asarray(reference.villari_by_offset) + dv[1:],
        "approach_by_offset": np.asarray(reference.approach_by_offset) + da[1:]}
    return replace(reference, villari=np.asarray(reference.villari) + dv[0],
                   approach=np.asarray(reference.approach) + da[0], impedance=impedance,
                   resistance_ohm=resistance,
                   static_inductance_H=float(reference.static_inductance_H * inductance_ratio),
                   source=f"{reference.source}; coil read from the solved coil's harmonic "
                          f"tables (msens.magnetics.eddy_coil_read)",
                   screening=None, **profiles)


def read_changed_coils(geometry: SensorGeometry, key: str, *, store: Store,
                       options: MeshOptions | None, frequencies: Sequence[float],
                       steel: float, magnets: Mapping[str, float] | None,
                       offsets: Sequence[float] | None):
    """The eddy-current model of ``geometry`` read from the stored model of the same sensors
    with other coils (coil-free ``key``, :func:`free_key`), or None when there is none, its
    report is gone or a coil lies outside its tables (keyed by :func:`tables_key`).

    Returns
    -------
    DynamicReport or None
    """
    from msens.progress import heartbeat

    model = read_model(store, key)
    if model is None:
        return None
    coils, _ = model
    if set(coils) != {u.coil.particle for u in geometry.sensors}:
        return None
    solved = solved_geometry(geometry, coils)
    misfits = [u.coil.particle for u in geometry.sensors if not fits(u.coil, geometry, solved)]
    if misfits:
        _log.info("coils at particles %s lie outside the harmonic tables of the stored "
                  "eddy-current model %s: a new model", misfits, key)
        return None
    _, name = report_name(solved, options, frequencies, steel, magnets, offsets)
    data = store.read_json(name)
    if data is None:
        return None
    reference = report_from_json(data)
    changed = [u.coil.particle for u in geometry.sensors if u.coil != coils[u.coil.particle]]
    if not changed:
        return reference
    table_key = tables_key(geometry, coils, options, frequencies, steel, magnets)
    tables = {p: t for p in changed if (t := read_table(store, table_key, p)) is not None}
    missing = [p for p in changed if p not in tables]
    if missing:
        _log.info("harmonic tables of the eddy-current model %s for the coils at particles "
                  "%s: its bias solve and every source at %d frequencies, minutes (once per "
                  "coil; later changes of these coils are read in seconds)", table_key, missing,
                  len(reference.responses[missing[0]].frequencies))
        with heartbeat(_log, "eddy-current coil tables"):
            built = build_tables(solved, missing, options=options, store=store,
                                 frequencies=frequencies, steel=steel, magnets=magnets)
        for p, t in built.items():
            write_table(store, table_key, p, t)
        tables.update(built)
    # the static incremental inductances (plain mesh) as the static coil read has them (the
    # solved coils' first: it records their field model, which the changed coils' read)
    old_l = transducer_report(solved, store=store).transducers
    new_l = transducer_report(geometry, store=store).transducers
    out = {}
    for u in geometry.sensors:
        p = u.coil.particle
        ref = reference.responses[p]
        out[p] = ref if p not in tables else read_response(
            tables[p], ref, coils[p], solved, u.coil, geometry,
            new_l[p].inductance_H / old_l[p].inductance_H)
    _log.info("eddy-current responses of the coils at particles %s read from the model of "
              "the solved coils %s (no new mesh or solve)", changed, key)
    details = {**reference.details, "coil_read": {
        "tables": [table_name(table_key, p) for p in changed], "spacing_m": SPACING,
        "inductance": "solved coil's L(ω) x ratio of the static incremental inductances",
        "version": COIL_TABLE_VERSION}}
    return DynamicReport(out, details)


__all__ = [
    "EDDY_TABLE_VERSION",
    "SPACING",
    "EddyCoilTable",
    "build_tables",
    "free_key",
    "low_rank",
    "read_changed_coils",
    "read_response",
    "read_table",
    "record_model",
    "table_name",
    "tables_key",
    "write_table",
]

"""Magneto-quasi-static (eddy-current) transducer: frequency-dependent sensitivities and Z(ω).

The static transducer (:mod:`msens.magnetics.transducer`) solves K_t a_s = f_s for every
mechanism source s (the Villari magnetisation of each bead per newton, the approach of each
contact per metre) at the bias point. The beads and pole pieces are conducting steel, so a
source that changes in time drives eddy currents J_φ = −jωσA_φ (phasors x(t) = Re X e^{jωt},
:mod:`msens.field.eddy`) which screen it. The small-signal problem stays linear:

    (K_t + jω M_σ) a_s(ω) = f_s,

with the SAME source load vectors f_s (:attr:`MechanismPotentials.rhs`), solved at a few
log-spaced frequencies with one factorisation per frequency (:class:`HarmonicOperator`).
Each coil's flux linkage of a_s(ω) gives the complex per-contact sensitivities S_c(ω) =
∂Λ/∂F_c (Villari) and D_c(ω) = ∂Λ/∂δ_c (approach); the coil's own harmonic field gives its
impedance Z(ω) = R_dc + jωΛ(ω)/I. K_t + jωM_σ is complex symmetric, so the coil's own field
a_1(ω) reads every source: Λ_s = 2π a_1ᵀ f_s (no conjugate). That is how the sensitivities
are computed (one solve per coil and frequency); ``direct=True`` also solves every source and
checks it to round-off.

Approximations (say so wherever the numbers are used):

* the approach source −∂R/∂δ_c is the static residual derivative; the motional EMF v × B
  of the moving beads (σ v × B_bias, velocities ≲ 1 m/s) is left out;
* the small-signal permeability is a study choice (``[field] small_signal_permeability``,
  :func:`msens.field.constitutive.small_signal_tangent`): the differential slope of the B–H
  curve, or its reversible part; the README shows how much it matters;
* the winding itself is non-conducting (fine wire); its R is the DC resistance.

In time (:func:`msens.readout.mss.mss_signals`) the contact force and approach rates are Fourier
transformed, multiplied by −S_c(ω) and −D_c(ω) (interpolated between the solved
frequencies, :meth:`FrequencyResponse.villari_at`) and by the read-out circuit's transfer
function with the coil's series impedance Z(ω)
(:func:`msens.readout.electronics.coil_transfer_function`).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from msens.errors import internal, require
from msens.field.build import MeshOptions
from msens.field.eddy import HarmonicOperator, dissipated_power
from msens.field.geometry import SensorGeometry
from msens.field.sensor_model import coil_current_density, coil_resistance
from msens.field.solve import FieldSolution
from msens.magnetics.frequency_response import FrequencyResponse
from msens.magnetics.mechanisms import (
    MechanismPotentials,
    offset_linkage,
    offset_table_grid,
)
from msens.magnetics.potentials import region_linkage
from msens.params.materials import MAGNET_CONDUCTIVITY, SIGMA_1018
from msens.params.units import TWO_PI
from msens.store import Store, content_key

_log = logging.getLogger(__name__)

#: Frequencies solved by default, Hz: 0 (the static transducer), 12 roughly log-spaced
#: points over 0.5–200 kHz (1-2-3-5 steps, so the reported 1, 3, 10, 30, 100 kHz are solved)
#: and four below: a bead's own diffusion time μσR² is ~ 40 ms (1/(πμσR²) ≈ 8 Hz at μr 900),
#: so its bulk (Villari) response has already fallen to ~0.3 at 500 Hz and the interpolation
#: between 0 and 500 Hz needs points there.
DEFAULT_FREQUENCIES: tuple[float, ...] = (0.0, 10.0, 30.0, 100.0, 300.0, 500.0, 1e3, 2e3,
                                          3e3, 5e3, 10e3, 20e3, 30e3, 50e3, 100e3, 150e3,
                                          200e3)

#: Step of the coil-offset profiles of :func:`dynamic_report` ``(offsets=True)``, m: ±3 mm
#: (``OFFSET_SPAN``) in 0.25 mm steps, 25 offsets; the sensitivities change over the coil's
#: length and the bead diameter (several mm), so cubic interpolation between the steps is
#: accurate (tested against a moved coil's own model).
RESPONSE_OFFSET_STEP = 0.25e-3

#: Frequencies of the screening split (:func:`screening_split`), Hz: those ``summary.json`` and
#: the docs quote.
SCREENING_FREQUENCIES: tuple[float, ...] = (10e3, 30e3, 100e3)

def sensor_conductivity(mesh, geometry: SensorGeometry, *, steel: float = SIGMA_1018,
                        magnets: Mapping[str, float] | None = None) -> np.ndarray:
    """Conductivity of every element of a sensor mesh, S/m, shape (n_elements,).

    Beads and pole pieces are the geometry's steel (``steel``, default 1018,
    :data:`msens.params.materials.SIGMA_1018`); each magnet gets the conductivity of its grade
    (:data:`msens.params.materials.MAGNET_CONDUCTIVITY`, or ``magnets`` keyed by grade); air,
    coils (fine wire) and the tube (not a mesh region: air) are insulators.

    Parameters
    ----------
    mesh : AxiMesh
    geometry : SensorGeometry
    steel : float
        S/m.
    magnets : Mapping[str, float], optional
        Conductivity per magnet grade, S/m (overrides
        :data:`msens.params.materials.MAGNET_CONDUCTIVITY`).
    """
    table = {**MAGNET_CONDUCTIVITY, **(magnets or {})}
    grades = {f"magnet_{u.magnet.particle}": u.magnet.grade for u in geometry.sensors
              if u.magnet is not None}
    require(steel >= 0, f"steel conductivity must be >= 0 S/m, got {steel}")
    sigma = np.zeros(mesh.n_elements)
    for name, el in mesh.subdomains.items():
        if name.startswith(("bead_", "pole_")):
            sigma[el] = steel
        elif name in grades:
            require(grades[name] in table,
                    f"no conductivity for magnet grade {grades[name]!r} (have "
                    f"{sorted(table)}); pass magnets={{grade: S/m}}")
            require(table[grades[name]] >= 0, "magnet conductivity must be >= 0 S/m")
            sigma[el] = table[grades[name]]
    return sigma


@dataclass(frozen=True)
class DynamicReport:
    """What :func:`frequency_responses` finds (also what the cache stores).

    Attributes
    ----------
    responses : dict of int -> FrequencyResponse
        One per coil, keyed by its particle.
    details : dict
        JSON-ready diagnostics: per coil and frequency the reciprocity error (direct source
        solves against the coil's own harmonic field) and the power balance; dofs;
        conductivities. (The seconds of each stage go to the log at DEBUG.)
    """

    responses: dict[int, FrequencyResponse]
    details: dict


def frequency_responses(model: MechanismPotentials, geometry: SensorGeometry,
                        frequencies: Sequence[float] = DEFAULT_FREQUENCIES, *,
                        sigma: np.ndarray | None = None, steel: float = SIGMA_1018,
                        magnets: Mapping[str, float] | None = None,
                        direct: bool = False, offsets: Sequence[float] | None = None,
                        screening: bool = False) -> DynamicReport:
    """Solve (K_t + jωM_σ) a_s = f_s for every source and coil at each frequency.

    Parameters
    ----------
    model : MechanismPotentials
        Bias solution and sources of ``geometry`` (:func:`mechanism_potentials`; its
        ``rhs`` is used, the static potentials only for the record's source string).
    geometry : SensorGeometry
    frequencies : sequence of float
        Hz, increasing, starting at 0 (the static limit, solved with the same algebra).
    sigma : ndarray, shape (n_elements,), optional
        Conductivity per element, S/m; default :func:`sensor_conductivity` with ``steel``
        and ``magnets``.
    steel : float
        Bead and pole-piece conductivity, S/m.
    magnets : Mapping[str, float], optional
        Conductivity per magnet grade, S/m.
    direct : bool
        Also solve every source directly, (K_t + jωM_σ) a_s = f_s, and read it with the
        coil (the check of reciprocity, ``reciprocity_rel_error`` in the details). Default:
        by reciprocity only, Λ_s = 2π a_1ᵀ f_s with the coil's own field a_1 — one solve per
        coil and frequency instead of one per source (on the main study's 52k dofs the ~40
        source back-substitutions took 13 s per frequency, the factorisation 2 s).
    offsets : sequence of float, optional
        Axial coil offsets, m (within ±``OFFSET_SPAN``): also solve every source and read it
        with each coil moved by each offset (:func:`msens.magnetics.mechanisms.offset_linkage`),
        the profiles of :meth:`FrequencyResponse.shifted`.
    screening : bool
        Also solve at :data:`SCREENING_FREQUENCIES` with the pole pieces and magnets
        non-conducting, and record how much of the screening comes from them
        (:func:`screening_split`, :attr:`FrequencyResponse.screening`).

    Returns
    -------
    DynamicReport
    """
    freqs = np.asarray([float(f) for f in frequencies])
    require(freqs.size >= 2 and freqs[0] == 0.0 and bool(np.all(np.diff(freqs) > 0)),
            f"frequencies must increase from 0 Hz (at least two), got {freqs.tolist()}")
    internal(model.rhs is not None, "internal: MechanismPotentials without source loads (rhs)")
    sol = model.solution
    mesh = sol.problem.mesh
    if sigma is None:
        sigma = sensor_conductivity(mesh, geometry, steel=steel, magnets=magnets)
    from msens.progress import timed

    with timed(_log, "eddy currents: assembly"):
        op = HarmonicOperator(sol, sigma)
        coils = [u.coil for u in geometry.iter_units()]
        regions = [f"coil_{c.particle}" for c in coils]
        # 1 A in each coil: J = N/S
        coil_loads = np.array([op.winding_load(r, coil_current_density(c))
                               for r, c in zip(regions, coils, strict=True)])
    n_f, n_s = freqs.size, model.rhs.shape[0]
    link = np.zeros((len(coils), n_f, n_s), dtype=complex)
    lam_self = np.zeros((len(coils), n_f), dtype=complex)
    checks = {str(c.particle): {"reciprocity_rel_error": [], "power_balance_rel_error": []}
              for c in coils}
    offs = None if offsets is None else np.asarray([float(o) for o in offsets])
    moved = (None if offs is None
             else np.zeros((len(coils), n_f, offs.size, n_s), dtype=complex))
    grids = ([] if offs is None
             else [offset_table_grid(sol, geometry, c) for c in coils])  # once per model
    for k, f in enumerate(freqs):
        with timed(_log, f"eddy currents: {f:g} Hz factor and solves"):
            fac = op.factor(f)
            own = op.solve(fac, coil_loads)
            pots = op.solve(fac, model.rhs) if direct or offs is not None else None
        for i, (c, r) in enumerate(zip(coils, regions, strict=True)):
            lam_self[i, k] = region_linkage(sol, own[i:i + 1], r, c.turns, c.area)[0]
            # reciprocity: K_t + jωM_σ is complex symmetric, Λ_s = 2π a_1ᵀ f_s (no conjugate)
            link[i, k] = TWO_PI * (model.rhs @ own[i])
            chk = checks[str(c.particle)]
            if moved is not None:
                moved[i, k] = offset_linkage(sol, pots, geometry, c, offs, grid=grids[i])
            if direct:
                dir_link = region_linkage(sol, pots, r, c.turns, c.area)
                scale = float(np.max(np.abs(dir_link))) or 1.0
                chk["reciprocity_rel_error"].append(
                    float(np.max(np.abs(dir_link - link[i, k])) / scale))
            if f > 0:
                # Re Z − R_dc = ω² ∫σ|A|² dV / |I|² = 2P/|I|² (I = 1 A)
                loss = 2.0 * dissipated_power(op.harmonic_solution(f, own[i]))
                re_z = float((1j * TWO_PI * f * lam_self[i, k]).real)
                chk["power_balance_rel_error"].append(abs(re_z - loss) / max(abs(loss), 1e-300))
            else:
                chk["power_balance_rel_error"].append(0.0)
    out: dict[int, FrequencyResponse] = {}
    src = (f"msens.magnetics.dynamic {DYNAMIC_VERSION}: (K_t + jωM_σ) a_s = f_s at "
           f"{n_f} frequencies; σ steel {steel:.4g} S/m on beads and pole pieces, magnets "
           f"{dict(magnets or {}) or 'by grade'}; {sol.dofs} dofs")
    split = None
    if screening:
        with timed(_log, "eddy currents: screening split"):
            split = screening_split(model, geometry, op, sigma, coil_loads)
    for i, c in enumerate(coils):
        contacts, vr, ar = model.contact_profiles(link[i].real)
        _, vi, ai = model.contact_profiles(link[i].imag)
        w = TWO_PI * freqs
        profiles = {}
        if moved is not None:
            by_offset = np.moveaxis(moved[i], 1, 0)  # (n_o, n_f, n_s)
            _, mvr, mar = model.contact_profiles(by_offset.real)
            _, mvi, mai = model.contact_profiles(by_offset.imag)
            profiles = {"offsets": offs, "villari_by_offset": mvr + 1j * mvi,
                        "approach_by_offset": mar + 1j * mai}
        out[c.particle] = FrequencyResponse(
            particle=c.particle, frequencies=freqs, contacts=contacts, villari=vr + 1j * vi,
            approach=ar + 1j * ai, impedance=coil_resistance(c) + 1j * w * lam_self[i],
            resistance_ohm=coil_resistance(c), static_inductance_H=float(lam_self[i, 0].real),
            source=src, screening=None if split is None else split[c.particle], **profiles)
    details = {"dofs": sol.dofs, "elements": mesh.n_elements, "frequencies_Hz": freqs.tolist(),
               "sigma_max_S_per_m": float(np.max(sigma)),
               "conducting_elements": int(np.count_nonzero(sigma)),
               "coils": checks}
    return DynamicReport(out, details)


def equivalent_magnet_elements(mesh) -> np.ndarray:
    """Elements of the equivalent bridge magnet's parts (pole pieces ``pole_*``, magnets
    ``magnet_*``), bool, shape (n_elements,)."""
    out = np.zeros(mesh.n_elements, dtype=bool)
    for name, el in mesh.subdomains.items():
        if name.startswith(("pole_", "magnet_")):
            out[el] = True
    return out


def screening_split(model: MechanismPotentials, geometry: SensorGeometry,
                    op: HarmonicOperator, sigma: np.ndarray, coil_loads: np.ndarray,
                    frequencies: Sequence[float] = SCREENING_FREQUENCIES) -> dict[int, dict]:
    """How much of the eddy-current screening comes from the equivalent magnet, per coil.

    The pole pieces (and a conducting magnet) belong to the axisymmetric equivalent of an
    undocumented bridge magnet (design.md §5); the beads are the chain's. Each coil's response
    is solved at ``frequencies`` twice, with every conductor (``sigma``) and with the magnet's
    parts non-conducting (:func:`equivalent_magnet_elements`), and compared on the contact
    approach of the coil's two contacts (D_c(f)/D_c(0), the dominant mechanism) and the
    coil's eddy-loss resistance R_eddy = Re Z − R_dc and inductance.

    Parameters
    ----------
    model : MechanismPotentials
    geometry : SensorGeometry
    op : HarmonicOperator
        With every conductor (``sigma``).
    sigma : ndarray, shape (n_elements,)
        S/m.
    coil_loads : ndarray, shape (n_coils, n_dofs)
        1 A in each coil of ``geometry.iter_units()``.
    frequencies : sequence of float
        Hz, > 0.

    Returns
    -------
    dict of int -> dict
        Per coil particle, JSON-ready: ``frequencies_Hz``, ``contacts``; for ``all`` (every
        conductor) and ``beads`` (magnet parts non-conducting) the approach ratio's
        magnitude and phase (deg, shape (n_f, 2)), ``eddy_resistance_ohm`` and
        ``inductance_H`` (n_f); ``magnet_share_of_screening``: the part of the approach
        ratio's loss of magnitude, 1 − |D_c(f)/D_c(0)|, that the magnet's parts cause,
        (|r_beads| − |r_all|) / (1 − |r_all|), shape (n_f, 2).
    """
    sol = model.solution
    mesh = sol.problem.mesh
    beads_only = np.where(equivalent_magnet_elements(mesh), 0.0, sigma)
    ops = {"all": op, "beads": HarmonicOperator(sol, beads_only)}
    coils = [u.coil for u in geometry.iter_units()]
    freqs = np.asarray([float(f) for f in frequencies])
    require(freqs.size > 0 and bool(np.all(freqs > 0)),
            f"screening frequencies must be > 0 Hz, got {freqs.tolist()}")
    fac0 = op.factor(0.0)
    static = op.solve(fac0, coil_loads)
    rows: dict[str, dict[str, list]] = {k: {"link": [], "lam": []} for k in ops}
    for f in freqs:
        for k, o in ops.items():
            own = o.solve(o.factor(f), coil_loads)
            rows[k]["link"].append(TWO_PI * (model.rhs @ own.T).T)  # (n_coils, n_s)
            rows[k]["lam"].append([region_linkage(sol, own[i:i + 1], f"coil_{c.particle}",
                                                  c.turns, c.area)[0]
                                   for i, c in enumerate(coils)])
    w = TWO_PI * freqs
    out = {}
    for i, c in enumerate(coils):
        pair = [c.particle - 1, c.particle]
        contacts, _, a0 = model.contact_profiles(TWO_PI * (model.rhs @ static[i].real))
        k = [int(np.flatnonzero(np.asarray(contacts) == q)[0]) for q in pair]
        entry: dict = {"frequencies_Hz": freqs.tolist(), "contacts": pair,
                       "what": "contact approach D_c(f)/D_c(0) of the coil's two contacts and "
                               "the coil's eddy-loss resistance and inductance, with every "
                               "conductor ('all') and with the pole pieces and magnet "
                               "non-conducting ('beads')"}
        mags = {}
        for name, r in rows.items():
            link = np.asarray(r["link"])[:, i, :]  # (n_f, n_s)
            _, _, ar = model.contact_profiles(link.real)
            _, _, ai = model.contact_profiles(link.imag)
            ratio = (ar + 1j * ai)[:, k] / a0[k]
            lam = np.asarray(r["lam"])[:, i]
            z_eddy = 1j * w * lam  # Z − R_dc
            mags[name] = np.abs(ratio)
            entry[name] = {"approach_ratio_magnitude": np.abs(ratio).tolist(),
                           "approach_ratio_phase_deg": np.degrees(np.angle(ratio)).tolist(),
                           "eddy_resistance_ohm": z_eddy.real.tolist(),
                           "inductance_H": (z_eddy.imag / w).tolist()}
        loss = 1.0 - mags["all"]
        entry["magnet_share_of_screening"] = np.where(
            np.abs(loss) > 1e-12, (mags["beads"] - mags["all"]) / np.where(loss == 0, 1, loss),
            0.0).tolist()
        out[c.particle] = entry
    return out


# ----------------------------------------------------------------------------- cache

#: Version of what :func:`frequency_responses` computes; part of the cache key.
DYNAMIC_VERSION = "dynamic/3"  # 3: the screening split; 2: the eddy mesh's bias starts
#                                  from the plain mesh's


def dynamic_key(transducer_key: str, frequencies: Sequence[float], steel: float,
                magnets: Mapping[str, float] | None,
                offsets: Sequence[float] | None = None) -> str:
    """Content hash (16 hex digits): the static transducer's key plus frequencies and σ (and
    the coil offsets of the profiles, if any)."""
    payload = {"version": DYNAMIC_VERSION, "transducer": transducer_key,
               "frequencies": [repr(float(f)) for f in frequencies], "steel": repr(float(steel)),
               "magnets": {k: repr(float(v)) for k, v in
                           sorted({**MAGNET_CONDUCTIVITY, **(magnets or {})}.items())}}
    if offsets is not None:
        payload["offsets"] = [repr(float(o)) for o in offsets]
    return content_key(payload, 16)


def _cplx(a: np.ndarray) -> dict:
    a = np.asarray(a)
    return {"real": a.real.tolist(), "imag": a.imag.tolist()}


def _uncplx(d: dict) -> np.ndarray:
    return np.asarray(d["real"], dtype=float) + 1j * np.asarray(d["imag"], dtype=float)


def report_to_json(report: DynamicReport) -> dict:
    """JSON-ready form of a :class:`DynamicReport` (complex arrays as real/imag lists)."""
    rs = {str(p): {"particle": r.particle, "frequencies_Hz": np.asarray(r.frequencies).tolist(),
                   "contacts": np.asarray(r.contacts).tolist(),
                   "villari_Wb_per_N": _cplx(r.villari), "approach_Wb_per_m": _cplx(r.approach),
                   "impedance_ohm": _cplx(r.impedance), "resistance_ohm": r.resistance_ohm,
                   "static_inductance_H": r.static_inductance_H, "source": r.source,
                   **({} if r.screening is None else {"screening": r.screening}),
                   **({} if r.offsets is None else {
                       "offsets_m": np.asarray(r.offsets).tolist(),
                       "villari_by_offset_Wb_per_N": _cplx(r.villari_by_offset),
                       "approach_by_offset_Wb_per_m": _cplx(r.approach_by_offset)})}
          for p, r in report.responses.items()}
    return {"schema": "msens.dynamic/1", "responses": rs, "details": report.details}


def report_from_json(data: dict) -> DynamicReport:
    """Inverse of :func:`report_to_json`."""
    require(data.get("schema") == "msens.dynamic/1",
            f"not a dynamic-transducer file (schema {data.get('schema')!r})")
    out = {}
    for v in data["responses"].values():
        out[int(v["particle"])] = FrequencyResponse(
            particle=int(v["particle"]), frequencies=np.asarray(v["frequencies_Hz"], float),
            contacts=np.asarray(v["contacts"], dtype=int), villari=_uncplx(v["villari_Wb_per_N"]),
            approach=_uncplx(v["approach_Wb_per_m"]), impedance=_uncplx(v["impedance_ohm"]),
            resistance_ohm=float(v["resistance_ohm"]),
            static_inductance_H=float(v["static_inductance_H"]), source=str(v["source"]),
            screening=v.get("screening"),
            **({} if "offsets_m" not in v else {
                "offsets": np.asarray(v["offsets_m"], dtype=float),
                "villari_by_offset": _uncplx(v["villari_by_offset_Wb_per_N"]),
                "approach_by_offset": _uncplx(v["approach_by_offset_Wb_per_m"])}))
    return DynamicReport(out, data.get("details", {}))


def report_name(geometry: SensorGeometry, options: MeshOptions | None,
                frequencies: Sequence[float], steel: float,
                magnets: Mapping[str, float] | None,
                offsets: Sequence[float] | None) -> tuple[str, str]:
    """The static transducer key and the artifact name (``dynamic-<key>.json``) of
    :func:`dynamic_report`'s model of ``geometry`` (``offsets``: the profiles' offset grid,
    m, or None)."""
    from msens.magnetics.steel_law import law_for_steel
    from msens.magnetics.transducer import cache_key
    from msens.params.materials import BEAD_STEEL

    tkey = cache_key(geometry, options, stress_force=geometry.beads.contact_load,
                     law=law_for_steel(geometry.steel), material=BEAD_STEEL, approach=True)
    return tkey, f"dynamic-{dynamic_key(tkey, frequencies, steel, magnets, offsets)}.json"


def eddy_sources(geometry: SensorGeometry, options: MeshOptions | None, *,
                 store: Store | None = None,
                 start: FieldSolution | None = None) -> MechanismPotentials:
    """The bias on the eddy-current mesh (:func:`eddy_bias_solution`) and the mechanism
    sources :func:`dynamic_report` solves at each frequency (the static transducer's:
    stress at the geometry's contact load, the steel's JAS law, both mechanisms)."""
    from msens.magnetics.mechanisms import mechanism_potentials
    from msens.magnetics.steel_law import law_for_steel

    sol = eddy_bias_solution(geometry, options, store=store, start=start)
    return mechanism_potentials(sol, geometry, stress_force=geometry.beads.contact_load,
                                law=law_for_steel(geometry.steel))


def eddy_bias_solution(geometry: SensorGeometry, options: MeshOptions | None, *,
                       store: Store | None = None,
                       start: FieldSolution | None = None) -> FieldSolution:
    """The bias on the eddy-current mesh (``options``), Newton starting from the bias on the
    plain mesh (``options=None``), interpolated: a start close to the solution, and one that
    does not depend on what a caller has at hand. ``start``: that plain-mesh solution if the
    caller has it (e.g. :attr:`msens.magnetics.transducer.TransducerReport.bias`), else it
    is solved first; the same start either way, so the same result."""
    from msens.magnetics.transducer import bias_solution

    if options is None or options == MeshOptions():
        start = None  # the plain mesh itself: a cold start, as the static transducer's
    elif start is None:
        start, _ = bias_solution(geometry, store=store)
    sol, _ = bias_solution(geometry, options=options, store=store, start=start)
    return sol


def join_reports(parts: Sequence[DynamicReport]) -> DynamicReport:
    """One report from reports of the same model at different frequencies (each from 0 Hz).

    The 0 Hz rows of all but the first are dropped (they repeat it); frequencies must then
    increase. Checks are concatenated.
    """
    first = parts[0]
    responses = {}
    for p, r0 in first.responses.items():
        rows = [r0, *(part.responses[p] for part in parts[1:])]
        keep = [slice(None)] + [slice(1, None)] * (len(rows) - 1)

        def cat(field, rows=rows, keep=keep):
            return np.concatenate([np.asarray(getattr(r, field))[k] for r, k in
                                   zip(rows, keep, strict=True)])

        freqs = cat("frequencies")
        profiles = {}
        if r0.offsets is not None:
            def cat_o(field, rows=rows, keep=keep):
                return np.concatenate([np.asarray(getattr(r, field))[:, k] for r, k in
                                       zip(rows, keep, strict=True)], axis=1)

            profiles = {"offsets": r0.offsets, "villari_by_offset": cat_o("villari_by_offset"),
                        "approach_by_offset": cat_o("approach_by_offset")}
        internal(bool(np.all(np.diff(freqs) > 0)),
                 "internal: join_reports: frequencies must increase")
        responses[p] = FrequencyResponse(
            particle=r0.particle, frequencies=freqs, contacts=r0.contacts,
            villari=cat("villari"), approach=cat("approach"), impedance=cat("impedance"),
            resistance_ohm=r0.resistance_ohm, static_inductance_H=r0.static_inductance_H,
            source=r0.source.replace(f"at {np.asarray(r0.frequencies).size} frequencies",
                                     f"at {freqs.size} frequencies"),
            screening=next((part.responses[p].screening for part in parts
                            if part.responses[p].screening is not None), None), **profiles)
    details = dict(first.details)
    details["frequencies_Hz"] = responses[next(iter(responses))].frequencies.tolist()
    details["coils"] = {
        c: {k: [x for i, part in enumerate(parts)
                for x in part.details["coils"][c][k][(1 if i else 0):]]
            for k in chk}
        for c, chk in first.details["coils"].items()}
    details["tasks"] = len(parts)
    return DynamicReport(responses, details)


__all__ = [
    "DEFAULT_FREQUENCIES",
    "DYNAMIC_VERSION",
    "RESPONSE_OFFSET_STEP",
    "SCREENING_FREQUENCIES",
    "DynamicReport",
    "dynamic_key",
    "eddy_bias_solution",
    "eddy_sources",
    "equivalent_magnet_elements",
    "frequency_responses",
    "join_reports",
    "report_from_json",
    "report_name",
    "report_to_json",
    "screening_split",
    "sensor_conductivity",
]

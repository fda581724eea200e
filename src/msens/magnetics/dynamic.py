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

In time (:func:`dynamic_signals`) the contact force and approach rates are Fourier
transformed, multiplied by −S_c(ω) and −D_c(ω) (interpolated between the solved
frequencies, :meth:`FrequencyResponse.villari_at`) and by the read-out circuit's transfer
function with the coil's series impedance Z(ω)
(:func:`msens.readout.electronics.coil_transfer_function`).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft, rfftfreq
from scipy.interpolate import PchipInterpolator

from msens.errors import internal, require
from msens.field.eddy import SIGMA_1018, HarmonicOperator, dissipated_power
from msens.field.geometry import SensorGeometry
from msens.field.sensor_model import coil_current_density, coil_resistance
from msens.io._files import atomic_write_bytes
from msens.io.hashing import content_hash
from msens.magnetics.emf import ContactRates, contact_forces_of, contact_rates
from msens.magnetics.mechanisms import MechanismPotentials
from msens.magnetics.mss import MssRecord
from msens.magnetics.potentials import region_linkage
from msens.magnetics.transducer import Transducer
from msens.mechanics.hertz import hertz_approach
from msens.params.units import TWO_PI
from msens.readout.electronics import ReadoutCircuit, coil_transfer_function
from msens.readout.noise import NoiseModel, add_readout_noise

#: Frequencies solved by default, Hz: 0 (the static transducer), 12 roughly log-spaced
#: points over 0.5–200 kHz (1-2-3-5 steps, so the reported 1, 3, 10, 30, 100 kHz are solved)
#: and four below: a bead's own diffusion time μσR² is ~ 40 ms (1/(πμσR²) ≈ 8 Hz at μr 900),
#: so its bulk (Villari) response has already fallen to ~0.3 at 500 Hz and the interpolation
#: between 0 and 500 Hz needs points there.
DEFAULT_FREQUENCIES: tuple[float, ...] = (0.0, 10.0, 30.0, 100.0, 300.0, 500.0, 1e3, 2e3,
                                          3e3, 5e3, 10e3, 20e3, 30e3, 50e3, 100e3, 150e3,
                                          200e3)

#: Electrical conductivity of the magnet grades of
#: :data:`msens.params.materials.MAGNET_GRADES`, S/m.
#: ceramic8: hard ferrite is an oxide ceramic, an insulator for eddy-current purposes
#: (ASSUMPTION: resistivity of order 1e4 Ω m on typical ferrite data sheets — not measured;
#: any value below ~1 S/m gives no screening at 200 kHz in a 7 mm wall). NdFeB: resistivity
#: 150 µΩ cm, σ = 0.667 MS/m (Stanford Magnets, "Characteristics of NdFeB magnets", physical
#: properties table; 120–160 µΩ cm elsewhere).
MAGNET_CONDUCTIVITY: dict[str, float] = {"ceramic8": 0.0, "N38": 0.667e6, "N42": 0.667e6}


def sensor_conductivity(mesh, geometry: SensorGeometry, *, steel: float = SIGMA_1018,
                        magnets: Mapping[str, float] | None = None) -> np.ndarray:
    """Conductivity of every element of a sensor mesh, S/m, shape (n_elements,).

    Beads and pole pieces are the geometry's steel (``steel``, default 1018,
    :data:`msens.field.eddy.SIGMA_1018`); each magnet gets the conductivity of its grade
    (:data:`MAGNET_CONDUCTIVITY`, or ``magnets`` keyed by grade); air, coils (fine wire) and
    the tube (not a mesh region: air) are insulators.

    Parameters
    ----------
    mesh : AxiMesh
    geometry : SensorGeometry
    steel : float
        S/m.
    magnets : Mapping[str, float], optional
        Conductivity per magnet grade, S/m (overrides :data:`MAGNET_CONDUCTIVITY`).
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


# ----------------------------------------------------------------------------- record

def _interp(freqs: np.ndarray, values: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Complex values (n_f, ...) solved at ``freqs`` (freqs[0] = 0) at frequencies ``f``.

    Above the first nonzero frequency f1: PCHIP in log f on the real and imaginary parts
    (monotone between samples, no overshoot), held at the last value beyond the last
    frequency. Below f1 the low-frequency form of a response analytic in jω,
    v(f) = v0 + jωa − ω²b + …: Re v = v0 + (Re v1 − v0)(f/f1)², Im v = Im v1 (f/f1)
    — continuous at f1 and exact (the static value) at 0.
    """
    f = np.abs(np.asarray(f, dtype=float))
    v0, v1, f1 = values[0].real, values[1], freqs[1]
    out = np.empty(f.shape + values.shape[1:], dtype=complex)
    low = f < f1
    x = (f[low] / f1).reshape((-1,) + (1,) * (values.ndim - 1))
    out[low] = v0 + (v1.real - v0) * x**2 + 1j * v1.imag * x
    hi = ~low
    u = np.log(np.minimum(f[hi], freqs[-1]))
    lf = np.log(freqs[1:])
    if freqs.size > 2:
        out[hi] = (PchipInterpolator(lf, values[1:].real, axis=0)(u)
                   + 1j * PchipInterpolator(lf, values[1:].imag, axis=0)(u))
    else:
        out[hi] = v1
    return out


@dataclass(frozen=True)
class FrequencyResponse:
    """Small-signal frequency response of one coil of a physics MsS (eddy currents included).

    Attributes
    ----------
    particle : int
        Particle at the coil's centre.
    frequencies : ndarray, shape (n_f,)
        Solved frequencies, Hz, increasing; frequencies[0] = 0 (the static transducer).
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers (as :attr:`Transducer.contacts`).
    villari : ndarray of complex, shape (n_f, n_c)
        S_c(ω) = ∂Λ/∂F_c phasor ratio, Wb/N (Λ per force amplitude; lag = negative phase).
    approach : ndarray of complex, shape (n_f, n_c)
        D_c(ω) = ∂Λ/∂δ_c, Wb/m.
    impedance : ndarray of complex, shape (n_f,)
        Coil impedance Z(ω) = R_dc + jωΛ(ω)/I, Ω (eddy losses in Re Z).
    resistance_ohm : float
        R_dc, Ω (copper at 20 °C, as the static transducer).
    static_inductance_H : float
        Λ/I at 0 Hz: the incremental inductance at the bias point, H.
    source : str
        Model, conductivities and mesh the numbers come from.
    """

    particle: int
    frequencies: np.ndarray
    contacts: np.ndarray
    villari: np.ndarray
    approach: np.ndarray
    impedance: np.ndarray
    resistance_ohm: float
    static_inductance_H: float
    source: str = ""

    def __post_init__(self) -> None:
        f = np.asarray(self.frequencies, dtype=float)
        n_f, n_c = f.size, np.asarray(self.contacts).size
        require(n_f >= 2 and f[0] == 0.0 and bool(np.all(np.diff(f) > 0)),
                "FrequencyResponse needs increasing frequencies starting at 0 Hz (>= 2)")
        require(np.shape(self.villari) == (n_f, n_c) and np.shape(self.approach) == (n_f, n_c)
                and np.shape(self.impedance) == (n_f,),
                "internal: FrequencyResponse arrays must have shapes (n_f, n_c) and (n_f,)")

    @property
    def inductance(self) -> np.ndarray:
        """Complex inductance L(ω) = Λ(ω)/I = (Z − R_dc)/(jω), H, shape (n_f,); L(0) is the
        static incremental inductance (Z(0) = R_dc carries no inductance)."""
        w = TWO_PI * np.asarray(self.frequencies, dtype=float)
        out = np.empty(w.size, dtype=complex)
        out[0] = self.static_inductance_H
        out[1:] = (np.asarray(self.impedance[1:]) - self.resistance_ohm) / (1j * w[1:])
        return out

    def villari_at(self, f: np.ndarray) -> np.ndarray:
        """S_c at frequencies ``f`` (Hz, |f| used), Wb/N, shape (n, n_c) (see :func:`_interp`)."""
        return _interp(np.asarray(self.frequencies, float), np.asarray(self.villari), f)

    def approach_at(self, f: np.ndarray) -> np.ndarray:
        """D_c at frequencies ``f`` (Hz), Wb/m, shape (n, n_c)."""
        return _interp(np.asarray(self.frequencies, float), np.asarray(self.approach), f)

    def impedance_at(self, f: np.ndarray) -> np.ndarray:
        """Z at frequencies ``f`` (Hz), Ω, shape (n,) (:func:`coil_impedance`)."""
        return coil_impedance(self.frequencies, self.inductance, self.resistance_ohm, f)


def coil_impedance(frequencies: np.ndarray, inductance: np.ndarray,
                   resistance: float | np.ndarray, f: np.ndarray) -> np.ndarray:
    """Z = R_dc + jω L(ω) of one or many coils at frequencies ``f``, with the complex
    inductance L(ω) interpolated (it is smooth and finite at DC; Z/ω is not).

    Parameters
    ----------
    frequencies : ndarray, shape (n_f,)
        Solved frequencies, Hz, from 0.
    inductance : ndarray of complex, shape (n_f, ...)
        L(ω) at them, H.
    resistance : float or ndarray, shape (...)
        R_dc, Ω.
    f : ndarray, shape (n,)
        Hz.

    Returns
    -------
    ndarray of complex, shape (n, ...)
        Ω.
    """
    f = np.asarray(f, dtype=float)
    ind = _interp(np.asarray(frequencies, float), np.asarray(inductance), f)
    w = TWO_PI * f.reshape((-1,) + (1,) * (ind.ndim - 1))
    return resistance + 1j * w * ind


@dataclass(frozen=True)
class DynamicReport:
    """What :func:`frequency_responses` finds (also what the cache stores).

    Attributes
    ----------
    responses : dict of int -> FrequencyResponse
        One per coil, keyed by its particle.
    details : dict
        JSON-ready diagnostics: per coil and frequency the reciprocity error (direct source
        solves against the coil's own harmonic field) and the power balance; timings; dofs;
        conductivities.
    """

    responses: dict[int, FrequencyResponse]
    details: dict


def frequency_responses(model: MechanismPotentials, geometry: SensorGeometry,
                        frequencies: Sequence[float] = DEFAULT_FREQUENCIES, *,
                        sigma: np.ndarray | None = None, steel: float = SIGMA_1018,
                        magnets: Mapping[str, float] | None = None,
                        direct: bool = False) -> DynamicReport:
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
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    op = HarmonicOperator(sol, sigma)
    coils = [u.coil for u in geometry.iter_units()]
    regions = [f"coil_{c.particle}" for c in coils]
    # 1 A in each coil: J = N/S
    coil_loads = np.array([op.winding_load(r, coil_current_density(c))
                           for r, c in zip(regions, coils, strict=True)])
    timings["assembly"] = time.perf_counter() - t0
    n_f, n_s = freqs.size, model.rhs.shape[0]
    link = np.zeros((len(coils), n_f, n_s), dtype=complex)
    lam_self = np.zeros((len(coils), n_f), dtype=complex)
    checks = {str(c.particle): {"reciprocity_rel_error": [], "power_balance_rel_error": []}
              for c in coils}
    timings["factor"] = timings["solve"] = timings["post"] = 0.0
    for k, f in enumerate(freqs):
        t0 = time.perf_counter()
        fac = op.factor(f)
        t1 = time.perf_counter()
        own = op.solve(fac, coil_loads)
        pots = op.solve(fac, model.rhs) if direct else None
        t2 = time.perf_counter()
        for i, (c, r) in enumerate(zip(coils, regions, strict=True)):
            lam_self[i, k] = region_linkage(sol, own[i:i + 1], r, c.turns, c.area)[0]
            # reciprocity: K_t + jωM_σ is complex symmetric, Λ_s = 2π a_1ᵀ f_s (no conjugate)
            link[i, k] = TWO_PI * (model.rhs @ own[i])
            chk = checks[str(c.particle)]
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
        t3 = time.perf_counter()
        timings["factor"] += t1 - t0
        timings["solve"] += t2 - t1
        timings["post"] += t3 - t2
    out: dict[int, FrequencyResponse] = {}
    src = (f"msens.magnetics.dynamic {DYNAMIC_VERSION}: (K_t + jωM_σ) a_s = f_s at "
           f"{n_f} frequencies; σ steel {steel:.4g} S/m on beads and pole pieces, magnets "
           f"{dict(magnets or {}) or 'by grade'}; {sol.dofs} dofs")
    for i, c in enumerate(coils):
        contacts, vr, ar = model.contact_profiles(link[i].real)
        _, vi, ai = model.contact_profiles(link[i].imag)
        w = TWO_PI * freqs
        out[c.particle] = FrequencyResponse(
            particle=c.particle, frequencies=freqs, contacts=contacts, villari=vr + 1j * vi,
            approach=ar + 1j * ai, impedance=coil_resistance(c) + 1j * w * lam_self[i],
            resistance_ohm=coil_resistance(c), static_inductance_H=float(lam_self[i, 0].real),
            source=src)
    details = {"dofs": sol.dofs, "elements": mesh.n_elements, "frequencies_Hz": freqs.tolist(),
               "sigma_max_S_per_m": float(np.max(sigma)),
               "conducting_elements": int(np.count_nonzero(sigma)),
               "coils": checks, "timings_s": timings}
    return DynamicReport(out, details)


# ----------------------------------------------------------------------------- cache

#: Version of what :func:`frequency_responses` computes; part of the cache key.
DYNAMIC_VERSION = "dynamic/1"


def dynamic_key(transducer_key: str, frequencies: Sequence[float], steel: float,
                magnets: Mapping[str, float] | None) -> str:
    """Content hash (16 hex digits): the static transducer's key plus frequencies and σ."""
    payload = {"version": DYNAMIC_VERSION, "transducer": transducer_key,
               "frequencies": [repr(float(f)) for f in frequencies], "steel": repr(float(steel)),
               "magnets": {k: repr(float(v)) for k, v in
                           sorted({**MAGNET_CONDUCTIVITY, **(magnets or {})}.items())}}
    return content_hash(payload, 16)


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
                   "static_inductance_H": r.static_inductance_H, "source": r.source}
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
            static_inductance_H=float(v["static_inductance_H"]), source=str(v["source"]))
    return DynamicReport(out, data.get("details", {}))


def dynamic_report(geometry: SensorGeometry, *, options=None, cache_dir: str | Path | None = None,
                   mesh_dir: str | Path | None = None,
                   frequencies: Sequence[float] = DEFAULT_FREQUENCIES,
                   steel: float = SIGMA_1018, magnets: Mapping[str, float] | None = None,
                   refresh: bool = False, scheduler: str | None = None) -> DynamicReport:
    """Cached :func:`frequency_responses` of a geometry (``dynamic-<key>.json``).

    The sources are those of the default static transducer (:func:`transducer_report`'s
    defaults: stress at the geometry's contact load, the steel's JAS law, both mechanisms);
    lookup and storage follow :func:`msens.magnetics.transducer_cache.transducer_report`.

    With ``scheduler`` (a Dask distributed scheduler address) the frequencies are split into
    one chunk per worker; each task meshes (through the shared mesh cache ``mesh_dir``),
    solves the bias and the sources and then its frequencies, and the chunks are joined
    (:func:`join_reports`). The result equals the local one to round-off.
    """
    from msens.field.cache import committed_mesh_dirs, default_mesh_dir
    from msens.magnetics.steel_law import law_for_steel
    from msens.magnetics.transducer import cache_key
    from msens.params.materials import BEAD_STEEL

    tkey = cache_key(geometry, options, stress_force=geometry.beads.contact_load,
                     law=law_for_steel(geometry.steel), material=BEAD_STEEL, approach=True)
    name = f"dynamic-{dynamic_key(tkey, frequencies, steel, magnets)}.json"
    if cache_dir is not None:
        directory, search = Path(cache_dir), [Path(cache_dir)]
    else:
        directory = default_mesh_dir()
        search = [*committed_mesh_dirs(), directory]
    if not refresh:
        for d in search:
            if (d / name).is_file():
                return report_from_json(json.loads((d / name).read_text()))
    freqs = [float(f) for f in frequencies]
    if scheduler is None:
        rep = _report_task((geometry, options, mesh_dir, freqs, steel, magnets))
    else:
        from msens.parallel import run_tasks

        meshes = str(Path(mesh_dir or default_mesh_dir()).resolve())
        chunks = [c for c in np.array_split(np.asarray(freqs[1:]), _workers(scheduler))
                  if c.size]
        tasks = [(geometry, options, meshes, [0.0, *c.tolist()], steel, magnets)
                 for c in chunks]
        parts = dict(run_tasks(_report_task, tasks, scheduler=scheduler))
        rep = join_reports([parts[i] for i in range(len(tasks))])
    rep.details["transducer_key"] = tkey
    directory.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(directory / name, json.dumps(report_to_json(rep), indent=1).encode(),
                       overwrite=True)
    return rep


def _workers(scheduler: str) -> int:
    """Workers of a Dask scheduler (at least 1)."""
    from distributed import Client

    with Client(scheduler) as client:
        return max(1, len(client.scheduler_info()["workers"]))


def _report_task(args: tuple) -> DynamicReport:
    """Mesh, bias, sources and the harmonic solves of one list of frequencies (from 0)."""
    from msens.magnetics.mechanisms import mechanism_potentials
    from msens.magnetics.steel_law import law_for_steel
    from msens.magnetics.transducer import bias_solution

    geometry, options, mesh_dir, freqs, steel, magnets = args
    t0 = time.perf_counter()
    sol, _ = bias_solution(geometry, options=options, mesh_dir=mesh_dir)
    timings: dict[str, float] = {"mesh_and_bias_solve": time.perf_counter() - t0}
    model = mechanism_potentials(sol, geometry, stress_force=geometry.beads.contact_load,
                                 law=law_for_steel(geometry.steel), timings=timings)
    rep = frequency_responses(model, geometry, freqs, steel=steel, magnets=magnets)
    rep.details["timings_s"] = {**timings, **rep.details["timings_s"]}
    return rep


def join_reports(parts: Sequence[DynamicReport]) -> DynamicReport:
    """One report from reports of the same model at different frequencies (each from 0 Hz).

    The 0 Hz rows of all but the first are dropped (they repeat it); frequencies must then
    increase. Timings are summed, checks concatenated.
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
        internal(bool(np.all(np.diff(freqs) > 0)),
                 "internal: join_reports: frequencies must increase")
        responses[p] = FrequencyResponse(
            particle=r0.particle, frequencies=freqs, contacts=r0.contacts,
            villari=cat("villari"), approach=cat("approach"), impedance=cat("impedance"),
            resistance_ohm=r0.resistance_ohm, static_inductance_H=r0.static_inductance_H,
            source=r0.source.replace(f"at {np.asarray(r0.frequencies).size} frequencies",
                                     f"at {freqs.size} frequencies"))
    details = dict(first.details)
    details["frequencies_Hz"] = responses[next(iter(responses))].frequencies.tolist()
    timings: dict[str, float] = {}
    for part in parts:
        for k, v in part.details.get("timings_s", {}).items():
            timings[k] = timings.get(k, 0.0) + v
    details["timings_s"] = timings
    details["coils"] = {
        c: {k: [x for i, part in enumerate(parts)
                for x in part.details["coils"][c][k][(1 if i else 0):]]
            for k in chk}
        for c, chk in first.details["coils"].items()}
    details["tasks"] = len(parts)
    return DynamicReport(responses, details)


# ----------------------------------------------------------------------------- in time

#: FFT length of the frequency-domain read-out in record lengths (zero padding: the circuit's
#: ring-down after the record must fit in it; run and design use the same).
PAD = 2.0


def emf_spectra(frequencies: np.ndarray, villari: np.ndarray, approach: np.ndarray,
                f: np.ndarray, force_rate: np.ndarray, approach_rate: np.ndarray) -> np.ndarray:
    """EMF(ω) = −Σ_c [S_c(ω) Ḟ_c(ω) + D_c(ω) δ̇_c(ω)] of one or many coils.

    Parameters
    ----------
    frequencies : ndarray, shape (n_f,)
        Solved frequencies, Hz, from 0.
    villari, approach : ndarray of complex, shape (n_f, ..., n_c)
        S_c (Wb/N) and D_c (Wb/m) at them, interpolated to ``f`` by :func:`_interp`.
    f : ndarray, shape (n,)
        Hz.
    force_rate, approach_rate : ndarray of complex, shape (n, n_c)
        Spectra of dF_c/dt (N/s per bin) and dδ_c/dt (m/s per bin), the coils' contacts.

    Returns
    -------
    ndarray of complex, shape (n, ...)
    """
    freqs = np.asarray(frequencies, float)
    s, d = _interp(freqs, np.asarray(villari), f), _interp(freqs, np.asarray(approach), f)
    shape = (s.shape[0],) + (1,) * (s.ndim - 2) + (s.shape[-1],)
    return -(np.sum(s * np.reshape(force_rate, shape), axis=-1)
             + np.sum(d * np.reshape(approach_rate, shape), axis=-1))


def emf_spectrum(response: FrequencyResponse, f: np.ndarray, force_rate: np.ndarray,
                 approach_rate: np.ndarray) -> np.ndarray:
    """EMF(ω) of one coil (:func:`emf_spectra`), shape (n,).

    Parameters
    ----------
    response : FrequencyResponse
    f : ndarray, shape (n,)
        Hz.
    force_rate, approach_rate : ndarray of complex, shape (n, n_c)
        Spectra of dF_c/dt (N/s per bin) and dδ_c/dt (m/s per bin), the record's contacts.
    """
    return emf_spectra(response.frequencies, response.villari, response.approach, f,
                       force_rate, approach_rate)


def mechanism_emfs(response: FrequencyResponse, rates: ContactRates,
                   pad: float = PAD) -> dict[str, np.ndarray]:
    """Each mechanism's open-circuit EMF alone, with eddy currents, V.

    Parameters
    ----------
    response : FrequencyResponse
    rates : ContactRates
        Rates of ``response.contacts`` on uniform times.
    pad : float
        FFT length ≥ ``pad`` × nt, as :func:`dynamic_signals`.

    Returns
    -------
    dict
        ``"villari"`` and ``"approach"``: ndarray, shape (nt,); they add up to the EMF of
        :func:`dynamic_signals`.
    """
    t = np.asarray(rates.t)
    dt = (t[-1] - t[0]) / (t.size - 1)
    n = next_fast_len(math.ceil(pad * t.size), real=True)
    f = rfftfreq(n, dt)
    force = rfft(rates.force, n, axis=0)
    approach = rfft(rates.approach, n, axis=0)
    return {"villari": irfft(emf_spectrum(response, f, force, 0.0 * approach), n)[:t.size],
            "approach": irfft(emf_spectrum(response, f, 0.0 * force, approach), n)[:t.size]}


def dynamic_signals(transducer: Transducer, response: FrequencyResponse,
                    circuit: ReadoutCircuit, t: np.ndarray, force: np.ndarray,
                    sample_rate: float, *, approach: np.ndarray | None = None,
                    columns: np.ndarray | None = None, pad: float = PAD,
                    noise: NoiseModel | None = None,
                    rng: np.random.Generator | int | None = None) -> MssRecord:
    """Coil signals of one physics MsS with eddy currents: the frequency-domain read-out.

    The contact force and approach rates (as :func:`msens.magnetics.mss.mss_signals`) are
    zero-padded to ``pad`` × their length and Fourier transformed; the EMF spectrum is
    :func:`emf_spectrum` and the DAQ voltage that times the read-out transfer function with
    the coil's impedance Z(ω) (:func:`msens.readout.electronics.coil_transfer_function`); inverse
    FFT. The circuit starts at rest and the EMF is zero before ``t[0]`` (chain histories
    start static). Noise (optional) is the read-out's, with the coil's Johnson noise from
    4kT Re Z(f) (:func:`msens.readout.noise.add_readout_noise`). With σ = 0 this is
    :func:`~msens.magnetics.mss.mss_signals` up to its first-order-hold EMF (agreement to
    ~(ωΔt)²/12 at the signal frequencies).

    Parameters
    ----------
    transducer : Transducer
        Contacts and Hertz stiffness (and the static sensitivities of ``weighted_force``).
    response : FrequencyResponse
        Of the same coil (same contacts).
    circuit : ReadoutCircuit
        Winding capacitance, cable and DAQ (its R and L are replaced by Z(ω)).
    t : ndarray, shape (nt,)
        Uniform chain output times, s.
    force : ndarray, shape (nt, m)
        Contact forces, N.
    sample_rate : float
        DAQ rate, Hz: the voltage is linearly interpolated from the chain's grid to the DAQ
        instants t[0] + k/sample_rate (exact where the DAQ samples at the chain's rate).
    approach, columns
        As :func:`~msens.magnetics.mss.mss_signals` (no ``static``: the EMF needs rates only).
    pad : float
        FFT length ≥ ``pad`` × nt (> 1: the circuit's ring-down must fit in the padding).
    noise : NoiseModel, optional
    rng : numpy.random.Generator or int, optional
        Seed or generator of the noise (None = seed 0).

    Returns
    -------
    MssRecord
        ``flux`` is −∫ EMF dt (eddy currents included).
    """
    from scipy.integrate import cumulative_trapezoid

    contacts = np.asarray(transducer.contacts, dtype=int)
    require(np.array_equal(contacts, np.asarray(response.contacts)),
            "transducer and frequency response describe different contacts")
    require(pad > 1, f"pad must be > 1, got {pad}")
    t = np.asarray(t, dtype=float)
    fc = contact_forces_of(force, contacts, columns)
    stiff = transducer.contact_stiffness
    delta = (hertz_approach(fc, stiff) if approach is None
             else contact_forces_of(approach, contacts, columns))
    rates = contact_rates(t, fc, contacts, stiff, columns=contacts, approach=delta,
                          equivalent=transducer.equivalent_approach)
    dt = (t[-1] - t[0]) / (t.size - 1)
    require(bool(np.allclose(np.diff(t), dt, rtol=1e-6, atol=0.0)),
            "chain times must be uniformly spaced")
    n = next_fast_len(math.ceil(pad * t.size), real=True)
    f = rfftfreq(n, dt)
    e_hat = emf_spectrum(response, f, rfft(rates.force, n, axis=0),
                         rfft(rates.approach, n, axis=0))
    h = coil_transfer_function(circuit, f, response.impedance_at(f))
    e = irfft(e_hat, n)[:t.size]
    v = irfft(h * e_hat, n)[:t.size]
    n_daq = math.floor((t[-1] - t[0]) * sample_rate * (1 + 1e-12)) + 1
    t_daq = t[0] + np.arange(n_daq) / sample_rate
    flux = -cumulative_trapezoid(e, t, initial=0.0)
    total = float(np.sum(transducer.sensitivity("both")))
    voltage = np.interp(t_daq, t, v)
    if noise is not None:
        voltage = add_readout_noise(voltage, circuit, noise, sample_rate, rng=rng,
                                    coil_impedance=response.impedance_at)
    return MssRecord(t=t, flux=flux, weighted_force=flux / total if total else flux * np.nan,
                     emf=e, t_daq=t_daq, voltage=voltage, circuit=circuit)


__all__ = [
    "DEFAULT_FREQUENCIES",
    "DYNAMIC_VERSION",
    "MAGNET_CONDUCTIVITY",
    "PAD",
    "DynamicReport",
    "FrequencyResponse",
    "coil_impedance",
    "dynamic_key",
    "dynamic_report",
    "dynamic_signals",
    "emf_spectra",
    "emf_spectrum",
    "frequency_responses",
    "join_reports",
    "report_from_json",
    "report_to_json",
    "sensor_conductivity",
]

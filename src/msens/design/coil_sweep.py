"""Coil-only sweeps: one bias solve, then every coil design by quadrature (>= 1000/s).

The coil is a passive receiver and (magnetically) air, so the bias state, the Villari sources
and their incremental potentials a_i do not depend on the coil; by reciprocity
(:mod:`msens.design.reciprocity`) bead i's sensitivity for a coil of N turns on the rectangle
[r_in, r_out] × [z0, z1] is S_i = (N/S) ∫∫ 2π r a_i dr dz, read from a summed-area table.

Electrical data per design from :mod:`msens.coil`: R (copper, 20 °C), the winding's
self-capacitance estimate, and L = L_Wheeler × (L_inc/L_air) of the study's own coil — the
bias-point incremental inductance of the base coil (field model) over its air-core value,
i.e. the steel's share of the flux is taken to scale like the air-core flux (an approximation
of a few per cent for coils near the base design; magnet sweeps compute L_inc exactly).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from msens.coil import wheeler_inductance, winding_capacitance, winding_from_coil
from msens.design.cache import ResultCache, atomic_write_bytes, content_key
from msens.design.metrics import circuit_metrics, peak_emf
from msens.design.physics import (
    bias_state,
    gravity_static,
    magnetic_compression,
    study_wave,
    wave_speed_change,
)
from msens.design.reciprocity import (
    LinkageTable,
    contact_sensitivities,
    linkage_table,
    rect_integral,
)
from msens.design.sweep import Design, SweepSpec, design_unit
from msens.field.geometry import SensorGeometry, SensorUnit
from msens.field.regions import Winding
from msens.field.sensor_model import (
    coil_current_density,
    flux_linkage,
    regions_for,
)
from msens.field.solve import FieldSolution, MagnetostaticProblem, incremental, solve
from msens.fieldsetup import mss_setup
from msens.study import Study

#: Grid spacing of the linkage table, m (rectangle integrals converge as spacing²; 0.1 mm
#: gives < 1e-5 relative error against exact mesh quadrature for the paper's coil).
TABLE_SPACING = 0.1e-3
#: Designs evaluated (and cached) per chunk.
CHUNK = 2048


@dataclass(frozen=True)
class CoilContext:
    """Everything a coil design needs from the one solve.

    Attributes
    ----------
    table : LinkageTable
    contacts : ndarray, shape (n_c,)
        Contact numbers c covered (between beads c and c+1).
    force_rate : ndarray, shape (n_c, nt)
        dF_c/dt of the study's wave, N/s.
    z_center : float
        Axial position of the sensor bead's centre, m.
    inductance_ratio : float
        L_inc / L_air of the study's coil.
    precompression_N, precompression_max_N, wave_speed_change : float
        Magnetic static compression (mean over c_{p−2}..c_{p+1}, max) and the relative change
        of the solitary-wave speed it causes.
    """

    table: LinkageTable
    contacts: np.ndarray
    force_rate: np.ndarray
    z_center: float
    inductance_ratio: float
    precompression_N: float
    precompression_max_N: float
    wave_speed_change: float


def coil_inductances(sol: FieldSolution, geometry: SensorGeometry, unit: SensorUnit
                     ) -> tuple[float, float]:
    """Incremental (bias point) and air-core inductance of a coil in the mesh, H."""
    axi = sol.problem.mesh
    c = unit.coil
    name = f"coil_{c.particle}"
    j = coil_current_density(c)
    inc = flux_linkage(incremental(sol, {name: Winding(j)}), name, c)
    air = regions_for(geometry, list(axi.subdomains), magnets=False, steel=False)
    air[name] = Winding(j)
    return inc, flux_linkage(solve(MagnetostaticProblem(axi, air)), name, c)


def wave_summary(study: Study, sol: FieldSolution, geometry: SensorGeometry, particle: int,
                 contacts: Sequence[int]) -> dict:
    """Force rates at ``contacts`` and the magnetic precompression figures of one bias state."""
    setup = mss_setup(study)
    n = study.chain.n_particles
    comp, pf = magnetic_compression(sol, geometry, n)
    t, force, static = study_wave(study, setup, pf)
    idx = np.asarray(contacts) - 1
    rate = np.gradient(force[:, idx], t, axis=0).T
    own = slice(max(particle - 3, 0), particle + 1)  # c_{p-2} .. c_{p+1}
    grav = gravity_static(study, setup)
    peak_dyn = float(np.max(force[:, particle - 1] - static[particle - 1]))
    change = float(wave_speed_change(study, peak_dyn, grav[particle - 1],
                                     comp[particle - 1]))
    return {"force_rate": rate, "precompression_N": float(np.mean(comp[own])),
            "precompression_max_N": float(np.max(np.abs(comp[own]))),
            "wave_speed_change": change}


def _coil_box(unit: SensorUnit, designs: Sequence[Design], geometry: SensorGeometry
              ) -> tuple[tuple[float, float], tuple[float, float]]:
    rects = [geometry.coil_rect(design_unit(unit, d.values, geometry.tube)) for d in designs]
    pad = 2 * TABLE_SPACING
    return ((geometry.tube.outer_radius, max(q.r1 for q in rects) + pad),
            (min(q.z0 for q in rects) - pad, max(q.z1 for q in rects) + pad))


def build_context(study: Study, geometry: SensorGeometry, particle: int,
                  designs: Sequence[Design], mesh_dir: str | Path | None = None
                  ) -> CoilContext:
    """The one bias solve of a coil sweep and everything derived from it."""
    unit = next(u for u in geometry.sensors if u.coil.particle == particle)
    state = bias_state(geometry, particle, mesh_dir)
    r_rng, z_rng = _coil_box(unit, designs, geometry)
    table = linkage_table(state.solution, state.potentials, r_rng, z_rng, TABLE_SPACING)
    l_inc, l_air = coil_inductances(state.solution, geometry, unit)
    wave = wave_summary(study, state.solution, geometry, particle, state.contacts)
    return CoilContext(table=table, contacts=np.asarray(state.contacts),
                       force_rate=wave["force_rate"],
                       z_center=geometry.beads.center(particle), inductance_ratio=l_inc / l_air,
                       precompression_N=wave["precompression_N"],
                       precompression_max_N=wave["precompression_max_N"],
                       wave_speed_change=wave["wave_speed_change"])


def save_context(ctx: CoilContext, path: Path) -> None:
    """Atomic .npz of a context."""
    buf = io.BytesIO()
    np.savez(buf, r=ctx.table.r, z=ctx.table.z, cumulative=ctx.table.cumulative,
             contacts=ctx.contacts, force_rate=ctx.force_rate,
             scalars=np.array([ctx.z_center, ctx.inductance_ratio, ctx.precompression_N,
                               ctx.precompression_max_N, ctx.wave_speed_change]))
    atomic_write_bytes(path, buf.getvalue())


def load_context(path: Path) -> CoilContext:
    with np.load(path) as f:
        s = f["scalars"]
        return CoilContext(LinkageTable(f["r"], f["z"], f["cumulative"]), f["contacts"],
                           f["force_rate"], *map(float, s))


def evaluate(ctx: CoilContext, unit: SensorUnit, designs: Sequence[Design],
             geometry: SensorGeometry, study: Study) -> list[dict]:
    """Metrics of coil designs (no validation: :func:`msens.design.sweep.validate_designs`)."""
    units = [design_unit(unit, d.values, geometry.tube) for d in designs]
    coils = [u.coil for u in units]
    zc = np.array([ctx.z_center + c.axial_offset for c in coils])
    half = np.array([c.length / 2 for c in coils])
    r_in = np.array([c.inner_radius for c in coils])
    r_out = np.array([c.outer_radius for c in coils])
    turns = np.array([c.turns for c in coils], dtype=float)
    area = (r_out - r_in) * 2 * half
    beads = turns[:, None] / area[:, None] * rect_integral(ctx.table, r_in, r_out, zc - half,
                                                           zc + half)
    sens = contact_sensitivities(beads)
    elec = {}
    for c in coils:
        key = (c.turns, c.length, c.inner_radius, c.wire.name)
        if key not in elec:
            w = winding_from_coil(c.turns, c.length, c.inner_radius, c.wire.name,
                                  c.packing_factor, insulated_diameter=c.wire.insulated_diameter)
            elec[key] = (w.resistance(), wheeler_inductance(w), winding_capacitance(w))
    rlc = np.array([elec[(c.turns, c.length, c.inner_radius, c.wire.name)] for c in coils])
    inductance = rlc[:, 1] * ctx.inductance_ratio
    circ = circuit_metrics(rlc[:, 0], inductance, rlc[:, 2], study.electronics)
    emf = peak_emf(sens, ctx.force_rate)
    snr = emf * circ["dc_gain"] / circ["noise_rms_V"]
    rows = []
    for k in range(len(designs)):
        rows.append({
            "outer_radius_m": float(r_out[k]), "resistance_ohm": float(rlc[k, 0]),
            "inductance_H": float(inductance[k]), "inductance_air_H": float(rlc[k, 1]),
            "winding_capacitance_F": float(rlc[k, 2]),
            "resonance_Hz": float(circ["resonance_Hz"][k]),
            "quality_factor": float(circ["quality_factor"][k]),
            "bandwidth_Hz": float(circ["bandwidth_Hz"][k]),
            "noise_rms_V": float(circ["noise_rms_V"][k]),
            "sensitivity_Wb_per_N": float(np.sum(sens[k])),
            "peak_emf_V": float(emf[k]), "snr": float(snr[k]),
            "precompression_N": ctx.precompression_N,
            "precompression_max_N": ctx.precompression_max_N,
            "wave_speed_change": ctx.wave_speed_change,
            "contacts": [int(c) for c in ctx.contacts],
            "dLambda_dF_Wb_per_N": [float(v) for v in sens[k]],
        })
    return rows


def run_coil_sweep(study: Study, spec: SweepSpec, geometry: SensorGeometry, particle: int,
                   designs: Sequence[Design], cache: ResultCache, *,
                   mesh_dir: str | Path | None = None, progress: bool = True
                   ) -> tuple[list[dict], int]:
    """All coil designs' rows (with ``status``) and how many were computed afresh."""
    from tqdm import tqdm

    unit = next(u for u in geometry.sensors if u.coil.particle == particle)
    ckey = content_key("coil-context", study, geometry, particle, _coil_box(unit, designs,
                                                                          geometry))
    cpath = cache.directory / f"context-{ckey}.npz"
    if cpath.exists():
        ctx = load_context(cpath)
    else:
        ctx = build_context(study, geometry, particle, designs, mesh_dir)
        save_context(ctx, cpath)
    rows: list[dict] = []
    computed = 0
    chunks = [designs[k:k + CHUNK] for k in range(0, len(designs), CHUNK)]
    for chunk in tqdm(chunks, desc="coil designs", unit="chunk", disable=not progress):
        key = content_key("coil-chunk", ckey, [d.values for d in chunk])
        got = cache.get(key)
        if got is None:
            got = [{"status": "ok", **r} for r in evaluate(ctx, unit, chunk, geometry, study)]
            cache.put(key, got)
            got = cache.get(key)
            computed += len(chunk)
        rows.extend(got)
    return rows, computed


__all__ = ["CHUNK", "TABLE_SPACING", "CoilContext", "build_context", "coil_inductances",
           "evaluate", "run_coil_sweep", "wave_summary"]

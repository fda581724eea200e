"""Convergence of the eddy-current sensitivities under refinement at the bead surfaces.

Usage: ``python benchmarks/dynamic_mesh_convergence.py [skin sizes in µm ...]`` (default
none 80 40 20 10). One-sensor model (beads 9..17, coil and magnet on bead 13) with the default
mesh sizes plus a skin refinement (MeshOptions.skin_size, growing at skin_growth 0.25 from the
bead surfaces). Prints JSON: per mesh the elements, dofs, times, and D_c(f)/D_c(0), S_c(f)/S_c(0)
of contacts 12 and 13 and Z(f) at 10, 30, 100, 200 kHz. The skin depth at 100 kHz is ~20 µm
(μr ~ 1000, σ = 6 MS/m).
"""

from __future__ import annotations

import json
import sys
import tempfile
import time

import numpy as np

from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.magnetics.dynamic import frequency_responses
from msens.magnetics.mechanisms import mechanism_potentials
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import bias_solution
from msens.store import Store

FREQS = (0.0, 1e4, 3e4, 1e5, 2e5)


def one_sensor() -> SensorGeometry:
    return SensorGeometry(beads=BeadChain(first=9, last=17),
                          sensors=(SensorUnit(Coil(particle=13), BiasMagnet(particle=13)),),
                          air=AirBox(0.06, 0.05))


def run(skin_um: float | None, mesh_dir: str) -> dict:
    g = one_sensor()
    opts = MeshOptions(skin_size=None if skin_um is None else skin_um * 1e-6)
    t0 = time.perf_counter()
    sol, _ = bias_solution(g, options=opts, store=Store.at(mesh_dir))
    t1 = time.perf_counter()
    m = mechanism_potentials(sol, g, stress_force=g.beads.contact_load,
                             law=law_for_steel(g.steel))
    t2 = time.perf_counter()
    rep = frequency_responses(m, g, FREQS)
    t3 = time.perf_counter()
    r = rep.responses[13]
    k = np.searchsorted(r.contacts, [12, 13])
    d = r.approach[:, k] / r.approach[0, k]
    s = r.villari[:, k] / r.villari[0, k]
    return {"skin_um": skin_um, "elements": sol.problem.mesh.n_elements, "dofs": sol.dofs,
            "t_mesh_bias_s": t1 - t0, "t_sources_s": t2 - t1, "t_harmonic_s": t3 - t2,
            "frequencies_Hz": list(FREQS[1:]),
            "approach_abs": np.round(np.abs(d[1:]), 4).tolist(),
            "approach_phase_deg": np.round(np.degrees(np.angle(d[1:])), 2).tolist(),
            "villari_abs": np.round(np.abs(s[1:]), 4).tolist(),
            "villari_phase_deg": np.round(np.degrees(np.angle(s[1:])), 2).tolist(),
            "static_approach_Wb_per_m": r.approach[0, k].real.tolist(),
            "static_villari_Wb_per_N": r.villari[0, k].real.tolist(),
            "L_static_H": r.static_inductance_H,
            "Z_ohm": [[float(z.real), float(z.imag)] for z in r.impedance[1:]]}


def main(args: list[str]) -> list[dict]:
    sizes = [None if a == "none" else float(a) for a in (args or ["none", "80", "40", "20",
                                                                 "10"])]
    with tempfile.TemporaryDirectory() as tmp:
        out = []
        for s in sizes:
            out.append(run(s, tmp))
            print(json.dumps(out[-1]), file=sys.stderr, flush=True)
    return out


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1:]), indent=1))

"""Physics MsS transducer on a sensor model: Villari vs contact approach, checks, timings.

Usage: ``python benchmarks/transducer.py [small|box|default]`` (default ``box``: the default
geometry in a 40 mm x 30 mm air box). Prints JSON: bead sensitivities S_i near each coil,
the per-contact profile of both mechanisms, reciprocity vs linear and nonlinear direct
perturbation, the adjoint approach derivative vs a nonlinear re-solve, the static magnetic
force per particle and contact, and timings.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from msens.field.build import MeshOptions
from msens.field.geometry import (
    AirBox,
    BeadChain,
    BiasMagnet,
    Coil,
    SensorGeometry,
    SensorUnit,
)
from msens.field.sensor_model import bias_problem, load_mesh
from msens.field.solve import solve
from msens.transducer import compute_transducers
from msens.units import MU0
from msens.villari import (
    StressSampler,
    approach_flux_change,
    bead_state,
    bead_stress,
    nonlinear_flux_change,
    stress_magnetisation,
)

MU0_TWO_PI = MU0 * 2 * np.pi


def model(name: str) -> tuple[SensorGeometry, MeshOptions | None]:
    """The named test model."""
    if name == "small":
        g = SensorGeometry(beads=BeadChain(first=9, last=17),
                           sensors=(SensorUnit(Coil(particle=13), BiasMagnet(particle=13)),),
                           air=AirBox(0.06, 0.05))
        return g, MeshOptions(bead_size=0.6e-3, centre_size=0.3e-3, flat_fraction=0.8,
                              wedge_factor=4.0)
    if name == "box":
        return SensorGeometry(air=AirBox(0.04, 0.03)), None
    if name == "default":
        return SensorGeometry(), None
    raise SystemExit(f"unknown model {name!r}: use small, box or default")


def main(name: str = "box") -> dict:
    geometry, options = model(name)
    t0 = time.perf_counter()
    rep = compute_transducers(geometry, options=options)
    t_total = time.perf_counter() - t0
    out: dict = {"model": name, "total_s": t_total, **rep.details}
    # independent checks on the sensor beads: nonlinear re-solves
    axi, _ = load_mesh(geometry, options)
    sol = solve(bias_problem(geometry, axi), max_iter=40, tol=1e-11)
    bs = bead_stress(geometry, geometry.beads.contact_load)
    sampler = StressSampler(bs)
    checks = []
    for unit in geometry.iter_units():
        coil = unit.coil
        state = bead_state(sol, coil)
        p = coil.particle
        el = axi.subdomains[f"bead_{p}"]
        dm = stress_magnetisation(sol, state, sampler, el, geometry.beads.center(p))
        s = float(MU0_TWO_PI * np.sum(sol.disc.quad.w[el]
                                      * np.einsum("eqc,eqc->eq", state.h_coil[el], dm)))
        t1 = time.perf_counter()
        nl = nonlinear_flux_change(sol, el, dm, coil, 0.1)
        t2 = time.perf_counter()
        ap = approach_flux_change(sol, geometry, p, coil, 1e-9)
        t3 = time.perf_counter()
        tr = rep.transducers[p]
        k = list(tr.contacts).index(p)
        checks.append({"coil": p, "S_reciprocity": s, "S_nonlinear_fd": nl,
                       "rel_err": (nl - s) / s, "nonlinear_s": t2 - t1,
                       "dLambda_dapproach_adjoint": float(tr.approach_sensitivity[k]),
                       "dLambda_dapproach_resolve": ap,
                       "approach_rel_err": (ap - tr.approach_sensitivity[k])
                       / tr.approach_sensitivity[k], "approach_resolve_s": t3 - t2})
        near = [c for c in tr.contacts if abs(c - p) <= 3]
        idx = [list(tr.contacts).index(c) for c in near]
        out.setdefault("profiles", {})[str(p)] = {
            "contacts": [int(c) for c in near],
            "villari_Wb_per_N": tr.sensitivity_villari[idx].tolist(),
            "reluctance_Wb_per_N": tr.sensitivity_reluctance[idx].tolist(),
            "sum_villari": float(np.sum(tr.sensitivity_villari)),
            "sum_reluctance": float(np.sum(tr.sensitivity_reluctance)),
            "L_H": tr.inductance_H, "R_ohm": tr.resistance_ohm}
    out["checks"] = checks
    tr = next(iter(rep.transducers.values()))
    f = tr.magnetic_particle_force
    out["magnetic_particle_force_N"] = {int(i + 1): float(v) for i, v in enumerate(f) if v}
    out["magnetic_contact_compression_N"] = {int(c + 1): float(v)
                                             for c, v in enumerate(np.cumsum(f)) if f[c] or v}
    return out


if __name__ == "__main__":
    print(json.dumps(main(*sys.argv[1:2]), indent=1))

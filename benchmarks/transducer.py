"""Physics MsS transducer on a sensor model: Villari vs contact approach, checks, timings.

Usage: ``python benchmarks/transducer.py [small|box|default]`` (default ``box``: the default
geometry in a 40 mm x 30 mm air box). Prints JSON: bead sensitivities S_i near each coil,
the per-contact profile of both mechanisms, the source potentials against the adjoint
reading (``reciprocity_adjoint_rel_error``) and against nonlinear re-solves (Villari and
contact approach), the static magnetic force per particle and contact, and timings.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.magnetics.approach import approach_flux_change
from msens.magnetics.mechanisms import coil_linkage, mechanism_potentials
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import bias_solution, compute_transducers
from msens.magnetics.villari import nonlinear_flux_change


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
    sol, _ = bias_solution(geometry, options=options)
    m = mechanism_potentials(sol, geometry, stress_force=geometry.beads.contact_load,
                             law=law_for_steel(geometry.steel))
    nb = m.particles.size
    checks = []
    for unit in geometry.iter_units():
        coil = unit.coil
        p = coil.particle
        link = coil_linkage(m, coil)
        i = int(np.flatnonzero(m.particles == p)[0])
        k = int(np.flatnonzero(m.contacts == p)[0])
        el, mu0_dm = m.villari_sources[i]
        t1 = time.perf_counter()
        nl = nonlinear_flux_change(sol, el, mu0_dm, coil, 0.1)
        t2 = time.perf_counter()
        ap = approach_flux_change(sol, geometry, p, coil, 1e-9)
        t3 = time.perf_counter()
        checks.append({"coil": p, "S_potentials": float(link[i]), "S_nonlinear_fd": nl,
                       "rel_err": (nl - link[i]) / link[i], "nonlinear_s": t2 - t1,
                       "dLambda_dapproach_potentials": float(link[nb + k]),
                       "dLambda_dapproach_resolve": ap,
                       "approach_rel_err": (ap - link[nb + k]) / link[nb + k],
                       "approach_resolve_s": t3 - t2})
        tr = rep.transducers[p]
        near = [c for c in tr.contacts if abs(c - p) <= 3]
        idx = [list(tr.contacts).index(c) for c in near]
        out.setdefault("profiles", {})[str(p)] = {
            "contacts": [int(c) for c in near],
            "villari_Wb_per_N": tr.sensitivity_villari[idx].tolist(),
            "approach_Wb_per_N": tr.sensitivity_approach[idx].tolist(),
            "sum_villari": float(np.sum(tr.sensitivity_villari)),
            "sum_approach": float(np.sum(tr.sensitivity_approach)),
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

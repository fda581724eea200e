"""Convergence of the eddy-current model under refinement of each conducting region.

Usage::

    python benchmarks/dynamic_mesh_convergence.py [--one] [LEVEL ...]

A LEVEL is ``NAME=BEAD_UM/POLE_UM`` (skin sizes at the bead and at the pole-piece and magnet
surfaces, µm; ``POLE_UM`` ``-`` grades the beads only, the mesh before issue 33), or one of
the names of :data:`LEVELS` (default: all of them, in order). The geometry is the main
study's (``studies/paper-mss.toml``: coils on beads 13 and 18, each with its bridge magnet
and pole pieces); ``--one`` uses a one-sensor model (beads 9..17, coil and magnet on bead 13).

Prints JSON: per level the elements, dofs and times, and per coil the contact-approach
sensitivity of the contacts next to the coil (12 and 13 for coil 13, 17 and 18 for coil 18)
relative to static, D_c(f)/D_c(0), as magnitude and phase at 10, 30 and 100 kHz, and the coil's
eddy-loss resistance R_eddy = Re Z − R_dc and inductance L = Im Z/ω; then the differences
of each level from the finest (``reference``) and, for the pole refinement sequence
40 → 20 → 10 µm, the observed convergence order p = log2(|q40 − q20| / |q20 − q10|) of each
quantity (complex sensitivities, R_eddy, L).
"""

from __future__ import annotations

import json
import math
import sys
import tempfile
import time

import numpy as np

from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.magnetics.dynamic import eddy_bias_solution, frequency_responses
from msens.magnetics.mechanisms import mechanism_potentials
from msens.magnetics.steel_law import law_for_steel
from msens.store import Store, committed_dirs

FREQS = (0.0, 1e4, 3e4, 1e5)

#: Refinement levels: name -> (bead skin size, pole/magnet skin size or None = beads only), µm.
LEVELS: dict[str, tuple[float, float | None]] = {
    "beads-only-40": (40.0, None),  # the eddy mesh before issue 33
    "all-40": (40.0, 40.0),  # every conducting surface at the former default
    "all-30": (30.0, 30.0),  # the default (SKIN_SIZE at every conducting surface)
    "poles-20": (40.0, 20.0),
    "poles-10": (40.0, 10.0),
    "beads-20": (20.0, 10.0),  # the reference: beads refined too
}
#: The sequence the observed order is measured on (pole skin size halved twice).
ORDER_SEQUENCE = ("all-40", "poles-20", "poles-10")


def one_sensor() -> SensorGeometry:
    return SensorGeometry(beads=BeadChain(first=9, last=17),
                          sensors=(SensorUnit(Coil(particle=13), BiasMagnet(particle=13)),),
                          air=AirBox(0.06, 0.05))


def main_study() -> SensorGeometry:
    from msens.config.fieldsetup import geometry_from_study
    from msens.config.study import load_study

    return geometry_from_study(load_study("studies/paper-mss.toml"))


def options_for(bead_um: float, pole_um: float | None) -> MeshOptions:
    if pole_um is None:
        return MeshOptions(skin_size=bead_um * 1e-6, skin_parts="beads")
    return MeshOptions(skin_size=bead_um * 1e-6, pole_skin_size=pole_um * 1e-6)


def run(name: str, bead_um: float, pole_um: float | None, g: SensorGeometry,
        store: Store) -> dict:
    opts = options_for(bead_um, pole_um)
    t0 = time.perf_counter()
    sol = eddy_bias_solution(g, opts, store=store)
    t1 = time.perf_counter()
    m = mechanism_potentials(sol, g, stress_force=g.beads.contact_load,
                             law=law_for_steel(g.steel))
    t2 = time.perf_counter()
    rep = frequency_responses(m, g, FREQS)
    t3 = time.perf_counter()
    coils = {}
    w = 2 * math.pi * np.asarray(FREQS[1:])
    for p, r in rep.responses.items():
        cs = [p - 1, p]
        k = np.searchsorted(r.contacts, cs)
        d = r.approach[1:, k] / r.approach[0, k]
        z = np.asarray(r.impedance[1:])
        coils[str(p)] = {
            "contacts": cs,
            "approach_rel": {str(c): {"abs": np.abs(d[:, j]).tolist(),
                                      "phase_deg": np.degrees(np.angle(d[:, j])).tolist(),
                                      "re": d[:, j].real.tolist(), "im": d[:, j].imag.tolist()}
                             for j, c in enumerate(cs)},
            "R_eddy_ohm": (z.real - r.resistance_ohm).tolist(),
            "L_H": (z.imag / w).tolist(), "L_static_H": r.static_inductance_H}
    return {"level": name, "bead_skin_um": bead_um, "pole_skin_um": pole_um,
            "elements": sol.problem.mesh.n_elements, "dofs": sol.dofs,
            "t_mesh_bias_s": round(t1 - t0, 1), "t_sources_s": round(t2 - t1, 1),
            "t_harmonic_s": round(t3 - t2, 1), "frequencies_Hz": list(FREQS[1:]),
            "coils": coils}


def _quantities(row: dict) -> dict[str, np.ndarray]:
    """Per coil: complex relative sensitivities of its contacts, R_eddy, L (each per f)."""
    out = {}
    for p, c in row["coils"].items():
        for ct, a in c["approach_rel"].items():
            out[f"coil {p} contact {ct}"] = np.asarray(a["re"]) + 1j * np.asarray(a["im"])
        out[f"coil {p} R_eddy"] = np.asarray(c["R_eddy_ohm"])
        out[f"coil {p} L"] = np.asarray(c["L_H"])
    return out


def compare(rows: list[dict]) -> dict:
    """Differences from the finest level, and the observed order on :data:`ORDER_SEQUENCE`."""
    by = {r["level"]: _quantities(r) for r in rows}
    ref_name = rows[-1]["level"]
    ref = by[ref_name]
    diffs = {}
    for name, q in by.items():
        d = {}
        for key, v in q.items():
            r = ref[key]
            if np.iscomplexobj(v):
                d[key] = {"rel_abs_pct": np.round(100 * (np.abs(v) / np.abs(r) - 1), 2).tolist(),
                          "phase_deg": np.round(np.degrees(np.angle(v / r)), 2).tolist()}
            else:
                d[key] = {"rel_pct": np.round(100 * (v / r - 1), 2).tolist()}
        diffs[name] = d
    order = {}
    if all(n in by for n in ORDER_SEQUENCE):
        a, b, c = (by[n] for n in ORDER_SEQUENCE)
        for key in a:
            e1, e2 = np.abs(a[key] - b[key]), np.abs(b[key] - c[key])
            with np.errstate(divide="ignore", invalid="ignore"):
                order[key] = np.round(np.log2(e1 / e2), 2).tolist()
    return {"reference": ref_name, "differences_from_reference": diffs,
            "observed_order_in_pole_skin_size": order}


def _parse(arg: str) -> tuple[str, float, float | None]:
    if arg in LEVELS:
        return (arg, *LEVELS[arg])
    name, _, sizes = arg.partition("=")
    bead, _, pole = sizes.partition("/")
    return name, float(bead), None if pole in ("", "-") else float(pole)


def main(args: list[str]) -> dict:
    one = "--one" in args
    args = [a for a in args if a != "--one"]
    levels = [_parse(a) for a in (args or list(LEVELS))]
    g = one_sensor() if one else main_study()
    with tempfile.TemporaryDirectory() as tmp:
        store = Store.at(tmp, committed=committed_dirs())
        rows = []
        for name, bead, pole in levels:
            rows.append(run(name, bead, pole, g, store))
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    return {"geometry": "one-sensor" if one else "studies/paper-mss.toml", "levels": rows,
            **compare(rows)}


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1:]), indent=1))

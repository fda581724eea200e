"""Convergence, cross-checks and sensitivity of the MsS field model; prints JSON.

    python benchmarks/field_model_convergence.py [--quick]

Measured against the default model (paper sensors at 13 and 18, equivalent ceramic-8 magnet):

- ``beads``: modelled bead range (5, 7, 9 beads beyond the sensors) against all 2..30 (default);
- ``box``: air-box radius and margin (x0.5, x2, x4 of the default 0.32 m / 0.24 m);
- ``flat``: contact flat radius 50 -> 6.25 um;
- ``mesh``: all mesh sizes halved; finer far air; contacts far from the coils as fine as near;
- ``gap``: touching flats vs air gaps of 4, 1, 0.25 um between them;
- ``cross_check``: in a gapped model, eggshell Maxwell stress vs virtual work (energy
  difference on morphed meshes, different shell) and eggshell shell-width independence;
- ``sensitivity``: one-at-a-time +10 % changes of the magnet/pole dimensions and remanence,
  as elasticities (dF/F)/(dp/p) of the mean force on the four sensor contacts.

Quantities compared: B_z at the centres of beads 11..20 (two beads either side of each sensor)
and the magnetic compression of the contacts 11-12 .. 19-20. Changes are max relative changes
against the reference run of each study.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from dataclasses import replace

import numpy as np

from msens.field import sensor_model as sm
from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, SensorGeometry
from msens.store import Store

SENSOR_BEADS = tuple(range(11, 21))
SENSOR_CONTACTS = tuple((p, p + 1) for p in range(11, 20))
FOUR_13 = ((11, 12), (12, 13), (13, 14), (14, 15))
FOUR_18 = ((16, 17), (17, 18), (18, 19), (19, 20))


def run(geometry: SensorGeometry, mesh_dir: str, options: MeshOptions | None = None) -> dict:
    """Bias solve and the compared quantities of one model."""
    t0 = time.perf_counter()
    axi, _ = sm.load_mesh(geometry, options, Store.at(mesh_dir))
    t1 = time.perf_counter()
    sol = sm.solve(sm.bias_problem(geometry, axi), max_iter=40)
    t2 = time.perf_counter()
    beads = {b.particle: b.B_center_T[1] for b in sm.bead_fields(sol, geometry)}
    forces = {(c.upper, c.lower): c.magnetic_force_N
              for c in sm.magnetic_contact_forces(sol, geometry, SENSOR_CONTACTS)}
    return {"Bz": [beads[p] for p in SENSOR_BEADS],
            "force": [forces[c] for c in SENSOR_CONTACTS],
            "mean_force_13": float(np.mean([forces[c] for c in FOUR_13])),
            "mean_force_18": float(np.mean([forces[c] for c in FOUR_18])),
            "dofs": sol.dofs, "elements": axi.n_elements, "iterations": sol.iterations,
            "t_mesh_s": t1 - t0, "t_solve_s": t2 - t1, "_sol": sol}


def change(a: dict, b: dict) -> dict:
    """Max relative change of bead fields and contact forces from ``b`` (reference) to ``a``."""
    def rel(x, y):
        x, y = np.asarray(x), np.asarray(y)
        return float(np.max(np.abs(x - y)) / np.max(np.abs(y)))
    return {"Bz": rel(a["Bz"], b["Bz"]), "force": rel(a["force"], b["force"])}


def public(r: dict) -> dict:
    return {k: v for k, v in r.items() if not k.startswith("_")}


def main(quick: bool = False) -> dict:
    tmp = tempfile.mkdtemp(prefix="msens-field-bench-")
    base_geom = SensorGeometry()
    base = run(base_geom, tmp)
    out: dict = {"reference": public(base), "sensor_beads": SENSOR_BEADS,
                 "sensor_contacts": SENSOR_CONTACTS}

    # modelled beads
    full = base  # the default models the whole chain 2..30
    out["beads"] = {"all_2_30": public(full)}
    for pad in (5, 7, 9):
        g = replace(base_geom, beads=replace(base_geom.beads, first=13 - pad, last=18 + pad))
        r = full if (13 - pad <= 2 and 18 + pad >= 30) else run(g, tmp)
        out["beads"][f"pad_{pad}"] = {"first": 13 - pad, "last": 18 + pad,
                                      "change_vs_all": change(r, full)}

    # air box
    out["box"] = {}
    for f in (0.5, 2.0):
        g = replace(base_geom, air=AirBox(base_geom.air.radius * f, base_geom.air.margin * f))
        out["box"][f"x{f}"] = {"radius_m": g.air.radius, "margin_m": g.air.margin,
                               "change_vs_default": change(run(g, tmp), base)}
    big = replace(base_geom, air=AirBox(base_geom.air.radius * 4, base_geom.air.margin * 4))
    out["box"]["x4"] = {"radius_m": big.air.radius, "margin_m": big.air.margin,
                        "change_vs_default": change(run(big, tmp), base)}

    # contact flat radius
    flats = {}
    runs = {}
    for a in (50e-6, 25e-6, 12.5e-6, 6.25e-6):
        g = replace(base_geom, beads=replace(base_geom.beads, contact_load=1e-9,
                                             min_flat_radius=a))
        runs[a] = run(g, tmp)
    for a, r in runs.items():
        flats[f"{a * 1e6:g}um"] = {"mean_force_13": r["mean_force_13"],
                                   "Bz_13": r["Bz"][SENSOR_BEADS.index(13)],
                                   "change_vs_6.25um": change(r, runs[6.25e-6]),
                                   "elements": r["elements"]}
    out["flat"] = flats

    # mesh refinement
    if not quick:
        rf = run(base_geom, tmp, MeshOptions().scaled(0.5))
        out["mesh"] = {"halved": {"dofs": rf["dofs"], "change_vs_default": change(base, rf)},
                       "far_air_finer": {"change_vs_default": change(
                           base, run(base_geom, tmp, MeshOptions(far_growth=0.15,
                                                                 far_size=3e-3)))},
                       "uniform_contacts": {"change_vs_default": change(
                           base, run(base_geom, tmp, MeshOptions(far_contact_factor=1.0)))}}

    # gaps between flats (bodies isolated by air) and the force cross-checks
    gaps = {}
    gap_runs = {}
    for gap in (4e-6, 1e-6, 0.25e-6):
        g = replace(base_geom, beads=replace(base_geom.beads, contact_gap=gap))
        gap_runs[gap] = (g, run(g, tmp))
        gaps[f"{gap * 1e6:g}um"] = {"change_vs_touching": change(gap_runs[gap][1], base),
                                    "dofs": gap_runs[gap][1]["dofs"]}
    out["gap"] = gaps
    g, r = gap_runs[1e-6]
    sol = r["_sol"]
    checks = []
    for upper in (12, 17):
        group = [f"bead_{p}" for p in range(g.beads.first, upper + 1)]
        egg = sm.group_force(sol, group)
        vw = sm.virtual_work_force(sol, group, delta=1e-8, layers=3)
        checks.append({"contact": [upper, upper + 1], "eggshell_N": egg,
                       "virtual_work_N": vw, "rel_diff": abs(vw - egg) / abs(egg)})
    sol0 = base["_sol"]
    shells = []
    for upper in (12, 17):
        group = [f"bead_{p}" for p in range(base_geom.beads.first, upper + 1)]
        flat = [f"contact_{upper}_{upper + 1}"]
        f = [sm.group_force(sol0, group, flat, layers=k) for k in (0, 2)]
        shells.append({"contact": [upper, upper + 1], "layers_0_N": f[0], "layers_2_N": f[1],
                       "rel_diff": abs(f[1] - f[0]) / abs(f[0])})
    out["cross_check"] = {"gap_1um_virtual_work": checks, "touching_shell_width": shells}

    # one-at-a-time sensitivity (+10 %) of the mean force on the four contacts of sensor 13
    def magnets(**kw):
        return tuple(replace(u, magnet=replace(u.magnet, **kw)) for u in base_geom.sensors)

    m = base_geom.sensors[0].magnet
    sens = {}
    cases = {
        "remanence": dict(remanence=m.remanence * 1.1),
        "magnet_length": dict(length=m.length * 1.1),
        "magnet_inner_radius": dict(inner_radius=m.inner_radius * 1.1),
        "magnet_outer_radius": dict(outer_radius=m.outer_radius * 1.1,
                                    pole_outer_radius=m.pole_outer_radius * 1.1),
        "pole_thickness": dict(pole_thickness=m.pole_thickness * 1.1),
        "pole_inner_radius": dict(pole_inner_radius=m.pole_inner_radius * 1.1),
    }
    f0 = base["mean_force_13"]
    for name, kw in cases.items():
        try:
            rr = run(replace(base_geom, sensors=magnets(**kw)), tmp)
        except Exception as exc:  # e.g. a +10 % part now overlaps its neighbour
            sens[name] = {"error": str(exc)}
            continue
        sens[name] = {"mean_force_13": rr["mean_force_13"],
                      "elasticity": (rr["mean_force_13"] / f0 - 1) / 0.1}
    rr = run(replace(base_geom, sensors=magnets(axial_offset=1e-3)), tmp)
    sens["axial_offset_+1mm"] = {"mean_force_13": rr["mean_force_13"],
                                 "relative_change": rr["mean_force_13"] / f0 - 1}
    rr = run(replace(base_geom, beads=replace(base_geom.beads, contact_load=1e-9,
                                              min_flat_radius=2 * base_geom.beads.flat_radius)),
             tmp)
    sens["flat_radius_x2"] = {"mean_force_13": rr["mean_force_13"],
                              "relative_change": rr["mean_force_13"] / f0 - 1}
    for grade in ("N38",):
        from msens.params.materials import MAGNET_GRADES
        gr = MAGNET_GRADES[grade]
        rr = run(replace(base_geom, sensors=magnets(grade=grade, remanence=gr.remanence,
                                                    recoil_permeability=gr.recoil_permeability)),
                 tmp)
        sens[f"grade_{grade}"] = {"mean_force_13": rr["mean_force_13"],
                                  "Bz_13": rr["Bz"][SENSOR_BEADS.index(13)],
                                  "iterations": rr["iterations"]}
    out["sensitivity"] = {"reference_mean_force_13_N": f0, "paper_N": 1.8, "cases": sens}
    return out


if __name__ == "__main__":
    print(json.dumps(main(quick="--quick" in sys.argv), indent=1, default=float))

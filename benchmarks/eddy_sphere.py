"""Conducting permeable sphere in a uniform field H0 e^{jωt}: FE vs exact; prints JSON.

    python benchmarks/eddy_sphere.py [--convergence]

Sphere R = 2.38 mm (the paper's bead), σ = 6 MS/m (1018 steel, msens.params.materials.SIGMA_1018),
μ_r = 100 and 1000, f = 0, 1, 10, 100 kHz; H0 = 1 A/m imposed as A_φ = μ0 H0 r/2 on a half
circle of 10 R, truncation removed exactly (msens.field.eddy_sphere.truncation_factor).
Mesh: a graded skin layer (first row 2.5 µm, ×1.3 per row) under the surface, 96 cells on the
half circle (msens.field.eddy_geometry). Per (μ_r, f): FE and exact moment m (A m²) and volume-mean
internal H_z (A/m) as magnitude and phase (degrees, e^{jωt}), relative magnitude and phase
errors, the loss and −(ωμ0/2) Im(m H0*), dofs, and the factorisation + solve time (best of
``REPEATS``; the machine is shared). ``--convergence`` adds the moment under radial
refinement of the layer at 100 kHz, μ_r = 1000 (observed order from successive differences).
"""

from __future__ import annotations

import json
import math
import sys
import time

import numpy as np

REPEATS = 3
RADIUS = 2.38e-3
R_OUT = 10 * RADIUS


def _polar(z: complex) -> dict:
    return {"abs": abs(z), "phase_deg": math.degrees(np.angle(z))}


def table() -> dict:
    from msens.field.eddy_geometry import layered_sphere_mesh, skin_layer
    from msens.field.eddy_sphere import sphere_check

    layer = skin_layer(RADIUS, 2.5e-6, 1.3, 96)
    t0 = time.perf_counter()
    mesh = layered_sphere_mesh(RADIUS, layer, R_OUT)
    t_mesh = time.perf_counter() - t0
    rows = []
    for mu_r in (100.0, 1000.0):
        runs = []
        for _ in range(REPEATS):
            t0 = time.perf_counter()
            checks = sphere_check(mesh, RADIUS, R_OUT, mu_r, (0.0, 1e3, 1e4, 1e5))
            runs.append((checks, time.perf_counter() - t0))
        for c in runs[0][0]:
            em, eh = c.moment_errors, c.h_mean_errors
            rows.append({
                "mu_r": mu_r, "frequency_hz": c.frequency, "skin_depth_um": c.skin_depth * 1e6,
                "moment_fe": _polar(c.moment), "moment_exact": _polar(c.moment_exact),
                "moment_rel_err": em[0], "moment_phase_err_deg": em[1],
                "h_mean_fe": _polar(c.h_mean), "h_mean_exact": _polar(c.h_mean_exact),
                "h_mean_rel_err": eh[0], "h_mean_phase_err_deg": eh[1],
                "loss_w": c.power, "loss_from_moment_w": c.power_identity,
                "dofs": c.dofs,
            })
        rows[-1]["setup_and_4_solves_s"] = min(r[1] for r in runs)
    return {"mesh": {"first_row_um": layer.first * 1e6, "ratio": layer.ratio,
                     "rows": layer.rows, "arc_segments": layer.arc_segments,
                     "elements": mesh.n_elements, "r_out_over_R": R_OUT / RADIUS,
                     "mesh_s": t_mesh},
            "max_rel_err": max(max(r["moment_rel_err"], r["h_mean_rel_err"]) for r in rows),
            "max_phase_err_deg": max(max(r["moment_phase_err_deg"], r["h_mean_phase_err_deg"])
                                     for r in rows),
            "rows": rows}


def convergence(levels: int = 5) -> dict:
    from msens.field.eddy_geometry import SkinLayer, layered_sphere_mesh
    from msens.field.eddy_sphere import conducting_sphere, sphere_check
    from msens.params.materials import SIGMA_1018

    exact = conducting_sphere(RADIUS, 1000.0, SIGMA_1018, 1e5)[0]
    out, m = [], []
    for k in range(levels):
        layer = SkinLayer(16e-6 / 2**k, 1.6 ** (1 / 2**k), 3 * 2**k, 128)
        (c,) = sphere_check(layered_sphere_mesh(RADIUS, layer, R_OUT), RADIUS, R_OUT,
                            1000.0, [1e5])
        m.append(c.moment)
        out.append({"first_row_um": layer.first * 1e6, "rows": layer.rows, "dofs": c.dofs,
                    "moment_rel_err": c.moment_errors[0],
                    "moment_phase_err_deg": c.moment_errors[1]})
    diff = np.abs(np.diff(m)) / abs(exact)
    return {"mu_r": 1000.0, "frequency_hz": 1e5, "arc_segments": 128, "levels": out,
            "successive_rel_diff": diff.tolist(),
            "observed_order": np.log2(diff[:-1] / diff[1:]).tolist()}


if __name__ == "__main__":
    result = table()
    if "--convergence" in sys.argv[1:]:
        result["layer_convergence"] = convergence()
    print(json.dumps(result, indent=2))

"""Bead stress solver: cost and accuracy under refinement (prints JSON).

Problem: a 4.76 mm steel bead (msens.params.materials.BEAD_STEEL) squeezed by two opposite Hertz
contacts of force F. For refine = 0..4 (all element sizes halved per level) it reports the
displacement unknowns, the wall time of mesh + assembly + solve + stress projection (best of
3), the relative errors of the mean axial stress (against the exact mean-stress-theorem value
for this load) and of sigma_zz at the pole (against -p0, the exact traction there), and the
stress at the bead centre per newton.

Run: python benchmarks/beadstress.py [F_newton]
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from msens.mechanics.beadstress import solve_bead_stress
from msens.mechanics.stress_sampling import mean_stress, mean_stress_exact, stress_at
from msens.params.materials import BEAD_STEEL

R = 2.38e-3


def main(force: float = 10.0, levels: int = 5) -> dict:
    rows = []
    for k in range(levels):
        best, bs = np.inf, None
        for _ in range(3 if k < 4 else 1):
            t0 = time.perf_counter()
            bs = solve_bead_stress(R, BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio,
                                   force, refine=k)
            best = min(best, time.perf_counter() - t0)
        ms = mean_stress(bs)
        exact = mean_stress_exact(R, force, bs.contact_radius)
        centre = stress_at(bs, 0.0, 0.0) / force
        rows.append({
            "refine": k,
            "dofs": bs.ndofs,
            "solve_s": round(best, 3),
            "mean_zz_rel_error": float(ms["zz"] / exact - 1),
            "pole_zz_rel_error": float(stress_at(bs, 0.0, R)[1] / bs.peak_pressure + 1),
            "centre_pa_per_n": {"rr": float(centre[0]), "zz": float(centre[1])},
        })
    return {
        "benchmark": "beadstress",
        "radius_m": R,
        "force_n": force,
        "contact_radius_m": bs.contact_radius,
        "peak_pressure_pa": bs.peak_pressure,
        "mean_zz_point_load_pa": mean_stress_exact(R, force),
        "rows": rows,
    }


if __name__ == "__main__":
    print(json.dumps(main(float(sys.argv[1]) if len(sys.argv) > 1 else 10.0), indent=1))

"""Nonlinear contact map Λ_c(δ) of the main study against full nonlinear solves (prints JSON).

For each contact near a coil of ``studies/paper-mss.toml``: the chain's approach range δ_c(t)
(static, most negative, peak), the tables of :mod:`msens.magnetics.contact_map` on the
contact's layer mesh, and the acceptance checks:

- table against full nonlinear solves at three pulse loads (7, 8.5, 10 N: Hertz δ) and one
  open gap (the most negative δ of the chain's contacts near the coil), none a table node;
  error = |table − solve| / |solve change|, the change being Λ(δ) − Λ(δ_static) at the
  chain's static δ of the contact;
- superposition: the contact at the open gap and its lower neighbour at the 10 N approach
  in one solve, against the sum of the two single-contact changes (same mesh);
- nonlinearity: the map's slope at the open gap and at the peak approach over its slope at
  the static approach, and the largest deviation of the map from its tangent at the static
  approach over the pulse's range, relative to the map's range there.

Run: ``python benchmarks/contact_map.py [--contacts 10 11 ...]`` (about 1.5 min per contact
on one core, plus the chain run).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from msens.field.cache import geometry_key
from msens.fieldsetup import geometry_from_study
from msens.magnetics.approach import hertz_stiffness
from msens.magnetics.contact_map import contact_flux, contact_map, layer_model, state_flux
from msens.mechanics.hertz import hertz_approach
from msens.pipeline import (
    calibrate_dissipation,
    output_times,
    setup_transducers,
    simulate_setup,
)
from msens.study import load_study

STUDY = "studies/paper-mss.toml"
LOADS = (7.0, 8.5, 10.0)
STEEL_NODES = (0.0, 0.5e-6, 1.0e-6, 1.5e-6, 2.0e-6, 2.5e-6)
AIR_GAPS = (1e-9, 0.05e-6, 0.2e-6, 0.5e-6, 1e-6, 2e-6, 4e-6, 6e-6, 9e-6, 13e-6, 18e-6)


def chain_approaches(study) -> tuple[np.ndarray, dict]:
    """The chain's contact approaches δ_c(t) (nt, n_contacts), m, and its setup's transducers."""
    t = output_times(study)
    fit = calibrate_dissipation(study, t)
    gc = fit.gamma_c if fit is not None else study.chain.gamma_contact
    gw = fit.gamma_w if fit is not None else study.chain.gamma_wall
    setup = study.setups[0]
    transducers = setup_transducers(study, setup)
    _, history = simulate_setup(study, setup, t, gamma_contact=gc, gamma_wall=gw,
                                transducers=transducers)
    return np.asarray(history.approach), transducers


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--contacts", type=int, nargs="*",
                        default=[10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20])
    args = parser.parse_args()
    study = load_study(STUDY)
    geometry = geometry_from_study(study)
    coils = {u.coil.particle: u.coil for u in geometry.sensors}
    approach, transducers = chain_approaches(study)
    stiffness = hertz_stiffness(geometry.beads.radius)
    out = {"study": STUDY, "mesh": geometry_key(geometry), "contacts": {}}
    for c in args.contacts:
        start = time.perf_counter()
        p = min(coils, key=lambda q: min(abs(c - q), abs(c + 1 - q)))
        coil = coils[p]
        near = [k for k in range(p - 3, p + 3)]  # contacts around the coil's particle
        d = approach[:, c - 1]
        d_static, d_peak = float(d[0]), float(d.max())
        d_open = float(approach[:, [k - 1 for k in near]].min())
        model = layer_model(geometry, c)
        table = contact_map(model, coil, STEEL_NODES, AIR_GAPS)
        base = contact_flux(model, d_static, coil)
        checks = []
        for label, delta in ([(f"{f} N", float(hertz_approach(f, stiffness))) for f in LOADS]
                             + [("open gap", d_open)]):
            solved = contact_flux(model, delta, coil) - base
            tabled = float(table(delta) - table(d_static))
            checks.append({"at": label, "delta_um": delta * 1e6, "solve_Wb": solved,
                           "table_Wb": tabled, "error": abs(tabled - solved) / abs(solved)})
        # superposition: the lower neighbour at the 10 N approach (plain morph, same mesh)
        nb = c + 1
        d_nb = float(hertz_approach(LOADS[-1], stiffness)) - table.delta_static
        ref = state_flux(model, "steel", table.delta_static, coil)
        alone = state_flux(model, "steel", table.delta_static, coil, {nb: d_nb}) - ref
        joint = state_flux(model, "air", d_open, coil, {nb: d_nb}) - ref
        summed = state_flux(model, "air", d_open, coil) - ref + alone
        slope_static = float(table.slope(d_static))
        grid = np.linspace(min(d_open, d.min()), d_peak, 401)
        tangent = table(grid) - table(d_static) - slope_static * (grid - d_static)
        span = float(np.ptp(table(grid)))
        tr = transducers[p]
        k = int(np.flatnonzero(np.asarray(tr.contacts) == c)[0])
        out["contacts"][str(c)] = {
            "coil": p,
            "chain_delta_um": {"static": d_static * 1e6, "min": float(d.min()) * 1e6,
                               "peak": d_peak * 1e6, "open_gap_checked": d_open * 1e6},
            "delta_static_model_um": table.delta_static * 1e6,
            "checks": checks,
            "max_error": max(x["error"] for x in checks),
            "superposition": {"joint_Wb": joint, "sum_Wb": summed,
                              "error": abs(summed - joint) / abs(joint)},
            "slope_Wb_per_m": {"static": slope_static,
                               "open_gap": float(table.slope(d_open)),
                               "peak": float(table.slope(d_peak)),
                               "transducer_linear": float(tr.dlambda_dapproach[k])},
            "slope_ratio_open_to_static": float(table.slope(d_open)) / slope_static,
            "slope_ratio_peak_to_static": float(table.slope(d_peak)) / slope_static,
            "nonlinearity": float(np.max(np.abs(tangent))) / span,
            "table": {"steel_delta_um": (table.steel_delta * 1e6).tolist(),
                      "steel_flux_Wb": table.steel_flux.tolist(),
                      "air_gap_um": (table.air_gap * 1e6).tolist(),
                      "air_flux_Wb": table.air_flux.tolist()},
            "seconds": time.perf_counter() - start,
        }
        print(json.dumps({c: out["contacts"][str(c)]["max_error"]}), flush=True)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()

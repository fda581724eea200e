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

Run: ``python benchmarks/contact_map.py`` (the tables: about a minute per contact on one core
when not cached; the checks: about 40 s per contact; plus the chain run).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from msens.config.fieldsetup import geometry_from_study
from msens.config.study import load_study
from msens.field.cache import geometry_key
from msens.magnetics.approach import hertz_stiffness
from msens.magnetics.contact_map import contact_flux, layer_model, mapped_contacts, state_flux
from msens.magnetics.transducer_cache import transducers_for
from msens.mechanics.hertz import hertz_approach
from msens.pipeline import (
    calibrate_dissipation,
    output_times,
    setup_transducers,
    simulate_setup,
)

STUDY = "studies/paper-mss.toml"
LOADS = (7.0, 8.5, 10.0)


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
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    study = load_study(STUDY)
    geometry = geometry_from_study(study)
    approach, _ = chain_approaches(study)
    start = time.perf_counter()
    transducers = transducers_for(geometry, contact_maps=True)  # cached, or tabulated here
    out = {"study": STUDY, "mesh": geometry_key(geometry),
           "tables_seconds": time.perf_counter() - start, "contacts": {}}
    stiffness = hertz_stiffness(geometry.beads.radius)
    coils = {u.coil.particle: u.coil for u in geometry.sensors}
    for c in mapped_contacts(geometry):
        start = time.perf_counter()
        p = min(coils, key=lambda q: min(abs(c - q), abs(c + 1 - q)))
        coil, tr = coils[p], transducers[p]
        table = next(m for m in tr.approach_map.maps if m.contact == c)
        near = [k for k in mapped_contacts(geometry) if p - 3 <= k <= p + 2]
        d = approach[:, c - 1]
        d_static, d_peak = float(d[0]), float(d.max())
        d_open = float(approach[:, [k - 1 for k in near]].min())
        model = layer_model(geometry, c)
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
            "pulse_flux_Wb": {"map": float(np.ptp(table(d) - table(d_static))),
                              "linear": float(np.ptp(tr.dlambda_dapproach[k] * (d - d_static)))},
            "check_seconds": time.perf_counter() - start,
        }
        print(json.dumps({c: out["contacts"][str(c)]["max_error"]}), flush=True)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()

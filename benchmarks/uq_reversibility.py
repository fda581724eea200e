"""Groundwork for propagating the small-signal permeability: field solves of the main study at
several steel reversibilities c, a spline surrogate in log c, and its error on held-out solves.

``field.reversibility`` (the reversible part of the steel's differential susceptibility,
1 = differential, ~0.1 = reversible) is declared in ``uncertainty-paper-mss.toml`` but held at
its nominal value by ``msens uq``: each value is a new bias and coil solve on the study's mesh
(the nonlinear contact maps do not depend on it and are shared). This script measures what a
surrogate would cost and how good it is: it solves the transducers at the spline nodes
:data:`NODES` and at held-out values :data:`HELD_OUT` (cached in the user cache, then
seconds), interpolates every transducer quantity with a cubic spline in log c, and compares
the peak DAQ voltage and peak EMF of each coil (the nominal chain run read through the
interpolated and the directly solved transducer, contact maps read as ``msens diagnose``'s
remanence variants read them) and the magnets' total pull.

Run: ``python benchmarks/uq_reversibility.py`` (prints JSON: seconds per solve, and the
surrogate's relative errors at the held-out values).
"""

from __future__ import annotations

import json
import time
from dataclasses import replace

import numpy as np
from scipy.interpolate import CubicSpline

from msens import api
from msens.config.fieldsetup import geometry_from_study
from msens.magnetics.transducer import magnetic_precompression
from msens.magnetics.transducer_cache import transducers_for
from msens.pipeline import run_study
from msens.readout.mss import MssSensor, mss_signals, readout

#: Reversibilities solved for the spline (log-uniform from 0.1 to 1) and held out.
NODES = (0.1, 0.178, 0.316, 0.562, 1.0)
HELD_OUT = (0.133, 0.237, 0.422, 0.75)
FIELDS = ("sensitivity_villari", "dlambda_dapproach", "magnetic_particle_force",
          "villari_by_offset", "approach_by_offset")


def interpolated(members: list[dict], c: float, particle: int, nominal):
    """The coil at ``particle`` at reversibility ``c`` by cubic splines in log c."""
    x = np.log(NODES)
    trs = [m[particle] for m in members]

    def at(name):
        return CubicSpline(x, np.stack([np.asarray(getattr(t, name), dtype=float)
                                        for t in trs]), axis=0)(np.log(c))

    return replace(trs[-1], inductance_H=float(at("inductance_H")),
                   **{f: at(f) for f in FIELDS}).reading_maps_of(nominal)


def main() -> dict:
    study = api.load_default()
    geometry = geometry_from_study(study)
    result = run_study(study)
    setup = result.setups[0]
    nominal = setup.transducers
    members, cost = {}, {}
    for c in (*NODES, *HELD_OUT):
        start = time.perf_counter()
        members[c] = transducers_for(replace(geometry, reversibility=c))
        cost[c] = time.perf_counter() - start
        print(json.dumps({"reversibility": c, "seconds": cost[c]}), flush=True)
    report = {"solve_seconds": cost, "held_out": {}}
    t, force, approach = setup.history.t, setup.history.force, setup.history.approach
    rate = study.electronics.sample_rate_hz
    for c in HELD_OUT:
        row = {}
        pull_direct = magnetic_precompression(members[c])
        for p, tr0 in nominal.items():
            direct = members[c][p].reading_maps_of(tr0)
            approx = interpolated([members[n] for n in NODES], c, p, tr0)
            peaks = []
            for tr in (direct, approx):
                sensor = MssSensor(tr, readout(_coil(study, p), tr.resistance_ohm,
                                               tr.inductance_H, study.electronics))
                rec = mss_signals(sensor, t, force, rate, approach=approach)
                peaks.append((np.max(np.abs(rec.voltage)), np.max(np.abs(rec.emf))))
            (v1, e1), (v2, e2) = peaks
            row[str(p)] = {"peak_voltage_V": [v1, v2], "voltage_error": v2 / v1 - 1.0,
                           "peak_emf_V": [e1, e2], "emf_error": e2 / e1 - 1.0}
        pull_approx = CubicSpline(np.log(NODES), np.stack(
            [magnetic_precompression(members[n]) for n in NODES]), axis=0)(np.log(c))
        row["pull_error_N"] = float(np.max(np.abs(pull_approx - pull_direct)))
        row["pull_max_N"] = float(np.max(np.abs(np.cumsum(pull_direct))))
        report["held_out"][str(c)] = row
    errors = [abs(v[k]) for r in report["held_out"].values() for p, v in r.items()
              if isinstance(v, dict) for k in ("voltage_error", "emf_error")]
    report["max_relative_error"] = max(errors)
    print(json.dumps(report, indent=1))
    return report


def _coil(study, particle):
    from msens.config.fieldsetup import coil_geometry
    from msens.config.schema import CoilSpec

    spec = next(s for s in study.setups[0].sensors if s.particle == particle)
    return coil_geometry(spec.coil or CoilSpec(), particle)


if __name__ == "__main__":
    main()

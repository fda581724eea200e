"""Hidden-effect benchmark of ``msens diagnose`` (issue 7): 30 seeded cases (the seven effects
in turn, random plausible parameters, 1 % noise, unknown gain and trigger delay), 10 null
cases and two two-effect cases. Prints JSON: per case the named effect, the parameter error
and the time; totals (right-effect rate, parameter recovery, false positives).

Run: ``python benchmarks/diagnose_hidden.py [--quick]``.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, load_study
from msens.diagnose import diagnose, diagnose_passes
from msens.diagnose.effects import NAMES, PHYSICS_MSS_NAMES, Context
from msens.diagnose.hidden import hidden_case, without_precompression
from msens.diagnose.predict import Predictor, baseline_state
from msens.pipeline import calibrate_dissipation, output_times

#: The effects of bead, rod and four-contact MsS data (physics MsS: diagnose_mss.py).
EFFECTS = tuple(n for n in NAMES if n not in PHYSICS_MSS_NAMES)


def setup_for(effect: str) -> str:
    return "mss" if effect == "magnetic_precompression" else "bead"


def rel_error(found: dict, truth: dict) -> float:
    return max(abs(found[k] - v) / abs(v) for k, v in truth.items())


def main(quick: bool = False) -> dict:
    study = without_precompression(load_study(builtin_study_path(PAPER_TABLE2)))
    fit = calibrate_dissipation(study, output_times(study))
    predictor = Predictor(output_times(study))
    bases = {}
    for name in ("bead", "mss"):
        ctx = Context(study, study.setup(name))
        bases[name] = (ctx, baseline_state(ctx, fit.gamma_c, fit.gamma_w))
    cases = []
    n_hidden, n_null = (7, 2) if quick else (30, 10)
    for i in range(n_hidden):
        effect = EFFECTS[i % len(EFFECTS)]
        ctx, base = bases[setup_for(effect)]
        wf, truth = hidden_case(ctx, base, predictor, seed=100 + i, draw_effects=(effect,))
        t0 = time.perf_counter()
        d = diagnose(wf, study, fit=fit)
        err = rel_error(d.parameters, truth[effect]) if d.effect == effect else None
        cases.append({"kind": "hidden", "seed": 100 + i, "truth": truth, "named": d.effect,
                      "parameters": d.parameters, "rel_error": err,
                      "score": d.candidates[0].score, "misfit_before": d.misfit_before,
                      "misfit_after": d.misfit_after, "seconds": time.perf_counter() - t0})
    for i in range(n_null):
        setup = "mss" if i % 3 == 2 else "bead"
        ctx, base = bases[setup]
        wf, _ = hidden_case(ctx, base, predictor, seed=200 + i)
        t0 = time.perf_counter()
        d = diagnose(wf, study, fit=fit)
        cases.append({"kind": "null", "seed": 200 + i, "setup": setup, "named": d.effect,
                      "best": d.candidates[0].effect, "score": d.candidates[0].score,
                      "seconds": time.perf_counter() - t0})
    pairs = [{"wall_stiffness": {"wall_youngs_modulus_pa": 60e9},
              "daq_lowpass": {"lowpass_tau_s": 1.0e-6}},
             {"striker_velocity": {"striker_velocity_m_per_s": 0.45},
              "wall_dissipation": {"gamma_wall_kg_per_s": 3.0}}]
    for j, pair in enumerate(pairs[:1] if quick else pairs):
        ctx, base = bases["bead"]
        wf, truth = hidden_case(ctx, base, predictor, pair, seed=300 + j)
        t0 = time.perf_counter()
        ds = diagnose_passes(wf, study, passes=3, fit=fit)
        cases.append({"kind": "two", "truth": truth,
                      "named": [d.effect for d in ds],
                      "parameters": [d.parameters for d in ds],
                      "seconds": time.perf_counter() - t0})
    hidden = [c for c in cases if c["kind"] == "hidden"]
    right = [c for c in hidden if c["named"] in c["truth"]]
    errs = [c["rel_error"] for c in right]
    nulls = [c for c in cases if c["kind"] == "null"]
    return {
        "right_effect": f"{len(right)}/{len(hidden)}",
        "within_15pct": f"{sum(e <= 0.15 for e in errs)}/{len(hidden)}",
        "max_rel_error": max(errs) if errs else None,
        "median_rel_error": float(np.median(errs)) if errs else None,
        "false_positives": f"{sum(c['named'] != 'none' for c in nulls)}/{len(nulls)}",
        "max_seconds_per_run": max(c["seconds"] for c in cases if c["kind"] != "two"),
        "mean_seconds_per_run": float(np.mean([c["seconds"] for c in cases
                                               if c["kind"] != "two"])),
        "cases": cases,
    }


if __name__ == "__main__":
    print(json.dumps(main(quick="--quick" in sys.argv), indent=1, default=float))

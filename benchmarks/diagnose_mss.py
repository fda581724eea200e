"""Hidden-effect benchmark of ``msens diagnose`` on the main study's physics MsS data.

Data: ``studies/paper-mss.toml`` (two physics MsS coils) simulated with one hidden effect at a
random plausible parameter (:mod:`msens.diagnose.hidden`), seeded, dressed as a measurement
(amplifier gain of order 1, DC offset, trigger delay and jitter, 1 % noise; 1 or 5 shots),
then diagnosed from the study's baseline. Cases: the chain effects (striker speed, wall,
precompression, DAQ low-pass) and the three MsS effects (bias magnet remanence, coil
position, cable capacitance), three seeds each, plus null cases. Prints JSON: per case the
named effect, truth, fit, whether the parameter is within 10 %, the time; totals.

Run: ``python benchmarks/diagnose_mss.py [--quick]``.
"""

from __future__ import annotations

import json
import sys
import time

from msens.config.study import default_study_path, load_study
from msens.diagnose import diagnose
from msens.diagnose.effects import Context
from msens.diagnose.hidden import hidden_case, parameters_recovered
from msens.diagnose.predict import Predictor, baseline_state
from msens.diagnose.workflow import baseline_dissipation
from msens.pipeline import output_times
from msens.synth import RigEffects

EFFECTS = ("striker_velocity", "wall_stiffness", "wall_dissipation", "magnetic_precompression",
           "daq_lowpass", "magnet_remanence", "coil_position", "cable_capacitance")
TOLERANCE = 0.10


def main(quick: bool = False) -> dict:
    study = load_study(default_study_path())
    ctx = Context(study, study.setups[0])
    gc, gw = baseline_dissipation(study)
    predictor = Predictor(output_times(study))
    base = baseline_state(ctx, gc, gw)
    seeds = (500,) if quick else (500, 501, 502)
    cases = []
    for k, seed in enumerate(seeds):
        for j, effect in enumerate(EFFECTS):
            shots = 5 if (j + k) % 3 == 0 else 1
            s = seed + 10 * j
            wf, truth = hidden_case(ctx, base, predictor, seed=s, draw_effects=(effect,),
                                    rig=RigEffects(seed=s, shots=shots, noise=0.01))
            t0 = time.perf_counter()
            d = diagnose(wf, study)
            ok = d.effect == effect and parameters_recovered(d.parameters, truth[effect],
                                                             TOLERANCE)
            cases.append({"kind": "hidden", "seed": s, "shots": shots, "effect": effect,
                          "truth": truth[effect], "named": d.effect, "fit": d.parameters,
                          "right": ok, "score": d.candidates[0].score,
                          "misfit_before": d.misfit_before, "misfit_after": d.misfit_after,
                          "seconds": time.perf_counter() - t0})
            print(json.dumps(cases[-1]), file=sys.stderr, flush=True)
    for i in range(2 if quick else 10):
        s = 600 + i
        shots = 5 if i % 2 else 1
        wf, _ = hidden_case(ctx, base, predictor, seed=s,
                            rig=RigEffects(seed=s, shots=shots, noise=0.01))
        t0 = time.perf_counter()
        d = diagnose(wf, study)
        cases.append({"kind": "null", "seed": s, "shots": shots, "named": d.effect,
                      "best": d.candidates[0].effect, "best_score": d.candidates[0].score,
                      "seconds": time.perf_counter() - t0})
        print(json.dumps(cases[-1]), file=sys.stderr, flush=True)
    hidden = [c for c in cases if c["kind"] == "hidden"]
    null = [c for c in cases if c["kind"] == "null"]
    return {"study": study.name, "tolerance": TOLERANCE, "cases": cases,
            "hidden": len(hidden), "right": sum(c["right"] for c in hidden),
            "right_rate": sum(c["right"] for c in hidden) / len(hidden),
            "null": len(null), "false_positives": sum(c["named"] != "none" for c in null),
            "mean_seconds": sum(c["seconds"] for c in cases) / len(cases)}


if __name__ == "__main__":
    print(json.dumps(main("--quick" in sys.argv), indent=1))

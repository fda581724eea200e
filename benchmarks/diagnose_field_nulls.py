"""The naming rule of ``msens diagnose`` against the field model's own errors.

Null files for the decision rule: the main study's magnetostatic variant (the physics of
:mod:`benchmarks.independent_mss`) with no effect. Each file's records are moved by one
joint draw of every field-model error that the likelihood allows for, at its stated 1 %
accuracy (:func:`msens.diagnose.field_modes.field_draws`: each bead's pull by a chain run,
each contact's Villari and approach sensitivity, the coils' R, L and winding capacitance).
The draws are not linearised, and their seeds differ from those of the likelihood's own
modes. The files are written by :func:`msens.synth.synthesize` (8 shots, 1 % noise) and
diagnosed as ``msens diagnose`` does.

Nothing in such a file is missing from the model beyond what the likelihood says it does
not know. A name here is a false alarm of the rule itself, before any physics that the two
simulators of :mod:`benchmarks.independent_mss` do not share.

Prints JSON, one line per file: the decision, whether explained, the best significant
candidate's score and the best negligible change's, the draw's size relative to the
record's peak, seconds. The last line holds the totals.

Run: ``python benchmarks/diagnose_field_nulls.py [--files 12] [--seed 1000]
[--eddy-currents]`` (the stages are logged on stderr).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import sys
from pathlib import Path

import numpy as np

if __package__ in (None, ""):  # run as a script: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from msens import api
from msens.diagnose import diagnose
from msens.diagnose.effects import Context
from msens.diagnose.field_modes import field_draws
from msens.diagnose.predict import Predictor, baseline_state, setup_result
from msens.diagnose.workflow import baseline_dissipation
from msens.pipeline import output_times
from msens.synth import RigEffects, synthesize


def null_world(eddy_currents: bool = False):
    """(study, context, baseline state, predictor, the baseline's run) of the main study
    (by default its magnetostatic variant)."""
    study = api.load_default(eddy_currents=eddy_currents)
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    predictor = Predictor(output_times(study))
    return study, ctx, base, predictor, setup_result(ctx, base, predictor)


def null_file(ctx: Context, base, predictor: Predictor, result, seed: int):
    """One null file: the baseline's records moved by one field-model draw, with noise.
    Returns (waveform, the draw's largest change over the records' peak)."""
    change = field_draws(base, predictor, draws=1, seed=seed)[0]
    sensors = tuple(dataclasses.replace(s, voltage_shape=s.voltage_shape + change[j])
                    for j, s in enumerate(result.sensors))
    peak = max(float(np.abs(s.voltage_shape).max()) for s in result.sensors)
    wf = synthesize(dataclasses.replace(result, sensors=sensors),
                    RigEffects(noise=0.01, seed=seed, shots=8))
    return wf, float(np.abs(change).max()) / peak


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--files", type=int, default=12)
    ap.add_argument("--seed", type=int, default=1000, help="the first file's seed")
    ap.add_argument("--eddy-currents", action="store_true",
                    help="the main study itself (eddy currents; default: its magnetostatic "
                         "variant, the independent simulator's physics)")
    a = ap.parse_args(argv)
    logging.basicConfig(format="%(name)s: %(message)s")  # the stages on stderr
    logging.getLogger("msens").setLevel(logging.INFO)
    study, *world = null_world(eddy_currents=a.eddy_currents)
    lines = []
    for seed in range(a.seed, a.seed + a.files):
        wf, size = null_file(*world, seed)
        d = diagnose(wf, study)
        live = [c for c in d.candidates if c.plausible and not c.at_bound]
        line = {"seed": seed, "named": d.effect, "explained": d.explained,
                "best_significant": max((c.score for c in live if c.significant),
                                        default=None),
                "best_negligible": max((c.score for c in live if not c.significant),
                                       default=None),
                "draw_over_peak": size, "diagnose_s": d.elapsed_s}
        print(json.dumps(line), flush=True)
        lines.append(line)
    totals = {"files": len(lines), "named": sum(x["named"] != "none" for x in lines),
              "explained": sum(x["explained"] for x in lines),
              "largest_significant_score": max(
                  (x["best_significant"] for x in lines if x["best_significant"] is not None),
                  default=None)}
    print(json.dumps({"totals": totals}))
    return totals


if __name__ == "__main__":
    main()

"""Coverage of ``msens calibrate`` on synthetic data with known inputs.

For each seeded case the true drop height and contact damping are drawn from their priors,
``msens synth`` writes a measurement of a small bead-sensor study with those values (one
shot or five, 1 % noise), and ``msens calibrate`` samples the posterior of both inputs from
the study's nominal values. A calibration is calibrated when its 90 % credible intervals
contain the truth in about 90 % of the cases; every case's split R-hat is reported.

Run: ``python benchmarks/calibrate_coverage.py [--cases 20] [--steps 1000]``; prints JSON.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: A 20-bead chain with bead sensors at particles 10 and 15 (0.8 ms record): a run takes
#: milliseconds, so a calibration of thousands of runs takes seconds.
STUDY = """schema = "msens.study/1"
name = "coverage"
[chain]
beads = 20
damping = "linear-loading"
gamma_contact_kg_per_s = 4.7
[striker]
drop_height_m = 7.2e-3
[simulation]
t_end_s = 8.0e-4
sample_rate_hz = 5e6
[[sensor]]
kind = "bead"
particle = 10
[[sensor]]
kind = "bead"
particle = 15
"""

#: The priors: the paper's drop height tolerance and the Eq. 10 fit's spread of gamma_c
#: (as in the built-in uncertainty-paper-table2.toml).
INPUTS = """schema = "msens.uncertainty/1"
study = "coverage"
[[input]]
name = "striker.drop_height_m"
distribution = "uniform"
lower = 6.7e-3
upper = 7.7e-3
reason = "drop height set by hand to +-0.5 mm"
source = "paper section 2"
[[input]]
name = "chain.gamma_contact_kg_per_s"
distribution = "triangular"
lower = 4.07
mode = 4.71
upper = 5.56
reason = "Eq. 10 fit with the top AR moved by its std"
source = "paper Eq. 10 and Table 2"
"""

NAMES = ("striker.drop_height_m", "chain.gamma_contact_kg_per_s")


def case(folder: Path, seed: int, shots: int, steps: int) -> dict:
    """One synthetic case: truth, posterior interval, R-hat."""
    from msens import api
    from msens.io.read import read_waveform
    from msens.uq.calibration import run_calibrate
    from msens.uq.inputs import load_inputs

    study_file = folder / "study.toml"
    inputs_file = folder / "inputs.toml"
    study = api.load(study_file)
    rng = np.random.default_rng(1000 + seed)
    inputs = load_inputs(inputs_file, study)
    truth = {p.name: float(p.distribution.values(rng.random(1))[0]) for p in inputs.propagated}
    data = api.synth(study.replace(truth), folder / f"case{seed}.csv", shots=shots,
                     noise=0.01, seed=seed)
    result = run_calibrate(study, folder / f"cal{seed}", data=read_waveform(data),
                           inputs=inputs_file, params=NAMES, steps=steps, seed=seed,
                           progress=False)
    out = {"seed": seed, "shots": shots}
    for p in result.report["inputs"]:
        lo, hi = p["credible_interval_90"]
        t = truth[p["name"]]
        out[p["name"]] = {"truth": t, "interval_90": [lo, hi], "inside": lo <= t <= hi,
                          "rhat": p["rhat"]}
    out["converged"] = result.report["convergence"]["converged"]
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--steps", type=int, default=1000)  # the command's default
    args = ap.parse_args(argv)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "study.toml").write_text(STUDY)
        (folder / "inputs.toml").write_text(INPUTS)
        cases = [case(folder, s, 1 if s % 2 == 0 else 5, args.steps) for s in range(args.cases)]
    summary = {"cases": len(cases), "steps": args.steps,
               "coverage_90": {n: float(np.mean([c[n]["inside"] for c in cases]))
                               for n in NAMES},
               "max_rhat": max(max(c[n]["rhat"] for n in NAMES) for c in cases),
               "converged_cases": int(sum(c["converged"] for c in cases)),
               "seconds": time.perf_counter() - start, "per_case": cases}
    print(json.dumps(summary, indent=1))
    return summary


if __name__ == "__main__":
    sys.exit(0 if main() else 1)

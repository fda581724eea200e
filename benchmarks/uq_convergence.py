"""Sobol indices of the main study at N and 4N base samples, and the wall time of each run.

Propagates the built-in uncertain inputs of ``studies/paper-mss.toml``
(``src/msens/data/uncertainty-paper-mss.toml``) with ``msens.uq.propagate`` twice, with N and
4N Saltelli base samples (the same seed), on local worker processes, and prints as JSON: per
run the model runs, field solves (0: the field inputs go through the committed tables), wall
time; per output the largest difference of its first-order and total indices between the
two runs (the acceptance of issue 34: within 0.05), and the 5-50-95 % bands of both.

Run: ``python benchmarks/uq_convergence.py [--samples 128] [--workers 2]`` (N = 128: 1,920 and
7,680 model runs; read-out dominated, about 0.35 s per run and worker).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from msens import api
from msens.parallel import allow_pools
from msens.uq.inputs import load_inputs
from msens.uq.propagate import propagate


def run(samples: int, workers: int | None, seed: int) -> tuple[dict, object]:
    study = api.load_default()
    inputs = load_inputs(None, study)
    start = time.perf_counter()
    with allow_pools():
        result = propagate(study, inputs, samples=samples, seed=seed, workers=workers)
    return {"base_samples": samples, "model_runs": result.runs, "field_solves": 0,
            "inputs_propagated": len(inputs.propagated), "inputs_held": len(inputs.held),
            "wall_s": time.perf_counter() - start}, result


def main() -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=128)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    small, a = run(args.samples, args.workers, args.seed)
    print(json.dumps({"run": small}), flush=True)
    large, b = run(4 * args.samples, args.workers, args.seed)
    print(json.dumps({"run": large}), flush=True)
    names = [p.name for p in a.inputs.propagated]
    outputs, worst = {}, 0.0
    for k, ia in a.indices.items():
        ib = b.indices[k]
        if ia.note or ib.note:
            outputs[k] = {"note": ia.note or ib.note}
            continue
        d1 = np.abs(ia.first - ib.first)
        dt = np.abs(ia.total - ib.total)
        worst = max(worst, float(d1.max()), float(dt.max()))
        outputs[k] = {"max_diff_S1": float(d1.max()), "max_diff_ST": float(dt.max()),
                      "worst_input": names[int(np.argmax(np.maximum(d1, dt)))],
                      "ST_4N": dict(zip(names, np.round(ib.total, 3).tolist(), strict=True)),
                      "band_N": a.band(k).tolist(), "band_4N": b.band(k).tolist()}
    report = {"runs": [small, large], "max_index_difference": worst,
              "within_0.05": worst <= 0.05, "outputs": outputs}
    print(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()

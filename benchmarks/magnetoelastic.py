"""Speed of the JAS magnetoelastic law on FE-sized arrays; prints JSON.

Run: python benchmarks/magnetoelastic.py
"""

from __future__ import annotations

import json
import time

import numpy as np

from msens.magnetics.magnetoelastic import (
    DEFAULT_STEEL,
    anhysteretic_magnetisation,
    piezomagnetic_coefficient,
    unique_stress_range,
)


def _best_of(f, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    rng = np.random.default_rng(0)
    n = 100_000
    h = rng.uniform(-5e4, 5e4, n)
    lo, hi = unique_stress_range(DEFAULT_STEEL)
    s = rng.uniform(0.9 * lo, 0.9 * hi, n)
    out = {
        "points": n,
        "d_of_H_sigma0_s": _best_of(lambda: piezomagnetic_coefficient(DEFAULT_STEEL, h)),
        "M_of_H_sigma_s": _best_of(lambda: anhysteretic_magnetisation(DEFAULT_STEEL, h, s)),
        "d_of_H_sigma_s": _best_of(lambda: piezomagnetic_coefficient(DEFAULT_STEEL, h, s)),
        "unique_stress_range_Pa": [lo, hi],
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()

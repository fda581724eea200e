"""The main study's static coil tables as truncated decompositions.

A changed coil is read from tables of the field model it was not solved with
(:mod:`msens.magnetics.coil_read`): per coil, the summed-area tables of 58 sources over the
coil's window (58 x 65 x 225 nodes) and the window's 1600 x 1600 inductance kernel, 17 MB,
built the first time a coil changes (half a minute: a bias solve, the sources and 1,600
tangent solves). The tables are nearly of low rank over the sources, and the kernel
(K = P K_t^-1 P^T, symmetric) has about as many non-zero eigenvalues as the mesh has degrees
of freedom among the cells, so ``write_tables(..., rank_tol=)`` stores a truncated SVD of the
first (:func:`msens.magnetics.low_rank.rows_svd`) and the leading eigenpairs of the second
(:func:`msens.magnetics.low_rank.symmetric_eig`).

This script measures, for both coils of the main study: the ranks kept, the stored size, the
largest reconstruction error of each part (relative to its largest entry), and what it does
to a read (as ``benchmarks/coil_read.py``): for the solved coil and five changes, the largest
difference of ∂Λ/∂F_c and ∂Λ/∂δ_c over seven offsets within ±3 mm (relative to the largest
|value| of that coil) and of the incremental inductance, full tables against truncated.

It needs the full tables in the user cache (the first changed coil builds them: ``msens run
--set sensor.1.coil.turns=1000 --set sensor.2.coil.turns=1000``). With ``--out DIR`` it
writes the truncated tables there with their checksum sidecars: how the committed tables in
``meshes/`` are made.

Run: ``python benchmarks/coil_table_rank.py [--tol 1e-7] [--out DIR]`` (prints JSON).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from msens import api
from msens.config.fieldsetup import geometry_from_study
from msens.magnetics.coil_read import read_model, read_tables, table_name, write_tables
from msens.magnetics.transducer_cache import free_key
from msens.store import Store, user_cache_dir

if __package__ in (None, ""):  # run as a script: the repository root for benchmarks.*
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from benchmarks.eddy_table_rank import CHANGES  # the same five coil changes


def main(argv: list[str] | None = None) -> dict:
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--tol", type=float, default=1e-7)
    args.add_argument("--out", default=None)
    opts = args.parse_args(argv)
    study = api.load_default()
    geometry = geometry_from_study(study)
    key = free_key(geometry)
    store = Store.at(user_cache_dir())  # the full tables, never the committed truncated ones
    model = read_model(store, key)
    particles = [u.coil.particle for u in geometry.sensors]
    full = None if model is None else read_tables(store, key, *model, particles)
    if full is None or sorted(full.tables) != particles:
        raise SystemExit(f"no full coil tables {key} in {store.directory}: run a changed coil "
                         "on the main study first")
    with tempfile.TemporaryDirectory() as tmp:
        return _measure(study, key, model, full, particles, Store.at(opts.out or tmp),
                        opts.tol)


def _measure(study, key, model, full, particles, scratch: Store, tol: float) -> dict:
    t0 = time.perf_counter()
    write_tables(scratch, key, full, rank_tol=tol)
    seconds = time.perf_counter() - t0
    small = read_tables(scratch, key, *model, particles)
    report: dict = {"free_key": key, "tol": tol, "write_seconds": seconds, "coils": {}}
    shifts = np.linspace(-3e-3, 3e-3, 7)
    for p in particles:
        path = scratch.find_file(table_name(key, p))
        with np.load(path) as f:
            ranks = {"tables": int(f["cumulative_u"].shape[1]),
                     "kernel": int(f["kernel_lam"].size)}
        a_t, b_t = full.tables[p].cumulative, small.tables[p].cumulative
        a_k, b_k = full.grids[p].kernel, small.grids[p].kernel
        index = particles.index(p)
        errors = {}
        for name, change in {"solved coil": {}, **CHANGES}.items():
            changed = study.replace({f"sensor[{index + 1}].{k}": v for k, v in change.items()})
            g = geometry_from_study(changed)
            coil = next(u.coil for u in g.sensors if u.coil.particle == p)
            _, *x = full.profiles(coil, g, shifts)
            _, *y = small.profiles(coil, g, shifts)
            row = {q: float(np.max(np.abs(u - v)) / np.max(np.abs(u)))
                   for q, u, v in zip(("villari", "approach"), x, y, strict=True)}
            la, lb = full.inductance(coil, g), small.inductance(coil, g)
            row["inductance"] = abs(lb - la) / la
            errors[name] = row
        report["coils"][str(p)] = {
            "rank": ranks, "bytes_full": int(a_t.nbytes + a_k.nbytes),
            "bytes_stored": int(path.stat().st_size),
            "size_ratio_full_to_stored": round((a_t.nbytes + a_k.nbytes)
                                               / path.stat().st_size, 2),
            "tables_max_rel_error": float(np.max(np.abs(b_t - a_t)) / np.max(np.abs(a_t))),
            "kernel_max_rel_error": float(np.max(np.abs(b_k.astype(float) - a_k))
                                          / np.max(np.abs(a_k))),
            "read_max_rel_error": errors}
    print(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()

"""The main study's eddy-current coil tables as truncated singular value decompositions.

A changed coil on a study with eddy currents is read from harmonic tables of every source
over the coil's window (:mod:`msens.magnetics.eddy_coil_read`): 17 frequencies x 58 sources
x 33 x 113 grid nodes, 59 MB per coil, built the first time a coil changes (minutes). The
potentials over the window are smooth and alike, so the matrix (frequency x source) x node is
nearly of low rank: :func:`msens.magnetics.eddy_coil_read.low_rank` keeps the singular values
above ``--tol`` times the largest. This script measures, for both coils of the main study
with eddy currents, the rank kept, the stored size, the largest reconstruction error of the
tables (relative to their largest entry), and what it does to a read: S_c(ω) and D_c(ω) of
the coil's own contacts for five coil changes (as ``benchmarks/coil_read.py --eddy``) and
seven offsets over ±3 mm, full tables against compressed, as the largest difference relative
to the largest |value| of that coil.

It needs the full tables in the user cache (the first changed coil builds them: ``msens run
STUDY --set sensor.1.coil.turns=1000 --set sensor.2.coil.turns=1000`` on the main study with
``[field] eddy_currents = true``). With ``--out DIR`` it writes the compressed tables there
(as the store writes artifacts, with their checksum sidecars): how the committed tables in
``meshes/`` are made.

Run: ``python benchmarks/eddy_table_rank.py [--tol 1e-7] [--out DIR]`` (prints JSON).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from msens import api
from msens.config.fieldsetup import eddy_settings, geometry_from_study
from msens.magnetics.dynamic import DEFAULT_FREQUENCIES
from msens.magnetics.eddy_coil_read import (
    EddyCoilTable,
    low_rank,
    read_table,
    tables_key,
    write_table,
)
from msens.magnetics.harmonic_tables import HarmonicTables
from msens.store import Store, user_cache_dir

#: Coil changes read (as benchmarks/coil_read.py): study keys of both coils.
CHANGES = {"turns 1000": {"coil.turns": 1000}, "length 8 mm": {"coil.length_m": 8e-3},
           "inner radius 8.5 mm": {"coil.inner_radius_m": 8.5e-3},
           "wire AWG38": {"coil.wire": "AWG38"}, "offset +1 mm": {"coil.axial_offset_m": 1e-3}}


def main(argv: list[str] | None = None) -> dict:
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--tol", type=float, default=1e-7)
    args.add_argument("--out", default=None)
    opts = args.parse_args(argv)
    study = api.load_default().replace({"field.eddy_currents": True})
    geometry = geometry_from_study(study)
    eddy = eddy_settings(study)
    solved = {u.coil.particle: u.coil for u in geometry.sensors}
    key = tables_key(geometry, solved, eddy.options, DEFAULT_FREQUENCIES, eddy.steel, None)
    store = Store.at(user_cache_dir())  # the full tables, never the committed truncated ones
    report: dict = {"tables_key": key, "tol": opts.tol, "coils": {}}
    for p in sorted(solved):
        full = read_table(store, key, p)
        if full is None:
            raise SystemExit(f"no full table {key}-{p} in {store.directory}: run a changed "
                             "coil on the main study with eddy currents first")
        h = full.harmonic
        t0 = time.perf_counter()
        arrays = low_rank(h.cumulative, opts.tol)
        seconds = time.perf_counter() - t0
        approx = (arrays["u"] @ arrays["v"].astype(complex)).reshape(h.cumulative.shape)
        small = EddyCoilTable(HarmonicTables(h.frequencies, h.r, h.z, approx),
                              full.particles, full.approach_contacts, full.count)
        index = next(i for i, u in enumerate(study.setups[0].sensors) if u.particle == p)
        shifts = np.linspace(-3e-3, 3e-3, 7)
        errors = {}
        for name, change in {"solved coil": {}, **CHANGES}.items():
            changed = study.replace({f"sensor[{index + 1}].{k}": v for k, v in change.items()})
            g = geometry_from_study(changed)
            coil = next(u.coil for u in g.sensors if u.coil.particle == p)
            a, b = full.profiles(coil, g, shifts), small.profiles(coil, g, shifts)
            errors[name] = {q: float(np.max(np.abs(x - y)) / np.max(np.abs(x)))
                            for q, x, y in zip(("villari", "approach"), a, b, strict=True)}
        report["coils"][str(p)] = {
            "rank": int(arrays["u"].shape[1]), "rows": int(arrays["u"].shape[0]),
            "nodes": int(arrays["v"].shape[1]),
            "bytes_full": int(h.cumulative.nbytes),
            "bytes_compressed": int(arrays["u"].nbytes + arrays["v"].nbytes),
            "svd_seconds": seconds,
            "table_max_rel_error": float(np.max(np.abs(approx - h.cumulative))
                                         / np.max(np.abs(h.cumulative))),
            "read_max_rel_error": errors}
        if opts.out:
            write_table(Store.at(opts.out), key, p, full, rank_tol=opts.tol)
    print(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()

"""Magnet designs with the full physics: time per design on the main study with eddy currents.

A magnet design cannot reuse the study's field model (the magnet sets the bias), so each one
meshes, solves the nonlinear bias, builds both mechanisms' sources, solves the
eddy-current model at the run's 17 frequencies and (the main study has ``[field]
contact_map = true``) tabulates the nonlinear contact maps of the six contacts around the
swept coil in its own bias field (:mod:`msens.design.magnet_sweep`). Printed as JSON:

- ``single_design_s``: one design (magnet moved 1 mm, so nothing is cached) in this process,
  its contact maps on the local cores as ``msens design`` tabulates them for a one-design
  sweep (the eddy-current model's stage seconds: the log at DEBUG);
- ``sweep``: ``--designs`` designs through ``msens design`` with two local workers (what a
  user runs), wall time per design;
- ``screening``: the same sweep with ``[model] contact_map = false`` (the linear contact
  sources: no maps per design);
- ``screen_and_verify``: the screening sweep with ``verify = 1`` (its best design evaluated
  again with its own maps, as ``studies/sweep-magnet.toml`` verifies three of 24);
- ``lu``: one factorisation of that design's K_t + jωM_σ at 30 kHz with msens' sparse LU
  (:mod:`msens.field.linsolve`) against scipy's ``splu`` with its defaults (what a user would
  pick), as a ratio.

Every cache goes to a temporary folder (``MSENS_MESH_DIR``, one per sweep), so each part
starts cold.

Run: ``python benchmarks/magnet_design_speed.py [--designs 4] [--parts
single,sweep,screening,verify]`` (about 20 min on 2 cores for all parts).
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np


def eddy_study():
    from msens import api
    from msens.config.study import default_study_path

    return api.load(default_study_path()).replace({"field.eddy_currents": True})


def single_design(study, offset: float, mesh_dir: Path) -> dict:
    from msens.config.fieldsetup import geometry_from_study
    from msens.design.magnet_sweep import MagnetTask, evaluate_design
    from msens.design.sweep import design_geometry, parse_sweep
    from msens.store import Store

    spec = parse_sweep(f'schema = "msens.sweep/1"\nname = "one"\nsensor = 13\n[magnet]\n'
                       f'axial_offset_m = [{offset!r}]\n')
    geometry = design_geometry(geometry_from_study(study), 13, spec.designs()[0])
    from msens.parallel import allow_pools

    t0 = time.perf_counter()
    with allow_pools():  # as `msens design` runs a one-design sweep: maps on the local cores
        row = evaluate_design(MagnetTask(study, geometry, 13, Store.at(mesh_dir)))
    seconds = time.perf_counter() - t0
    # the eddy-current model's stage seconds are in the log at DEBUG (msens.magnetics.dynamic)
    return {"seconds": round(seconds, 2), "peak_voltage_V": row["peak_voltage_V"]}, geometry


def sweep(study, designs: int, folder: Path, model: str = "") -> dict:
    from msens import api

    offsets = ", ".join(repr(float(x)) for x in np.linspace(-1.5e-3, 1.5e-3, designs))
    folder.mkdir(parents=True, exist_ok=True)
    spec = folder / "sweep.toml"
    spec.write_text(f'schema = "msens.sweep/1"\nname = "speed"\nsensor = 13\n[magnet]\n'
                    f"axial_offset_m = [{offsets}]\n{model}")
    # a cold user cache per sweep: no sweep reads another's maps or transducers
    os.environ["MSENS_MESH_DIR"] = str(folder / "user-cache")  # workers inherit it
    from msens.parallel import allow_pools

    t0 = time.perf_counter()
    with allow_pools():  # as `msens design` runs: contact maps may use the local cores
        api.design(study, spec, folder / "out", workers=2, progress=False)
    wall = time.perf_counter() - t0
    return {"designs": designs, "workers": 2, "wall_s": round(wall, 1),
            "per_design_s": round(wall / designs, 2)}


def lu_comparison(study, geometry, mesh_dir: Path) -> dict:
    from scipy.sparse.linalg import splu

    from msens.config.fieldsetup import eddy_settings
    from msens.field.eddy import HarmonicOperator
    from msens.field.linsolve import factorize
    from msens.magnetics.dynamic import sensor_conductivity
    from msens.magnetics.transducer import bias_solution
    from msens.store import Store

    eddy = eddy_settings(study)
    sol, _ = bias_solution(geometry, options=eddy.options, store=Store.at(mesh_dir))
    op = HarmonicOperator(sol, sensor_conductivity(sol.problem.mesh, geometry,
                                                   steel=eddy.steel))
    a = op.matrix(30e3)
    b = np.random.default_rng(0).standard_normal(a.shape[0]).astype(complex)
    factorize(op.k_ff)  # the pattern's ordering, once per model (as in a design)
    t0 = time.perf_counter()
    x = factorize(a).solve(b)
    t_msens = time.perf_counter() - t0
    t0 = time.perf_counter()
    ref = splu(a).solve(b)
    t_scipy = time.perf_counter() - t0
    return {"dofs": int(a.shape[0]), "msens_s": round(t_msens, 3),
            "scipy_splu_default_s": round(t_scipy, 3), "ratio": round(t_msens / t_scipy, 3),
            "max_rel_difference": float(np.max(np.abs(x - ref)) / np.max(np.abs(ref)))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=4)
    parser.add_argument("--parts", default="single,sweep,screening,verify",
                        help="comma-separated subset of single, sweep, screening, verify")
    args = parser.parse_args()
    parts = set(args.parts.split(","))
    study = eddy_study()
    out: dict = {"study": "paper-mss with [field] eddy_currents = true",
                 "contact_map": study.field.contact_map}
    with tempfile.TemporaryDirectory() as tmp:
        if "single" in parts:
            os.environ["MSENS_MESH_DIR"] = str(Path(tmp) / "cache")
            out["single_design"], geometry = single_design(study, 1e-3, Path(tmp) / "one")
            out["lu"] = lu_comparison(study, geometry, Path(tmp) / "one")
        models = {"sweep": "", "screening": "[model]\ncontact_map = false\n",
                  "verify": "[model]\ncontact_map = false\nverify = 1\n"}
        names = {"sweep": "sweep", "screening": "screening", "verify": "screen_and_verify"}
        for part, model in models.items():
            if part in parts:
                out[names[part]] = sweep(study, args.designs, Path(tmp) / part, model)
    print(json.dumps({**out, "target_per_design_s": 20.0}, indent=1))


if __name__ == "__main__":
    main()

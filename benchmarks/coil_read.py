"""A changed coil read from the main study's field model against a full rebuild.

For each coil change (``--set`` of the main study, both coils), ``msens run`` twice:

1. *read*: in a user cache that has seen the default run (the coil-free field model's record
   and, after the first change, its coil tables), the changed coil's transducers are read
   from tables (:mod:`msens.magnetics.coil_read`); wall time of the run;
2. *rebuild*: in an empty user cache (nothing to read), the changed geometry is meshed and
   solved anew with its own contact maps (minutes per change).

Prints JSON: per change the read run's wall time, and per coil the peak DAQ voltage, its
time, the peak EMF, R, L and the resonance of both, with the relative differences. The
committed field model (``meshes/``) serves both; only the user caches differ.

Without ``--eddy`` the main study's magnetostatic variant runs (``--set
field.eddy_currents=false``); with ``--eddy`` the main study as it stands, with eddy currents:
the changed coils' frequency responses are read from the solved eddy-current model's harmonic
tables (:mod:`msens.magnetics.eddy_coil_read`; the first change of each coil builds them),
the rebuild solves the changed geometry's own eddy-current model too.

    python benchmarks/coil_read.py                 # five changes (about half an hour)
    python benchmarks/coil_read.py --changes turns # one
    python benchmarks/coil_read.py --eddy --changes turns,axial_offset
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: Coil changes within the tables' window (--set values for both sensors).
CHANGES = {
    "turns": {"coil.turns": "1000"},
    "length": {"coil.length_m": "8e-3"},
    "inner_radius": {"coil.inner_radius_m": "8.5e-3"},
    "wire": {"coil.wire": "'AWG38'"},
    "axial_offset": {"coil.axial_offset_m": "1e-3"},
}
KEYS = ("peak_voltage_V", "peak_voltage_time_us", "peak_emf_V", "resistance_ohm",
        "inductance_H", "resonance_Hz")


def _run(cache: Path, out: Path, sets: dict[str, str], eddy: bool
         ) -> tuple[float, list[dict]]:
    args = [sys.executable, "-m", "msens", "run", "paper-mss", "--out", str(out), "-q",
            "--no-figures", "--set", f"field.eddy_currents={str(eddy).lower()}"]
    for k, v in sets.items():
        for i in (1, 2):
            args += ["--set", f"sensor.{i}.{k}={v}"]
    env = {**os.environ, "MSENS_MESH_DIR": str(cache), "MPLBACKEND": "Agg"}
    start = time.perf_counter()
    subprocess.run(args, env=env, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    coils = json.loads((out / "summary.json").read_text())["coils"]
    return wall, [{k: c[k] for k in ("particle", *KEYS)} for c in coils]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--changes", default=",".join(CHANGES),
                    help=f"comma-separated subset of {', '.join(CHANGES)}")
    ap.add_argument("--eddy", action="store_true",
                    help="the main study as it stands, with eddy currents (default: magnetostatic)")
    args = ap.parse_args(argv)
    names = [n for n in args.changes.split(",") if n]
    unknown = sorted(set(names) - set(CHANGES))
    if unknown:
        ap.error(f"unknown changes {unknown}; allowed: {', '.join(CHANGES)}")
    report = {"study": "paper-mss", "eddy_currents": args.eddy, "changes": {}}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        warm = tmp / "warm-cache"
        default_s, _ = _run(warm, tmp / "default", {}, args.eddy)
        report["default_run_s"] = round(default_s, 2)
        for name in names:
            sets = CHANGES[name]
            read_s, read = _run(warm, tmp / f"read-{name}", sets, args.eddy)
            rebuild_s, full = _run(tmp / f"cold-{name}", tmp / f"full-{name}", sets, args.eddy)
            coils = []
            for a, b in zip(read, full, strict=True):
                coils.append({"particle": a["particle"], "read": a, "rebuild": b,
                              "rel_diff": {k: (a[k] - b[k]) / b[k] for k in KEYS}})
            report["changes"][name] = {"set": sets, "read_run_s": round(read_s, 2),
                                       "rebuild_run_s": round(rebuild_s, 1), "coils": coils}
            print(json.dumps({"progress": name, "read_run_s": round(read_s, 2),
                              "rebuild_run_s": round(rebuild_s, 1)}), file=sys.stderr)
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

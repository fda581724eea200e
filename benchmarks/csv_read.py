"""Reading a large measured waveform: wall time and peak memory (prints JSON).

Two files of ``--rows`` samples (default one million, three columns) are written to a
temporary folder:

- ``scope``: an oscilloscope's text export (a few settings lines, ``Time,CH1,CH2``, a units
  row, fixed-format numbers such as ``-1.00000e-04``), read through a column map as
  ``msens compare data.csv --columns time=Time,mss@13=CH1,mss@18=CH2`` reads it
  (:func:`msens.io.read.read_waveform` with ``columns=``);
- ``msens``: the same record in msens's own CSV format (design.md §8, shortest-repr numbers),
  read by :func:`msens.io.read.read_waveform`.

Each read runs in a fresh process (imports done before the clock starts) and reports its
wall time and peak memory: the rise of the process's peak resident set (``VmHWM``, reset
after the imports) over the resident set before the read. The same file read by plain
``pandas.read_csv`` (what a user would pick) gives the reference; ``ratio`` is msens's time
(memory) over pandas's. The memory target of issue 37 is at most 3x the file's size.

Run: ``python benchmarks/csv_read.py [--rows N] [--repeat K]`` (best of K reads, default 1).
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

import numpy as np

DT = 1e-7  # s, a 10 MS/s record


def write_files(folder: Path, rows: int) -> dict[str, Path]:
    """The scope export and the msens CSV of one ``rows``-sample record."""
    rng = np.random.default_rng(0)
    t = -1e-4 + DT * np.arange(rows)
    ch = rng.normal(0.0, 1e-3, size=(rows, 2))
    scope = folder / "scope.csv"
    with scope.open("w", encoding="ascii", newline="\n") as f:
        f.write("Model,DSO-X 2024A\nFirmware,2.43\nSample rate,1.0E+07\n\n")
        f.write("Time,CH1,CH2\ns,V,V\n")
        np.savetxt(f, np.column_stack((t, ch)), fmt="%.5e", delimiter=",")
    own = folder / "msens.csv"
    from msens.io.read import write_waveform
    from msens.io.waveform import Channel, Waveform

    write_waveform(Waveform(t, ch, (Channel("mss", 13), Channel("mss", 18)),
                            {"units": "V"}), own)
    return {"scope": scope, "msens": own}


_CHILD = r"""
import json, os, sys, time
kind, path = sys.argv[1], sys.argv[2]
import numpy as np, pandas as pd
from msens.io.read import read_waveform

def rss():
    with open("/proc/self/status") as f:
        fields = dict(line.split(":", 1) for line in f)
    return {k: int(fields[k].split()[0]) * 1024 for k in ("VmRSS", "VmHWM")}

try:  # reset the peak to the current resident set (Linux >= 4.0)
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
except OSError:
    pass
before = rss()["VmRSS"]
start = time.perf_counter()
if kind == "pandas":
    frame = pd.read_csv(path, skiprows=int(sys.argv[3]), header=None)
    n = len(frame)
elif kind == "scope":
    n = read_waveform(path, columns="time=Time,mss@13=CH1,mss@18=CH2").time.size
else:
    n = read_waveform(path).time.size
wall = time.perf_counter() - start
print(json.dumps({"wall_s": wall, "peak_bytes": rss()["VmHWM"] - before, "rows": n}))
"""


def measure(kind: str, path: Path, *extra: str, repeat: int = 1) -> dict:
    """Best wall time and smallest peak of ``repeat`` reads, each in a new process."""
    runs = []
    for _ in range(repeat):
        out = subprocess.run([sys.executable, "-c", _CHILD, kind, str(path), *extra],
                             capture_output=True, text=True, check=True)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    return {"wall_s": round(min(r["wall_s"] for r in runs), 3),
            "peak_mb": round(min(r["peak_bytes"] for r in runs) / 1e6, 1),
            "rows": runs[0]["rows"]}


def main(rows: int = 1_000_000, repeat: int = 1) -> dict:
    report: dict = {"rows": rows, "cpu_count": os.cpu_count(),
                    "load_average_1min": round(os.getloadavg()[0], 2)}
    with tempfile.TemporaryDirectory() as tmp:
        files = write_files(Path(tmp), rows)
        skip = {"scope": 6, "msens": 3}  # lines before the numbers: a user's skiprows
        for kind, path in files.items():
            size = path.stat().st_size
            ours = measure(kind, path, repeat=repeat)
            plain = measure("pandas", path, str(skip[kind]), repeat=repeat)
            report[kind] = {
                "file_mb": round(size / 1e6, 1),
                "msens": ours,
                "pandas_read_csv": plain,
                "memory_over_file_size": round(ours["peak_mb"] * 1e6 / size, 2),
                "ratio_time": round(ours["wall_s"] / plain["wall_s"], 2),
                "ratio_memory": round(ours["peak_mb"] / max(plain["peak_mb"], 1e-3), 2),
            }
    return report


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=1)
    a = ap.parse_args()
    start = time.perf_counter()
    result = main(a.rows, a.repeat)
    result["benchmark_s"] = round(time.perf_counter() - start, 1)
    print(json.dumps(result, indent=2))

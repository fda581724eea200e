"""Fuzz campaign over the msens commands: hostile study files, waveform files, sweep specs,
command-line arguments and Python API calls.

Each case runs ``msens.cli.main`` in a forked child (the parent has imported msens and
compiled the chain kernel once) with a wall-clock limit and a memory limit; the outcome is
classified as

- ``ok``: exit 0 (the input was accepted and the command finished),
- ``input``: exit 2 with one ``msens: error:`` line,
- ``internal``: exit 1 with msens's internal-error line (a bug),
- ``traceback``: an exception escaped ``main`` (a bug),
- ``timeout``: over the time limit and silent (a hang); ``crash``: the child died (signal,
  memory);
- ``long-work``: over the time limit (or 60 s of CPU) while still reporting progress on
  work whose size the input asks for: a study whose changed sensor geometry needs a new
  field model and its contact maps (minutes), or a sampler asked for many steps
  (``calibrate --steps 10001``); counted apart, listed for review;
- ``py-warning``: a Python warning (numpy, matplotlib...) reached stderr;
- ``unresolved-ok``: exit 0 from ``msens run`` whose summary reports a TOF or AR that its
  record cannot hold (a pulse narrower than two samples, a TOF that is not positive, or a
  missing feature without a note saying why): confident nonsense (issue 38).

Besides mutated studies, waveform files, sweeps and uncertainty files (``msens uq`` and
``msens calibrate`` read them), the campaign draws hostile command-line arguments
(``--scheduler``, ``--workers``, ``--out``, ``--shots``, ``--columns``, ``--set``,
``--samples``, ``--steps``, ``--param``...) for every command and
Python API calls (``msens.api.load(None)``, ``synth(study, "x.csv", shots=2.5)``...), and
studies mutated only in the keys that decide whether a record resolves the pulse (sample
rates, record length, bead count, drop height, damping).

The cases are random but seeded (``--seed``), so a campaign is reproducible. Usage::

    python benchmarks/fuzz_campaign.py --cases 2000 --out fuzz-report.json

The report lists the counts, every bad outcome with its reproducer, and the accepted cases
grouped by category (which key was changed and how), for review.
"""

from __future__ import annotations

import argparse
import copy
import io
import json
import math
import os
import random
import resource
import select
import signal
import sys
import time
import tomllib
import traceback
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.hostile: the tiny study and the TOML writer

from benchmarks.calibrate_coverage import INPUTS as COVERAGE_INPUTS  # noqa: E402
from tests.hostile.conftest import TWENTY  # noqa: E402
from tests.hostile.tomltext import dumps  # noqa: E402

import msens.cli  # noqa: E402

#: Uncertain inputs of the tiny study (msens.uncertainty/1) for ``uq`` and ``calibrate``:
#: the calibration-coverage benchmark's.
INPUTS = COVERAGE_INPUTS.replace('study = "coverage"', 'study = "tiny"')

HOSTILE_VALUES: list[Any] = [
    0, -1, 1, 0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e300, 1e308, -1e308, math.nan, math.inf,
    -math.inf, 2**63, -2**63, 10**30, True, False, "", "NaN", "x" * 200, "AWG99", [], [1, 2],
    [0, 0], {}, {"a": 1}, 1e-12, 1e12, 3, 0.5, -0.5, 1e6, 1e-6,
]


# --------------------------------------------------------------------------- running a case

#: Longest wait for a progress line, s: a stage speaks at least every 4 s (msens.progress's
#: heartbeat), so a case silent for longer when it is stopped has stalled.
STALL_S = 20.0


def _field_work(stderr: str) -> bool:
    """Whether a case's progress shows work whose size the input asks for: a field model
    (solves, maps, meshes) or a sampler's steps and runs (``calibrate --steps 10001``)."""
    return any(w in stderr for w in ("field model", "contact map", "mesh", "transducer",
                                     "eddy-current", "bias", "calibrate steps",
                                     "uq model runs"))


def _overdue(progress: Path, seconds: float) -> dict:
    """The outcome of a case stopped at the time limit: ``long-work`` if it was still
    reporting progress on field-model work (a changed sensor geometry legitimately solves
    a new field model and its contact maps: minutes), else ``timeout`` (a hang)."""
    try:
        text = progress.read_text(encoding="utf-8", errors="replace")
        quiet = time.time() - progress.stat().st_mtime
    except OSError:
        text, quiet = "", math.inf
    lines = [line for line in text.splitlines() if line.strip()]
    stage = lines[-1] if lines else ""
    field_work = _field_work(text)
    outcome = "long-work" if field_work and quiet < STALL_S else "timeout"
    return {"outcome": outcome, "seconds": seconds, "cpu_seconds": float("nan"),
            "message": stage[-300:], "quiet_s": quiet}


def run_case(argv: list[str], timeout: float, mem_gb: float) -> dict:
    """``msens.cli.main(argv)`` in a forked child; its outcome as a dict."""
    progress = Path(os.environ.get("MSENS_FUZZ_WORK", ".")) / "case-stderr.txt"
    r, w = os.pipe()
    start = time.monotonic()
    pid = os.fork()
    if pid == 0:  # child
        os.close(r)
        try:
            limit = int(mem_gb * 2**30)
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
            out = io.StringIO()
            # stderr to a file as it is written: a case over the limit is judged by it
            err = open(progress, "w+", buffering=1, encoding="utf-8")
            sys.stdout, sys.stderr = out, err
            tb = ""
            try:
                code = msens.cli.main(argv) if isinstance(argv, list) else _api_case(argv)
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            except BaseException:
                tb = traceback.format_exc()
                code = 1
            err.seek(0)
            res = {"code": code, "stderr": err.read()[-4000:], "traceback": tb[-4000:]}
        except BaseException:
            res = {"code": 1, "stderr": "", "traceback": traceback.format_exc()[-4000:]}
        os.write(w, json.dumps(res).encode())
        os._exit(0)
    os.close(w)
    data = b""
    while True:
        left = start + timeout - time.monotonic()
        if left <= 0:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(r)
            return _overdue(progress, time.monotonic() - start)
        ready, _, _ = select.select([r], [], [], min(left, 1.0))
        if ready:
            chunk = os.read(r, 1 << 16)
            if not chunk:
                break
            data += chunk
    os.close(r)
    _, status, usage = os.wait4(pid, 0)
    seconds = time.monotonic() - start
    cpu = usage.ru_utime + usage.ru_stime  # the bound that a loaded machine does not blur
    try:
        res = json.loads(data)
    except ValueError:
        return {"outcome": "crash", "seconds": seconds, "cpu_seconds": cpu, "status": status}
    err = res["stderr"]
    errors = [line for line in err.splitlines() if line.startswith("msens: error:")]
    nonsense = _unresolved(argv) if res["code"] == 0 and not res["traceback"] else None
    if res["traceback"]:
        outcome = "traceback"
    elif "msens: internal error" in err:
        outcome = "internal"
    elif _py_warning(err):
        outcome = "py-warning"
        errors = [_py_warning(err)]
    elif res["code"] == 0 and nonsense:
        outcome = "unresolved-ok"
        errors = [nonsense]
    elif res["code"] == 0:
        outcome = "ok"
    elif res["code"] == 2 and len(errors) == 1 and "Traceback" not in err:
        outcome = "input"
    else:
        outcome = "other"
    return {"outcome": outcome, "seconds": seconds, "cpu_seconds": cpu, "code": res["code"],
            "field_work": _field_work(err),
            "message": errors[0] if errors else err.strip().splitlines()[-1:] and
            err.strip().splitlines()[-1], "traceback": res["traceback"]}


def _py_warning(stderr: str) -> str | None:
    """A Python warning that reached the user (``file.py:12: RuntimeWarning: ...``): under
    ``python -W error`` it is an internal error; msens says what it means or avoids it."""
    import re

    m = re.search(r"^\S+:\d+: (\w*Warning): (.*)$", stderr, re.MULTILINE)
    return f"{m.group(1)}: {m.group(2)[:200]}" if m else None


def _api_case(expr: str) -> int:
    """Evaluate a Python API call (an expression over ``api``, ``study``, ``work``, ``Path``)
    in the child: 0 if it returns, 2 with one ``msens: error:`` line on InputError; any
    other exception propagates (a traceback: a bug)."""
    from msens import api
    from msens.errors import InputError
    from msens.field.geometry import BeadChain

    env = {"api": api, "Path": Path, "work": Path(os.environ["MSENS_FUZZ_WORK"]),
           "math": math, "BeadChain": BeadChain}
    env["study"] = api.load(env["work"] / "tiny.toml")
    try:
        eval(expr, env)  # the campaign's own generated expressions
    except InputError as exc:
        print(f"msens: error: {exc}", file=sys.stderr)
        return 2
    return 0


def _unresolved(argv) -> str | None:
    """Why an exit-0 ``msens run`` reports features its record cannot hold, or None."""
    if not isinstance(argv, list) or not argv or argv[0] != "run" or "--out" not in argv:
        return None
    summary = Path(argv[argv.index("--out") + 1]) / "summary.json"
    try:
        rows = json.loads(summary.read_text())["rows"]
        text = Path(argv[1]).read_text()
        rate = tomllib.loads(text).get("simulation", {}).get("sample_rate_hz")
    except (OSError, ValueError, KeyError, IndexError, TypeError):
        return None
    for r in rows:
        tof, ar, width = r.get("tof_us"), r.get("ar"), r.get("width_us")
        if tof is None or ar is None:
            if not r.get("note"):
                return f"{r.get('sensor')}@{r.get('particle')}: TOF/AR missing without a note"
            continue
        if not tof > 0:
            return f"{r.get('sensor')}@{r.get('particle')}: TOF {tof} us is not positive"
        if isinstance(rate, int | float) and width is not None and width * 1e-6 * rate < 2:
            return (f"{r.get('sensor')}@{r.get('particle')}: pulse width {width} us spans "
                    f"fewer than two samples at {rate} Hz")
    return None


# --------------------------------------------------------------------------- mutations

def write_doc(path: Path, doc: dict, notes: list[str]) -> Path:
    """Write ``doc`` as TOML to ``path``, or as its Python text when no TOML can hold it (a
    mutation left a None or an odd type: also hostile, noted)."""
    try:
        path.write_text(dumps(doc))
    except (TypeError, ValueError):
        path.write_text(str(doc))
        notes.append("not TOML")
    return path


def leaves(doc: Any, path: tuple = ()) -> list[tuple]:
    if isinstance(doc, dict):
        return [p for k, v in doc.items() for p in leaves(v, (*path, k))]
    if isinstance(doc, list) and doc and all(isinstance(x, dict) for x in doc):
        return [p for i, v in enumerate(doc) for p in leaves(v, (*path, i))]
    return [path]


def tables(doc: Any, path: tuple = ()) -> list[tuple]:
    if isinstance(doc, dict):
        return [path] + [p for k, v in doc.items() for p in tables(v, (*path, k))]
    if isinstance(doc, list) and doc and all(isinstance(x, dict) for x in doc):
        return [p for i, v in enumerate(doc) for p in tables(v, (*path, i))]
    return []


def node(doc: Any, path: tuple) -> Any:
    for p in path:
        doc = doc[p]
    return doc


def key_name(path: tuple) -> str:
    """``sensor[].coil.turns``: the key without array indices (the category)."""
    return ".".join(f"{p}" if isinstance(p, str) else "[]" for p in path).replace(".[]", "[]")


def mutate(doc: dict, rng: random.Random) -> tuple[dict, list[str]]:
    """One to three edits; returns the new document and a description of each edit."""
    doc = copy.deepcopy(doc)
    notes = []
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        paths = leaves(doc)
        if not paths:
            break
        path = rng.choice(paths)
        parent, key = node(doc, path[:-1]), path[-1]
        old = parent[key]
        kind = rng.choice(["value", "scale", "scale", "remove", "unknown", "type"])
        if kind == "scale" and isinstance(old, int | float) and not isinstance(old, bool):
            factor = 10.0 ** rng.randint(-40, 40) * rng.choice([1, -1])
            new = old * factor
            if isinstance(old, int) and abs(new) < 2**62:
                new = int(new)
            parent[key] = new
            notes.append(f"scale {key_name(path)} x{factor:g}")
        elif kind == "remove":
            del parent[key]
            notes.append(f"remove {key_name(path)}")
        elif kind == "unknown":
            t = rng.choice(tables(doc))
            node(doc, t)[rng.choice(["colour", "Beads", "t_end", "gamma"])] = 1
            notes.append(f"unknown key in {key_name(t) or 'root'}")
        elif kind == "type":
            parent[key] = rng.choice([str(old), [old], {"v": old}, None is old])
            notes.append(f"type {key_name(path)}")
        else:
            parent[key] = rng.choice(HOSTILE_VALUES)
            notes.append(f"value {key_name(path)}={parent[key]!r:.30}")
    return doc, notes


def damage_bytes(data: bytes, rng: random.Random, text: bool) -> tuple[bytes, list[str]]:
    b = bytearray(data)
    notes = []
    for _ in range(rng.choice([1, 1, 2, 4])):
        if not b:
            break
        kinds = (["byte", "cut", "line", "number", "header", "cr"] if text
                 else ["byte", "cut", "zero"])
        kind = rng.choice(kinds)
        at = rng.randrange(len(b))
        if kind == "byte":
            b[at] = rng.randrange(256)
        elif kind == "cut":
            del b[at:]
        elif kind == "zero":
            b[at:at + 64] = bytes(len(b[at:at + 64]))
        elif kind == "cr":  # classic Mac line endings: the whole file is one "line"
            b = bytearray(bytes(b).replace(b"\r\n", b"\n").replace(b"\n", b"\r"))
        elif kind == "line":
            lines = bytes(b).split(b"\n")
            i = rng.randrange(len(lines))
            if rng.random() < 0.5:
                lines.insert(i, lines[i])
            else:
                lines.pop(i)
            b = bytearray(b"\n".join(lines))
        elif kind == "number":
            lines = bytes(b).split(b"\n")
            i = rng.randrange(len(lines))
            cells = lines[i].split(b",")
            cells[rng.randrange(len(cells))] = rng.choice(
                [b"nan", b"-inf", b"1e308", b"0", b"-1e-300", b"", b"x", b"1e999", b"1,2"])
            lines[i] = b",".join(cells)
            b = bytearray(b"\n".join(lines))
        else:
            b = bytearray(bytes(b).replace(b"time_s,", rng.choice(
                [b"time_s,bead@10#2,", b"t,", b"time_s,,", b"time_s,bead@15,", b"time_s,mss@0,",
                 b"\xef\xbb\xbftime_s,"]), 1))
        notes.append(kind)
    return bytes(b), notes


def transform_record(waveform, rng: random.Random):
    """A whole-record transformation (physical or not) of a valid waveform."""
    import numpy as np

    from msens.io import Waveform

    kind = rng.choice(["invert", "time-scale", "amplitude", "noise-only", "offset", "shift",
                       "resample", "drop-channel", "identity"])
    t, d, ch = waveform.time.copy(), waveform.data.copy(), waveform.channels
    note = kind
    if kind == "invert":
        d = -d
    elif kind == "time-scale":
        f = rng.choice([1e-6, 1e-3, 0.5, 0.8, 1.25, 2.0, 1e3, 1e6])
        t = t * f
        note += f" x{f:g}"
    elif kind == "amplitude":
        f = 10.0 ** rng.randint(-320, 300)
        d = d * f
        note += f" x{f:g}"
    elif kind == "noise-only":
        d = np.random.default_rng(rng.randrange(2**32)).normal(0, 1e-3, d.shape)
    elif kind == "offset":
        d = d + rng.choice([-10.0, 1.0, 1e3])
    elif kind == "shift":
        t = t + rng.choice([-1e-3, -1e-4, 1e-4, 1e-2])
    elif kind == "resample":
        t, d = t[::2], d[::2]
    elif kind == "drop-channel" and len(ch) > 1:
        keep = [i for i in range(len(ch)) if i != rng.randrange(len(ch))]
        d, ch = d[:, keep], tuple(ch[i] for i in keep)
    return Waveform(t, d, ch, waveform.metadata), note


#: Scheduler addresses: malformed, other protocols, unreachable.
ADDRESSES = ["garbage", "", " ", "tcp://", "tcp://:8786", "inproc://x", "tls://127.0.0.1:8786",
             "ucx://127.0.0.1:1", "127.0.0.1", "tcp://127.0.0.1:1", "tcp://127.0.0.1:99999",
             "tcp://[::1]:1", "localhost:0", "x" * 3000, "tcp://a b:1", "http://example.org",
             "tcp://127.0.0.1:-1", "\u00e9t\u00e9:1"]
#: Output paths: empty, folders, devices, unwritable places, very long names, bad suffixes.
OUTS = ["", ".", "/", "/proc/self/msens-fuzz.csv", "/proc/x/y.csv", "/dev/null", "/dev/full",
        "/sys/msens.csv", "x.txt", "noext", "a/" * 200 + "x.csv", "y" * 300 + ".csv",
        "/mnt/msens-full/x.csv", "/mnt/msens-ro/x.csv", "~nobody/x.csv"]
NUMBERS = ["0", "-3", "2.5", "1e9", "nan", "inf", "-0", "10001", "x", "", "999999999999999999999"]
#: --set KEY=VALUE arguments: malformed, unknown, out of range, of the wrong type, huge.
SETS = ["", "=", "chain.beads", "chain.beads=", "=3", "chain..beads=3", ".chain.beads=3",
        "chain.beads=x", "chain.beads=[1", "chain.beads=3.5", "chain.beads=-0",
        "chain.beads=1e400", "chain.beads=99999999999999999999999", "chain=3",
        "chain.beads.x=3", "sensor.99.particle=3", "sensor.0.particle=3", "sensor.x.particle=3",
        "sensor.1.kind='mss'", "striker.drop_height_m=nan", "striker.drop_height_m=-0.0",
        "striker.drop_height_m=inf", "simulation.t_end_s=1e-300", "nope.key=1",
        "name=" + "x" * 3000, "x" * 3000 + "=1", "chain.beads={a=1}", "schema='x'",
        'name="\u0000"', "chain.damping='linear'", "chain.damping=3"]


def cli_case(rng: random.Random, work: Path, i: int) -> tuple[str, list[str]]:
    """A command line with one or two hostile arguments."""
    tiny, mss = str(work / "tiny.toml"), str(work / "tiny-mss.toml")
    sweep, record = str(work / "sweep-coil.toml"), str(work / "record.csv")
    out = str(work / f"a{i}")
    command = rng.choice(["run", "design", "synth", "convert", "check-waveform", "compare",
                          "diagnose", "field", "uq", "calibrate", "study"])
    inputs = str(work / "inputs.toml")
    if command == "uq":
        argv = ["uq", tiny, "--inputs", inputs, "--samples", "8", "--workers", "1",
                "--out", out]
        extra = rng.choice([["--samples", rng.choice([*NUMBERS, "7", "3", "65536"])],
                            ["--seed", rng.choice(NUMBERS)], ["--workers", rng.choice(NUMBERS)],
                            ["--scheduler", rng.choice(ADDRESSES)], ["--out", rng.choice(OUTS)],
                            ["--inputs", rng.choice(["/dev/zero", "/tmp", "", record, tiny])],
                            ["--format", rng.choice(["jpg", "", "PDF"])]])
    elif command == "calibrate":
        argv = ["calibrate", record, "--study", tiny, "--inputs", inputs,
                "--param", "striker.drop_height_m", "--param", "chain.gamma_contact_kg_per_s",
                "--steps", "20", "--walkers", "4", "--out", out]
        extra = rng.choice([["--steps", rng.choice(NUMBERS)], ["--walkers", rng.choice(NUMBERS)],
                            ["--seed", rng.choice(NUMBERS)], ["--out", rng.choice(OUTS)],
                            ["--param", rng.choice(["", "x", "chain.beads", "chain",
                                                    "striker.drop_height_m", "x" * 400])],
                            ["--reference", rng.choice(["", "nope", "tiny"])],
                            ["--columns", rng.choice(["", "time", "x" * 3000])],
                            ["--set", rng.choice(SETS)],
                            ["--inputs", rng.choice(["/dev/zero", "/tmp", "", record])]])
    elif command == "study":
        argv = ["study", tiny]
        extra = rng.choice([["--set", rng.choice(SETS)],
                            ["--set", rng.choice(SETS), "--set", rng.choice(SETS)],
                            ["--out", rng.choice([*OUTS, tiny, str(work / f"st{i}.toml")])]])
    elif command == "run":
        argv = ["run", tiny, "--out", out, "--no-figures"]
        extra = rng.choice([["--scheduler", rng.choice(ADDRESSES)], ["--out", rng.choice(OUTS)],
                            ["--format", rng.choice(["png", "jpg", "", "PDF"])],
                            ["--set", rng.choice(SETS)]])
    elif command == "design":
        argv = ["design", mss, "--sweep", sweep, "--out", out, "-q"]
        extra = rng.choice([["--scheduler", rng.choice(ADDRESSES)],
                            ["--workers", rng.choice(NUMBERS)], ["--out", rng.choice(OUTS)],
                            ["--sweep", rng.choice(["/dev/zero", "/tmp", "", record])]])
    elif command == "synth":
        argv = ["synth", tiny, "--out", str(work / f"syn{i}.csv")]
        extra = rng.choice([["--out", rng.choice(OUTS)], ["--shots", rng.choice(NUMBERS)],
                            ["--noise", rng.choice(NUMBERS)], ["--seed", rng.choice(NUMBERS)],
                            ["--setup", rng.choice(["", "nope", "x" * 500])]])
    elif command == "convert":
        argv = ["convert", record, str(work / f"conv{i}.npz")]
        extra = []
        argv[2] = rng.choice([*OUTS, str(work / f"conv{i}.tdms")])
    elif command == "check-waveform":
        argv = ["check-waveform", rng.choice([record, "/dev/zero", "/proc/self/status", "/tmp",
                                              "", str(work / "missing.csv")])]
        extra = rng.choice([[], ["--columns", rng.choice(
            ["", "time", "x" * 5000, "time=Time:s," * 400, "time=time_s,bead@1e30=bead@10"])]])
    elif command == "compare":
        argv = ["compare", tiny, record, "--out", out]
        extra = rng.choice([["--out", rng.choice(OUTS)], ["--format", "jpg"]])
    elif command == "diagnose":
        argv = ["diagnose", record, "--study", tiny, "--out", out]
        extra = rng.choice([["--passes", rng.choice(NUMBERS)], ["--reference", "nope"],
                            ["--out", rng.choice(OUTS)]])
    else:
        argv = ["field", tiny, "--out", out]
        extra = []
    argv += extra
    return f"{command} {' '.join(a[:40] for a in extra)}", argv


def api_case(rng: random.Random) -> tuple[str, str]:
    """A Python API call with a hostile argument (an expression for :func:`_api_case`)."""
    bad = rng.choice(["None", "3", "2.5", "''", "'x.csv'", "[]", "{}", "math.nan", "True",
                      "b'x'", "Path('/dev/zero')", "Path('/proc/self/x.csv')", "-1", "10**30",
                      "'x' * 5000", "object()"])
    calls = [f"api.load({bad})", f"api.synth(study, {bad})",
             f"api.synth(study, work / 'api.csv', shots={bad})",
             f"api.synth(study, work / 'api.csv', noise={bad})",
             f"api.synth(study, work / 'api.csv', seed={bad})",
             f"api.synth(study, work / 'api.csv', setup={bad})",
             f"api.synth({bad}, work / 'api.csv')", f"api.run({bad})",
             f"api.run(study, scheduler={bad})",
             f"api.design(study, work / 'sweep-coil.toml', work / 'api-d', workers={bad})",
             f"api.design(study, work / 'sweep-coil.toml', work / 'api-d', scheduler={bad})",
             f"api.design(study, {bad}, work / 'api-d')",
             f"api.replace(study, {{'chain.beads': {bad}}})",
             f"api.compare(study, {bad}, work / 'api-c')",
             f"BeadChain(contact_layer={bad})", f"BeadChain(count={bad})"]
    expr = rng.choice(calls)
    # the good value of a call that only fails by its hostile argument would run a study:
    # keep those that are plainly valid out (a tiny run is fine, but not a design)
    return expr.split("(")[0], expr


#: Keys deciding whether a record resolves the pulse, and hostile values for them.
RESOLVE_KEYS = {
    ("simulation", "sample_rate_hz"): [1e3, 1e4, 5e4, 1e5, 2e5, 5e5, 1e6],
    ("simulation", "t_end_s"): [2e-5, 5e-5, 1e-4, 1.5e-4, 2e-4, 4e-4, 1e-3, 0.1, 1.0],
    ("chain", "beads"): [2, 3, 5, 40, 100, 300],
    ("striker", "drop_height_m"): [1e-6, 1e-4, 0.5, 2.0, 3.0, 10.0],
    ("chain", "gamma_contact_kg_per_s"): [0.0, 20.0, 60.0, 200.0, 1000.0],
    ("electronics", "sample_rate_hz"): [1e3, 1e5, 1e6],
}


def resolve_case(doc: dict, rng: random.Random) -> tuple[dict, list[str]]:
    """``doc`` with one to three resolvability keys set to hostile values."""
    doc = copy.deepcopy(doc)
    notes = []
    for key in rng.sample(sorted(RESOLVE_KEYS), rng.choice([1, 1, 2, 3])):
        value = rng.choice(RESOLVE_KEYS[key])
        doc.setdefault(key[0], {})[key[1]] = value
        notes.append(f"{key[0]}.{key[1]}={value:g}")
    if doc["simulation"]["t_end_s"] * doc["simulation"]["sample_rate_hz"] > 2e6:
        doc["simulation"]["t_end_s"] = 2e6 / doc["simulation"]["sample_rate_hz"]
        notes.append("t_end_s capped at 2e6 samples")
    return doc, notes


# --------------------------------------------------------------------------- the campaign

def cases(args: argparse.Namespace, work: Path):
    """Yield (category, description, argv) for the whole campaign."""
    from msens import api
    from msens.io import read_waveform, write_waveform

    rng = random.Random(args.seed)
    shipped = {"paper-mss": tomllib.loads((ROOT / "studies" / "paper-mss.toml").read_text()),
               "paper-table2": tomllib.loads((ROOT / "src" / "msens" / "data" /
                                              "paper-table2.toml").read_text()),
               "tiny": tomllib.loads(TWENTY),
               "inputs": tomllib.loads(INPUTS)}
    # the shipped sweeps, moved to the tiny physics study's sensor (particle 6); the magnet
    # sweep cut to two designs (each is a field solve: 24 would take minutes, legitimately)
    sweeps = {p.stem: tomllib.loads(p.read_text())
              for p in sorted((ROOT / "studies").glob("sweep-*.toml"))}
    for doc in sweeps.values():
        doc["sensor"] = 6
    magnet = sweeps["sweep-magnet"]["magnet"]
    sweeps["sweep-magnet"]["magnet"] = {"grade": magnet["grade"]}
    # the tiny study has no contact maps to verify with (verify would be refused, exit 2)
    sweeps["sweep-magnet"].get("model", {}).pop("verify", None)
    design_study = ROOT / "tests" / "data" / "tiny-mss.toml"
    tiny = work / "tiny.toml"
    tiny.write_text(TWENTY)
    (work / "inputs.toml").write_text(INPUTS)
    (work / "tiny-mss.toml").write_text(design_study.read_text())
    (work / "sweep-coil.toml").write_text(dumps(sweeps["sweep-coil"]))
    os.environ["MSENS_FUZZ_WORK"] = str(work)
    record = api.synth(api.load(tiny), work / "record.csv", shots=2, noise=0.01, seed=5)
    good = read_waveform(record)
    for suffix in (".npz", ".tdms"):
        write_waveform(good, work / f"record{suffix}")
    n = args.cases
    plan = (["study:paper-mss"] * int(0.08 * n) + ["study:paper-table2"] * int(0.08 * n)
            + ["study:tiny"] * int(0.12 * n) + ["inputs"] * int(0.05 * n)
            + ["resolve"] * int(0.10 * n)
            + ["wave:csv"] * int(0.10 * n) + ["wave:npz"] * int(0.04 * n)
            + ["wave:tdms"] * int(0.04 * n) + ["wave:record"] * int(0.07 * n)
            + ["sweep"] * int(0.10 * n) + ["cli"] * int(0.12 * n) + ["api"] * int(0.10 * n))
    plan += ["study:tiny"] * (n - len(plan))
    rng.shuffle(plan)
    for i, what in enumerate(plan):
        out = work / f"out{i}"
        if what == "cli":
            note, argv = cli_case(rng, work, i)
            yield f"cli:{argv[0]}", note, argv
            continue
        if what == "api":
            name, expr = api_case(rng)
            yield f"api:{name}", expr, expr
            continue
        if what == "inputs":
            doc, notes = mutate(shipped["inputs"], rng)
            path = write_doc(work / f"in{i}.toml", doc, notes)
            if rng.random() < 0.5:
                argv = ["uq", str(tiny), "--inputs", str(path), "--samples", "8",
                        "--workers", "1", "--out", str(out), "-q"]
            else:
                argv = ["calibrate", str(work / "record.csv"), "--study", str(tiny),
                        "--inputs", str(path), "--steps", "20", "--walkers", "8",
                        "--out", str(out), "-q"]
            yield f"inputs:{argv[0]}", "; ".join(notes), argv
            continue
        if what == "resolve":
            doc, notes = resolve_case(shipped["tiny"], rng)
            path = work / f"rs{i}.toml"
            path.write_text(dumps(doc))
            yield what, "; ".join(notes), ["run", str(path), "--out", str(out), "--no-figures"]
            continue
        if what.startswith("study:"):
            name = what.split(":")[1]
            doc, notes = mutate(shipped[name], rng)
            path = write_doc(work / f"s{i}.toml", doc, notes)
            yield what, "; ".join(notes), ["run", str(path), "--out", str(out), "--no-figures"]
        elif what.startswith("wave:") and what != "wave:record":
            fmt = what.split(":")[1]
            raw = (work / f"record.{fmt}").read_bytes()
            data, notes = damage_bytes(raw, rng, text=fmt == "csv")
            path = work / f"w{i}.{fmt}"
            path.write_bytes(data)
            command = rng.choice(["check-waveform", "compare", "convert"])
            if command == "check-waveform":
                argv = ["check-waveform", str(path)]
            elif command == "convert":
                argv = ["convert", str(path), str(work / f"c{i}.{rng.choice(['csv', 'npz'])}")]
            else:
                argv = ["compare", str(tiny), str(path), "--out", str(out)]
            yield f"{what}:{command}", "; ".join(notes), argv
        elif what == "wave:record":
            w, note = transform_record(good, rng)
            path = work / f"r{i}.csv"
            try:
                write_waveform(w, path)
            except Exception as exc:
                yield what, f"{note} (writer refused: {type(exc).__name__})", \
                    ["check-waveform", str(work / "missing.csv")]
                continue
            command = rng.choice(["compare", "diagnose"])
            argv = (["compare", str(tiny), str(path), "--out", str(out)] if command == "compare"
                    else ["diagnose", str(path), "--study", str(tiny), "--out", str(out)])
            yield f"{what}:{command}", note, argv
        else:
            name = rng.choice(sorted(sweeps))
            doc, notes = mutate(sweeps[name], rng)
            model = doc.get("model")
            if isinstance(model, dict) and model.get("contact_map") is True:
                # contact maps take minutes per design by design (README: 11-12 s per
                # contact): legitimately long work, not a hang
                model["contact_map"] = False
                notes.append("contact_map kept false (minutes per design)")
            path = write_doc(work / f"sw{i}.toml", doc, notes)
            yield f"sweep:{name}", "; ".join(notes), [
                "design", str(design_study), "--sweep", str(path),
                "--out", str(out), "--workers", "1"]


def refusal(message: str) -> str:
    """The kind of an input error: the key it names, else its text without file names."""
    import re

    text = re.sub(r"/\S+", "<file>", message.removeprefix("msens: error: "))
    key = re.search(r"'([A-Za-z_][^']*)'", text)
    return f"key {re.sub(r'[0-9]+', '#', key.group(1))}" if key else text[:70]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", type=int, default=2000)
    p.add_argument("--seed", type=int, default=24)
    p.add_argument("--timeout", type=float, default=180.0,
                   help="wall-clock limit per case, s (the 60 s bound is checked on CPU time, "
                        "which a loaded machine does not stretch)")
    p.add_argument("--mem-gb", type=float, default=6.0)
    p.add_argument("--work", default="/tmp/msens-fuzz")
    p.add_argument("--out", default="fuzz-report.json")
    p.add_argument("--stop-at", type=float, default=None,
                   help="stop (and report) after this many seconds")
    args = p.parse_args()
    work = Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    args.out = str(Path(args.out).resolve())
    os.chdir(work)  # relative hostile outputs ("noext", "x.txt") land in the work folder
    os.environ.setdefault("MPLBACKEND", "Agg")
    import logging

    logging.getLogger("msens").setLevel(logging.WARNING)
    results = []
    start = time.monotonic()
    for i, (category, note, argv) in enumerate(cases(args, work)):
        res = run_case(argv, args.timeout, args.mem_gb)
        res.update(category=category, note=note, argv=argv)
        results.append(res)
        if res["outcome"] not in ("ok", "input", "long-work"):
            print(f"[{i}] {res['outcome']}: {category} {note}: {argv}\n"
                  f"    {res.get('message')}\n{res.get('traceback', '')[-800:]}", flush=True)
        if i % 50 == 0:
            counts = Counter(r["outcome"] for r in results)
            print(f"{i} cases, {time.monotonic() - start:.0f} s: {dict(counts)}", flush=True)
            write_report(results, args)
        if args.stop_at is not None and time.monotonic() - start > args.stop_at:
            break
    return write_report(results, args)


def write_report(results: list[dict], args: argparse.Namespace) -> int:
    """Write the report of ``results`` to ``args.out``; 0 if nothing bad happened."""
    counts = Counter(r["outcome"] for r in results)
    # over 60 s of CPU without field-model work to show for it (a new sensor geometry solves
    # a field model and its contact maps: minutes of legitimate work, counted apart)
    over = [r for r in results if not r["cpu_seconds"] <= 60.0
            and r["outcome"] != "long-work" and not r.get("field_work")]
    long_work = [r for r in results if r["outcome"] == "long-work"
                 or (r.get("field_work") and not r["cpu_seconds"] <= 60.0)]
    accepted: dict[str, list[str]] = defaultdict(list)
    for r in results:
        if r["outcome"] == "ok":
            accepted[r["category"]].append(r["note"])
    refused_by = Counter(refusal(r.get("message") or "") for r in results
                         if r["outcome"] == "input")
    report = {
        "cases": len(results), "seed": args.seed, "counts": dict(counts),
        "over_60_s_cpu": len(over), "max_cpu_seconds": max(r["cpu_seconds"] for r in results),
        "max_wall_seconds": max(r["seconds"] for r in results),
        "by_category": {c: dict(Counter(r["outcome"] for r in results if r["category"] == c))
                        for c in sorted({r["category"] for r in results})},
        "bad": [r for r in results if r["outcome"] not in ("ok", "input", "long-work")],
        "long_work_cases": len(long_work), "long_work": long_work,
        "accepted": {k: sorted(v) for k, v in sorted(accepted.items())},
        "top_refusals": refused_by.most_common(40),
    }
    Path(args.out).write_text(json.dumps(report, indent=1, default=str))
    print(json.dumps({k: report[k] for k in ("cases", "counts", "over_60_s_cpu",
                                              "long_work_cases", "max_cpu_seconds",
                                              "max_wall_seconds")}))
    return 0 if not report["bad"] and not over else 1


if __name__ == "__main__":
    sys.exit(main())

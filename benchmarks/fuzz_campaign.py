"""Fuzz campaign over the msens commands: hostile study files, waveform files and sweep specs.

Each case runs ``msens.cli.main`` in a forked child (the parent has imported msens and
compiled the chain kernel once) with a wall-clock limit and a memory limit; the outcome is
classified as

- ``ok``: exit 0 (the input was accepted and the command finished),
- ``input``: exit 2 with one ``msens: error:`` line,
- ``internal``: exit 1 with msens's internal-error line (a bug),
- ``traceback``: an exception escaped ``main`` (a bug),
- ``timeout``: over the time limit; ``crash``: the child died (signal, memory).

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

from tests.hostile.conftest import TWENTY  # noqa: E402
from tests.hostile.tomltext import dumps  # noqa: E402

import msens.cli  # noqa: E402

HOSTILE_VALUES: list[Any] = [
    0, -1, 1, 0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e300, 1e308, -1e308, math.nan, math.inf,
    -math.inf, 2**63, -2**63, 10**30, True, False, "", "NaN", "x" * 200, "AWG99", [], [1, 2],
    [0, 0], {}, {"a": 1}, 1e-12, 1e12, 3, 0.5, -0.5, 1e6, 1e-6,
]


# --------------------------------------------------------------------------- running a case

def run_case(argv: list[str], timeout: float, mem_gb: float) -> dict:
    """``msens.cli.main(argv)`` in a forked child; its outcome as a dict."""
    r, w = os.pipe()
    start = time.monotonic()
    pid = os.fork()
    if pid == 0:  # child
        os.close(r)
        try:
            limit = int(mem_gb * 2**30)
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
            out, err = io.StringIO(), io.StringIO()
            sys.stdout, sys.stderr = out, err
            tb = ""
            try:
                code = msens.cli.main(argv)
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            except BaseException:
                tb = traceback.format_exc()
                code = 1
            res = {"code": code, "stderr": err.getvalue()[-4000:], "traceback": tb[-4000:]}
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
            return {"outcome": "timeout", "seconds": time.monotonic() - start,
                    "cpu_seconds": float("nan")}
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
    if res["traceback"]:
        outcome = "traceback"
    elif "msens: internal error" in err:
        outcome = "internal"
    elif res["code"] == 0:
        outcome = "ok"
    elif res["code"] == 2 and len(errors) == 1 and "Traceback" not in err:
        outcome = "input"
    else:
        outcome = "other"
    return {"outcome": outcome, "seconds": seconds, "cpu_seconds": cpu, "code": res["code"],
            "message": errors[0] if errors else err.strip().splitlines()[-1:] and
            err.strip().splitlines()[-1], "traceback": res["traceback"]}


# --------------------------------------------------------------------------- mutations

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
        kinds = ["byte", "cut", "line", "number", "header"] if text else ["byte", "cut", "zero"]
        kind = rng.choice(kinds)
        at = rng.randrange(len(b))
        if kind == "byte":
            b[at] = rng.randrange(256)
        elif kind == "cut":
            del b[at:]
        elif kind == "zero":
            b[at:at + 64] = bytes(len(b[at:at + 64]))
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


# --------------------------------------------------------------------------- the campaign

def cases(args: argparse.Namespace, work: Path):
    """Yield (category, description, argv) for the whole campaign."""
    from msens import api
    from msens.io import read_waveform, write_waveform

    rng = random.Random(args.seed)
    shipped = {"paper-mss": tomllib.loads((ROOT / "studies" / "paper-mss.toml").read_text()),
               "paper-table2": tomllib.loads((ROOT / "src" / "msens" / "data" /
                                              "paper-table2.toml").read_text()),
               "tiny": tomllib.loads(TWENTY)}
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
    record = api.synth(api.load(tiny), work / "record.csv", shots=2, noise=0.01, seed=5)
    good = read_waveform(record)
    for suffix in (".npz", ".tdms"):
        write_waveform(good, work / f"record{suffix}")
    n = args.cases
    plan = (["study:paper-mss"] * int(0.17 * n) + ["study:paper-table2"] * int(0.13 * n)
            + ["study:tiny"] * int(0.25 * n) + ["wave:csv"] * int(0.12 * n)
            + ["wave:npz"] * int(0.05 * n) + ["wave:tdms"] * int(0.05 * n)
            + ["wave:record"] * int(0.10 * n) + ["sweep"] * int(0.13 * n))
    plan += ["study:tiny"] * (n - len(plan))
    rng.shuffle(plan)
    for i, what in enumerate(plan):
        out = work / f"out{i}"
        if what.startswith("study:"):
            name = what.split(":")[1]
            doc, notes = mutate(shipped[name], rng)
            path = work / f"s{i}.toml"
            try:
                path.write_text(dumps(doc))
            except (TypeError, ValueError):
                path.write_text(str(doc))  # not TOML at all: also hostile
                notes.append("not TOML")
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
            path = work / f"sw{i}.toml"
            try:
                path.write_text(dumps(doc))
            except (TypeError, ValueError):
                path.write_text(str(doc))
                notes.append("not TOML")
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
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("MPLBACKEND", "Agg")
    import logging

    logging.getLogger("msens").setLevel(logging.WARNING)
    results = []
    start = time.monotonic()
    for i, (category, note, argv) in enumerate(cases(args, work)):
        res = run_case(argv, args.timeout, args.mem_gb)
        res.update(category=category, note=note, argv=argv)
        results.append(res)
        if res["outcome"] not in ("ok", "input"):
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
    over = [r for r in results if not r["cpu_seconds"] <= 60.0]
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
        "bad": [r for r in results if r["outcome"] not in ("ok", "input")],
        "accepted": {k: sorted(v) for k, v in sorted(accepted.items())},
        "top_refusals": refused_by.most_common(40),
    }
    Path(args.out).write_text(json.dumps(report, indent=1, default=str))
    print(json.dumps({k: report[k] for k in ("cases", "counts", "over_60_s_cpu",
                                              "max_cpu_seconds", "max_wall_seconds")}))
    return 0 if not report["bad"] and not over else 1


if __name__ == "__main__":
    sys.exit(main())

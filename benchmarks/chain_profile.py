"""Where the chain kernel's time goes, per part of its step loop (prints JSON).

Runs a copy of :func:`msens.chain.kernel.stepper.integrate` with cycle counters (LLVM's
``readcyclecounter``) between the phases of its loop: choosing the step (openings), predicting
dashpot switches, the Runge-Kutta step(s), finding violated states, cut-backs, the end-of-step
bookkeeping, the dense output and the switch at the step's end. The copy is written to a
temporary folder and compiled there (no cache), so the first run takes ~1 min. Problem: the
paper chain (``linear-loading`` unless ``--law``), 64 damping values drawn as in
``chain_speed.py``'s batch, 1 ms, 1001 output samples, one thread; shares of the cycles spent
in the loop, and ns per step at the counter's rate (calibrated against the wall clock; the
loop's share of the wall time says how much falls outside the parts).

The counters cost a few ns each, and the parts are cut at source lines: after a change to
``stepper.integrate`` that moves them, the script stops and names the missing line.

Run: python benchmarks/chain_profile.py [--law linear|linear-loading] [--contacts 11,12,16,17]
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from msens.chain import DampingLaw, paper_chain, stable_step, striker_velocity
from msens.chain.integrate import _LAW_CODE, GRADE_LEVELS, _rate_tol, initial_state
from msens.chain.kernel import stepper

_COUNTER = '''
from llvmlite import ir as _ir
from numba.core import types as _types
from numba.extending import intrinsic as _intrinsic


@_intrinsic
def _cycles(typingctx):
    def codegen(context, builder, signature, args):
        fn = builder.module.declare_intrinsic("llvm.readcyclecounter",
                                              fnty=_ir.FunctionType(_ir.IntType(64), []))
        return builder.call(fn, [])
    return _types.int64(), codegen


@nb.njit
def cycles_now():
    return _cycles()

'''

#: Parts of the loop, each starting at the first line (after the previous part's) that begins
#: with this text.
PARTS = [
    ("step length and openings", "        h = nominal_length("),
    ("dashpot-switch prediction", "        k_pred = -1\n"),
    ("last-step stretch, Runge-Kutta step", "        if t + h > t_end - 0.01 * dt:"),
    ("violated states", "        if loading:\n            accelerations(u1, v1"),
    ("cut-backs and switches now", "        if kmin >= 0 and th_min <= THETA_NOW"),
    ("accelerations, predicted switch check", "        if not (loading and kmin < 0):"),
    ("predictor history", "        if loading:\n            keep_history("),
    ("jerks for the output", "        j1_ok = output_jerks("),
    ("dense output", "        j = dense_output("),
    ("switch at the step's end", "        t += h\n"),
]
#: The Runge-Kutta step with its Newton re-steps to an opening (not the cut-backs).
_RK_CALL = "        h, mode, k_open, taken = take_step("
_LOOP_END = "    return steps\n"


def _instrumented_source() -> str:
    src = inspect.getsource(stepper)
    start = src.index("def integrate(")
    head, body = src[:start], src[start:]
    # prof (the counters) through integrate into its step loop
    for a, b in [("store_uv, out_F, out_d, out_u, out_v, sel):",
                  "store_uv, out_F, out_d, out_u, out_v, sel, prof):"),
                 ("(out_F, out_d, out_u, out_v, sel))", "(out_F, out_d, out_u, out_v, sel), prof)"),
                 ("contacts, history, out):", "contacts, history, out, prof):")]:
        if a not in body:
            sys.exit(f"chain_profile: stepper.py has no {a!r}; update _instrumented_source")
        body = body.replace(a, b, 1)
    pos = 0
    for i, (_, line) in enumerate(PARTS):
        at = body.find(line, pos)
        if at < 0:
            sys.exit(f"chain_profile: stepper.integrate has no line starting {line!r} "
                     "after the previous part; update PARTS")
        mark = f"        _c{i} = _cycles()\n"
        if i:
            mark += f"        prof[{i - 1}] += _c{i} - _c{i - 1}\n"
        body = body[:at] + mark + body[at:]
        pos = at + len(mark) + len(line)
    last = len(PARTS) - 1
    end = body.index(_LOOP_END, pos)
    body = (body[:end] + f"        prof[{last}] += _cycles() - _c{last}\n" + body[end:])
    # The Runge-Kutta step (take_step: the regular step and its Newton re-steps).
    rk = body.index(_RK_CALL)
    after = body.index("\n", body.index(")", rk)) + 1
    body = body[:after] + f"        prof[{len(PARTS)}] += _cycles() - _rk\n" + body[after:]
    body = body[:rk] + "        _rk = _cycles()\n" + body[rk:]
    numpy = "\nimport numpy as np\n"
    if numpy not in head:
        sys.exit("chain_profile: stepper.py no longer imports numpy as np; update "
                 "_instrumented_source")
    head = head.replace(numpy, numpy + _COUNTER, 1)
    return (head + body).replace("cache=True", "cache=False")


def _load(source: str, folder: Path):
    path = folder / "kernel_profiled.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("kernel_profiled", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(law: DampingLaw, contacts: list[int] | None = None) -> dict:
    v = striker_velocity()
    t = np.linspace(0.0, 1e-3, 1001)
    gammas = np.random.default_rng(12345).uniform(0.0, 9.6, 64)
    prof = np.zeros(len(PARTS) + 1, dtype=np.int64)
    with tempfile.TemporaryDirectory() as folder:
        k = _load(_instrumented_source(), Path(folder))
        p = k.padded_length(30)
        sel = np.arange(p) if contacts is None else np.array(contacts, dtype=np.int64)
        runs = []
        for g in gammas:
            c = paper_chain(g, damping_law=law)
            u0, v0 = initial_state(c, v)
            runs.append((u0, v0, c.mass, c.stiffness, c.damping, c.drag, _LAW_CODE[law],
                         c.load(), t, stable_step(c, v), GRADE_LEVELS[law], _rate_tol(v), False,
                         np.empty((t.size, sel.size)), np.empty((t.size, sel.size)),
                         np.empty((1, 30)), np.empty((1, 30)), sel, prof))
        for r in runs:  # compile, warm up
            k.integrate(*r)
        # The counter's rate, against the wall clock.
        c0, t0 = k.cycles_now(), time.perf_counter_ns()
        time.sleep(0.2)
        per_ns = (k.cycles_now() - c0) / (time.perf_counter_ns() - t0)
        prof[:] = 0
        repeats = 5
        steps = 0
        start = time.perf_counter_ns()
        for _ in range(repeats):
            for r in runs:
                steps += k.integrate(*r)
        wall_ns = time.perf_counter_ns() - start
    loop = int(prof[:-1].sum())
    return {
        "problem": f"paper chain, {law.value}, 64 damping values 0-9.6 kg/s, 1 ms, 1001 "
                   "output samples, one thread",
        "contacts": "all" if contacts is None else contacts,
        "us_per_run": wall_ns / 1e3 / (repeats * len(runs)),
        "steps_per_run": steps / (repeats * len(runs)),
        "loop_share_of_wall": loop / per_ns / wall_ns,
        "parts": {name: {"share": float(prof[i] / loop),
                         "ns_per_step": float(prof[i] / per_ns / steps)}
                  for i, (name, _) in enumerate(PARTS)},
        "runge_kutta_step": {"share": float(prof[-1] / loop),
                                   "ns_per_step": float(prof[-1] / per_ns / steps)},
    }


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--law", choices=["linear", "linear-loading"], default="linear-loading")
    parser.add_argument("--contacts", type=lambda x: [int(c) for c in x.split(",")],
                        help="output only these contacts (0-based, comma-separated), as "
                             "simulate_batch(contacts=...); default all")
    args = parser.parse_args()
    print(json.dumps(main(DampingLaw(args.law), args.contacts), indent=2))

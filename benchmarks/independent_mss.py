"""Hidden-effect campaign of ``msens diagnose`` on data from an independent simulator.

Issue 35, item 5: physics-MsS data of the main study (``studies/paper-mss.toml``, its
magnetostatic variant: the simulator has no eddy currents) made by a
second implementation that is not msens's code path (:mod:`benchmarks.independent`: scipy's
DOP853 on the chain from its own static equilibrium, contact approaches from the beads'
positions, the coil flux and a read-out circuit of its own, the field model's tabulated
outputs perturbed by a seeded 1 %), with one hidden effect per file (every library effect
that applies to the physics MsS, at random plausible parameters), null files (1-8 shots) and
effects outside the library. Each file is written as a DAQ export would be read (``.npz``,
channels ``mss@13``/``mss@18`` in volts, ``#k`` per shot) and diagnosed with that study
(:func:`msens.diagnose.diagnose`, as ``msens diagnose`` does).

Prints JSON: per case the truth, the named effect, its fitted parameters and 95 % intervals,
whether the true parameter is inside its interval, whether explained, at-bound flags, the
times; and the totals against the issue's acceptance numbers. Each case's result is kept in
``<out>/results/<case>.json`` and reused by a later run (the campaign can be resumed).

Run: ``python benchmarks/independent_mss.py [--cases a,b,...] [--seed 35] [--out DIR]
[--generate-only] [--field-seed N]`` (``--cases`` takes case names or kinds: effect, null, outside).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

if __package__ in (None, ""):  # run as a script: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.independent import cases as cs
from benchmarks.independent import field, sim

#: The issue's acceptance numbers.
ACCEPTANCE = {"right_effect": 0.90, "inside_interval": 0.80, "nulls_explained": 5 / 6,
              "outside_named_confidently": 0, "named_at_bound": 0}


def setup(accuracy: float = field.FIELD_ACCURACY, field_seed: int = field.FIELD_SEED):
    """(study, study numbers, perturbed field tables, nominal world)."""
    study = field.main_study()
    s = sim.study_numbers(study)
    tables = field.perturbed(field.read_tables(study), accuracy, seed=field_seed)
    return study, s, tables, sim.nominal(s, tables)


def generate(case: cs.Case, s, tables, base, folder: Path) -> tuple[Path, dict, float]:
    """Write the case's file; (path, rig truth, seconds)."""
    from msens.io import Channel, Waveform, write_waveform

    start = time.perf_counter()
    world = cs.world_of(case, s, tables, base)
    tau, data, names, rig_truth = sim.record(world, tables, s, sim.Rig(shots=case.shots),
                                             case.seed)
    channels = tuple(Channel.parse(n) for n in names)
    wf = Waveform(time=tau, data=data, channels=channels,
                  metadata={"units": "V", "source": "independent simulator"})
    path = folder / f"{case.name}.npz"
    write_waveform(wf, path, overwrite=True)
    return path, rig_truth, time.perf_counter() - start


def _inside(value: float, interval) -> bool | None:
    if interval is None or interval[0] is None:
        return None
    return bool(interval[0] <= value <= interval[1])


def score(case: cs.Case, d) -> dict:
    """The case's entry: truth, what the diagnosis said, and the checks."""
    named = d.named_candidate()
    intervals = d.intervals or (named.intervals if named else {})
    out = {"case": case.name, "kind": case.kind, "truth": case.effect,
           "truth_parameters": case.parameters, "shots": case.shots, "named": d.effect,
           "parameters": d.parameters,
           "intervals": {k: list(v) for k, v in intervals.items()},
           "explained": d.explained, "misfit_before": d.misfit_before,
           "misfit_after": d.misfit_after,
           "named_at_bound": bool(named.at_bound) if named else False,
           "closest_at_bound": (None if d.closest_at_bound() is None else
                                {"effect": d.closest_at_bound().effect,
                                 "parameters": d.closest_at_bound().parameters}),
           "candidates": [{"effect": c.effect, "score": c.score, "parameters": c.parameters,
                           "at_bound": list(c.at_bound), "plausible": c.plausible,
                           "significant": c.significant} for c in d.candidates[:4]],
           "summary": d.summary(), "diagnose_s": d.elapsed_s,
           "discrepancy": d.noise.get("discrepancy"),
           "coil_inductance": (d.noise.get("coil_inductance") or {}).get("factors")}
    if case.kind == "effect":
        right = d.effect == case.effect
        checks = {}
        if right:
            for k, v in case.parameters.items():
                if k in intervals:
                    checks[k] = _inside(v, intervals[k])
                else:  # integer parameters: no interval, exact value
                    checks[k] = bool(round(d.parameters.get(k, -1)) == round(v))
        out.update(right=right, inside=checks,
                   inside_all=bool(right and all(v for k, v in checks.items()
                                                 if k in intervals)))
    elif case.kind == "null":
        out.update(right=d.effect == "none" and d.explained)
    else:
        out.update(named_confidently=d.effect != "none" and d.explained,
                   named_any=d.effect != "none")
    return out


def totals(results: list[dict]) -> dict:
    """The campaign's totals against :data:`ACCEPTANCE`."""
    eff = [r for r in results if r["kind"] == "effect"]
    nul = [r for r in results if r["kind"] == "null"]
    out_ = [r for r in results if r["kind"] == "outside"]
    right = sum(r["right"] for r in eff)
    inside = sum(r["inside_all"] for r in eff)
    t = {"effect_cases": len(eff), "right_effect": right,
         "right_effect_fraction": right / len(eff) if eff else None,
         "true_parameter_inside_interval": inside,
         "inside_fraction": inside / len(eff) if eff else None,
         "null_cases": len(nul), "nulls_none_and_explained": sum(r["right"] for r in nul),
         "outside_cases": len(out_),
         "outside_named_confidently": sum(r["named_confidently"] for r in out_),
         "outside_named_not_explained": sum(r["named_any"] and not r["named_confidently"]
                                            for r in out_),
         "named_at_bound": sum(r["named_at_bound"] for r in results),
         "diagnose_s_max": max((r["diagnose_s"] for r in results), default=None)}
    t["acceptance"] = ACCEPTANCE
    t["pass"] = {
        "right_effect": bool(eff) and t["right_effect_fraction"] >= ACCEPTANCE["right_effect"],
        "inside_interval": bool(eff) and t["inside_fraction"] >= ACCEPTANCE["inside_interval"],
        "nulls": bool(nul) and t["nulls_none_and_explained"] >= 5 * len(nul) / 6 - 1e-9,
        "outside": t["outside_named_confidently"] == 0,
        "at_bound": t["named_at_bound"] == 0}
    return t


def select(all_cases: list[cs.Case], wanted: str | None) -> list[cs.Case]:
    """Cases by name or kind (comma-separated); all when ``wanted`` is None."""
    if not wanted:
        return all_cases
    keys = wanted.split(",")
    chosen = []  # in the order asked
    for k in keys:
        chosen += [c for c in all_cases if (c.name == k or c.kind == k) and c not in chosen]
    unknown = set(keys) - {c.name for c in all_cases} - {c.kind for c in all_cases}
    if unknown:
        raise SystemExit(f"unknown cases {sorted(unknown)}; known: "
                         f"{', '.join(c.name for c in all_cases)}")
    return chosen


def run(wanted: str | None = None, seed: int = 35, out: Path = Path("out/independent-mss"),
        generate_only: bool = False, reuse: bool = True,
        field_seed: int = field.FIELD_SEED) -> dict:
    """Generate the cases, diagnose each, return ``{"cases": [...], "totals": {...}}``."""
    from msens.diagnose import diagnose
    from msens.io import read_waveform
    from msens.io.atomic import atomic_write_text

    study, s, tables, base = setup(field_seed=field_seed)
    chosen = select(cs.campaign(s, seed), wanted)
    data, results_dir = out / "data", out / "results"
    data.mkdir(parents=True, exist_ok=True)
    results_dir.mkdir(parents=True, exist_ok=True)
    results = []
    for case in chosen:
        kept = results_dir / f"{case.name}.json"
        if reuse and kept.exists() and not generate_only:
            entry = json.loads(kept.read_text())
            if entry.get("seed") == case.seed and entry.get("field_seed",
                                                              field.FIELD_SEED) == field_seed:
                results.append(entry)
                continue
        print(f"{case.name}: generating {case.shots} shot(s)", file=sys.stderr, flush=True)
        path, rig_truth, gen_s = generate(case, s, tables, base, data)
        if generate_only:
            print(json.dumps({"case": case.name, "file": str(path), "generate_s": gen_s}),
                  file=sys.stderr, flush=True)
            continue
        d = diagnose(read_waveform(path), study)
        entry = {**score(case, d), "seed": case.seed, "field_seed": field_seed,
                 "rig": rig_truth, "generate_s": gen_s,
                 "file": str(path)}
        atomic_write_text(kept, json.dumps(entry, indent=1, default=float))
        print(json.dumps({k: entry[k] for k in ("case", "named", "parameters", "intervals",
                                                "explained", "diagnose_s")}, default=float),
              file=sys.stderr, flush=True)
        results.append(entry)
    return {"cases": results, "totals": totals(results) if results else {}}


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=None, help="case names or kinds, comma-separated")
    ap.add_argument("--seed", type=int, default=35)
    ap.add_argument("--out", type=Path, default=Path("out/independent-mss"))
    ap.add_argument("--generate-only", action="store_true")
    ap.add_argument("--fresh", action="store_true", help="ignore kept results")
    ap.add_argument("--field-seed", type=int, default=field.FIELD_SEED,
                    help="seed of the field tables' perturbation (one draw for all files)")
    args = ap.parse_args(argv)
    logging.basicConfig(format="%(name)s: %(message)s")  # the diagnoses' stages on stderr
    logging.getLogger("msens").setLevel(logging.INFO)
    res = run(args.cases, args.seed, args.out, args.generate_only, reuse=not args.fresh,
              field_seed=args.field_seed)
    print(json.dumps(res, indent=1, default=float))
    return res


if __name__ == "__main__":
    main()

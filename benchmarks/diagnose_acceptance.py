"""Acceptance set of ``msens diagnose`` (issue 21): seeded hidden data, every effect of the
library, null files, effects outside the library, two effects at once. Prints JSON.

Data (all seeded; :mod:`msens.diagnose.hidden`): the model with a hidden effect at a random
plausible parameter, dressed as a measurement (unknown gain, offset and trigger delay, 1 %
noise); multi-shot files have 4 or 8 shots whose striker speeds scatter by 0.5-1 % (the rig's
jitter) besides their own trigger, offset and noise.

- *effect* cases: every library effect, on the data where it is physical: bead sensors
  (paper Table 2 bead setup), four-contact MsS (its MsS setup without the declared
  precompression) and physics MsS (``studies/paper-mss.toml``); single- and multi-shot.
  Right: the effect named first, every parameter within 10 % (integers exact).
- *null* cases: no hidden effect, single shots and jittered multi-shot files. Right: none.
- *outside* cases: effects the library does not hold (:data:`msens.diagnose.hidden.OUTSIDE`).
  Right: ``"explained": false`` or none.
- *two* cases: two hidden effects; up to three passes. Right: the stronger (the larger
  baseline misfit when alone) named first, the other second.

Run: ``python benchmarks/diagnose_acceptance.py [--quick] [--only KIND,...]`` (KIND: effect,
null, outside, two, physics; ``--only physics`` runs the physics-MsS effect and null cases
alone, e.g. in a second process; ``--cases A:B`` a slice of the effect cases). Progress goes to
stderr, one line per case.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, default_study_path, load_study
from msens.diagnose import diagnose, diagnose_passes
from msens.diagnose.effects import Context, get
from msens.diagnose.hidden import (
    OUTSIDE,
    hidden_case,
    hidden_shots,
    outside_case,
    without_precompression,
)
from msens.diagnose.objective import WaveformObjective
from msens.diagnose.predict import Predictor, baseline_state, setup_result
from msens.diagnose.workflow import baseline_dissipation
from msens.pipeline import calibrate_dissipation, output_times
from msens.synth import RigEffects

TOLERANCE = 0.10
#: Effects of bead data and of four-contact / physics MsS data.
BEAD = ("wall_dissipation", "wall_stiffness", "striker_velocity", "contact_damping_law",
        "daq_lowpass", "sensor_position", "static_precompression", "sensor_mass")
MSS4 = ("magnetic_precompression", "static_precompression", "striker_velocity",
        "wall_stiffness")
PHYSICS = ("magnet_remanence", "coil_position", "cable_capacitance")


def recovered(found: dict, truth: dict, integers: set[str]) -> bool:
    """Every true parameter within ``TOLERANCE`` (relative; integers exact; a zero truth
    within ``TOLERANCE`` of the largest true value)."""
    scale = max(abs(v) for v in truth.values())
    for k, v in truth.items():
        if k not in found:
            return False
        if k in integers:
            if round(found[k]) != round(v):
                return False
        elif abs(found[k] - v) > TOLERANCE * (abs(v) if v else scale):
            return False
    return True


def integer_names(effect: str, ctx, base) -> set[str]:
    return {p.name for p in get(effect).space(ctx, base) if p.integer}


class Bench:
    """The studies, baselines and predictors of the three kinds of data."""

    def __init__(self, physics: bool) -> None:
        table2 = without_precompression(load_study(builtin_study_path(PAPER_TABLE2)))
        self.fit = calibrate_dissipation(table2, output_times(table2))
        self.predictor = Predictor(output_times(table2))
        self.kinds = {}
        for name in ("bead", "mss"):
            ctx = Context(table2, table2.setup(name))
            self.kinds[name] = (table2, ctx, baseline_state(ctx, self.fit.gamma_c,
                                                            self.fit.gamma_w), self.fit)
        if physics:
            study = load_study(default_study_path())
            ctx = Context(study, study.setups[0])
            gc, gw = baseline_dissipation(study)
            self.physics_predictor = Predictor(output_times(study))
            self.kinds["physics"] = (study, ctx, baseline_state(ctx, gc, gw), None)

    def data(self, kind: str, seed: int, shots: int, jitter: float, effects=None,
             draw=()):
        _, ctx, base, _ = self.kinds[kind]
        predictor = self.physics_predictor if kind == "physics" else self.predictor
        if shots > 1:
            return hidden_shots(ctx, base, predictor, effects, seed=seed, shots=shots,
                                velocity_jitter=jitter, draw_effects=draw)
        return hidden_case(ctx, base, predictor, effects, seed=seed, draw_effects=draw,
                           rig=RigEffects(seed=seed, noise=0.01))

    def diagnose(self, kind: str, wf, passes: int = 1):
        study, _, _, fit = self.kinds[kind]
        t0 = time.perf_counter()
        ds = diagnose_passes(wf, study, passes=passes, fit=fit) if passes > 1 else \
            [diagnose(wf, study, fit=fit)]
        return ds, time.perf_counter() - t0

    def strength(self, kind: str, effect: str, params: dict, seed: int) -> float:
        """Baseline misfit of data holding ``effect`` alone (chi^2 per sample)."""
        _, ctx, base, _ = self.kinds[kind]
        wf, _ = hidden_case(ctx, base, self.predictor, {effect: params}, seed=seed)
        obj = WaveformObjective(wf, setup_result(ctx, base, self.predictor))
        return float(obj.rss(self.predictor.records([base])[0]).sum() / obj.n_obs.sum())


def _log(case: dict) -> None:
    print(json.dumps(case, default=float), file=sys.stderr, flush=True)


def _shots_of(i: int) -> tuple[int, float]:
    """Shots and speed jitter of the i-th case of an effect: 1, 1, 4, 8 shots."""
    return ((1, 0.0), (1, 0.0), (4, 0.005), (8, 0.01))[i % 4]


def effect_cases(bench: Bench, quick: bool, physics: bool, chain: bool,
                 part: slice = slice(None)) -> list[dict]:
    plan = [("bead", e, i) for e in BEAD for i in range(1 if quick else 4)]
    plan += [("mss", e, k) for k, e in enumerate(MSS4)]
    if not chain:
        plan = []
    if physics:
        plan += [("physics", e, i) for e in PHYSICS for i in range(1 if quick else 2)]
    # Appended last, so that the cases above keep their seeds.
    if chain:
        plan += [("bead", "tube_friction", i) for i in range(1 if quick else 4)]
    if physics:
        plan += [("physics", "tube_friction", i) for i in range(1 if quick else 2)]
    cases = []
    for n, (kind, effect, i) in list(enumerate(plan))[part]:
        seed = 1000 + 17 * n
        shots, jitter = _shots_of(i) if kind != "physics" else ((1, 0.0), (4, 0.005))[i % 2]
        wf, truth = bench.data(kind, seed, shots, jitter, draw=(effect,))
        (d,), secs = bench.diagnose(kind, wf)
        _, ctx, base, _ = bench.kinds[kind]
        right = d.effect == effect and recovered(d.parameters, truth[effect],
                                                 integer_names(effect, ctx, base))
        cases.append({"kind": "effect", "data": kind, "seed": seed, "shots": shots,
                      "effect": effect, "truth": truth[effect], "named": d.effect,
                      "fit": d.parameters, "right": right, "explained": d.explained,
                      "score": d.candidates[0].score if d.candidates else None,
                      "misfit_before": d.misfit_before, "misfit_after": d.misfit_after,
                      "seconds": secs})
        _log(cases[-1])
    return cases


def null_cases(bench: Bench, quick: bool, physics: bool, chain: bool) -> list[dict]:
    plan = [("bead", 1, 0.0), ("bead", 1, 0.0), ("bead", 1, 0.0), ("bead", 4, 0.005),
            ("bead", 8, 0.01), ("bead", 8, 0.01), ("mss", 1, 0.0), ("mss", 8, 0.01),
            ("bead", 8, 0.02), ("mss", 4, 0.01)]
    if quick:
        plan = [("bead", 1, 0.0), ("bead", 8, 0.01)]
    if not chain:
        plan = []
    if physics:
        plan += [("physics", 1, 0.0), ("physics", 4, 0.01)][:1 if quick else 2]
    cases = []
    for n, (kind, shots, jitter) in enumerate(plan):
        seed = 2000 + 13 * n
        wf, _ = bench.data(kind, seed, shots, jitter)
        (d,), secs = bench.diagnose(kind, wf)
        best = d.candidates[0] if d.candidates else None
        cases.append({"kind": "null", "data": kind, "seed": seed, "shots": shots,
                      "jitter": jitter, "named": d.effect, "right": d.effect == "none",
                      "explained": d.explained,
                      "best": best.effect if best else None,
                      "best_score": best.score if best else None,
                      "best_notes": list(best.notes) if best else [], "seconds": secs})
        _log(cases[-1])
    return cases


def outside_cases(bench: Bench, quick: bool) -> list[dict]:
    names = list(OUTSIDE)[:2] if quick else list(OUTSIDE)
    cases = []
    for n, name in enumerate(names):
        seed = 3000 + 7 * n
        _, ctx, base, _ = bench.kinds["bead"]
        shots = 8 if n == 1 else 1
        wf = outside_case(name, ctx, base, bench.predictor, seed=seed, shots=shots,
                          velocity_jitter=0.01 if shots > 1 else 0.0)
        (d,), secs = bench.diagnose("bead", wf)
        cases.append({"kind": "outside", "case": name, "what": OUTSIDE[name], "seed": seed,
                      "shots": shots, "named": d.effect, "parameters": d.parameters,
                      "explained": d.explained,
                      "right": d.effect == "none" or not d.explained,
                      "where": d.verdict.get("unexplained_where"),
                      "misfit_before": d.misfit_before, "misfit_after": d.misfit_after,
                      "seconds": secs})
        _log(cases[-1])
    return cases


PAIRS = (
    {"static_precompression": {"first_contact": 8, "contact_count": 4,
                               "precompression_force_n": 2.5},
     "wall_dissipation": {"gamma_wall_kg_per_s": 3.0}},
    {"sensor_mass": {"sensor_mass_kg": 0.7e-3},
     "daq_lowpass": {"lowpass_tau_s": 1.5e-6}},
)


def two_cases(bench: Bench, quick: bool) -> list[dict]:
    cases = []
    for n, pair in enumerate(PAIRS[:1] if quick else PAIRS):
        seed = 4000 + n
        _, ctx, base, _ = bench.kinds["bead"]
        strength = {e: bench.strength("bead", e, p, seed) for e, p in pair.items()}
        order = sorted(pair, key=lambda e: -strength[e])
        wf, truth = bench.data("bead", seed, 1, 0.0, effects=pair)
        ds, secs = bench.diagnose("bead", wf, passes=3)
        named = [d.effect for d in ds]
        last = [d for d in ds if d.effect != "none"]
        final = dict(last[-1].refit) if last and last[-1].refit else \
            ({last[-1].effect: last[-1].parameters} if last else {})
        params_ok = all(e in final and recovered(final[e], pair[e],
                                                 integer_names(e, ctx, base))
                        for e in pair)
        cases.append({"kind": "two", "truth": truth, "strength": strength,
                      "named": named, "right": named[:2] == order,
                      "parameters_within_10pct": params_ok, "final": final,
                      "explained": [d.explained for d in ds],
                      "passes": [{"effect": d.effect, "parameters": d.parameters,
                                  "misfit_after": d.misfit_after} for d in ds],
                      "seconds": secs})
        _log(cases[-1])
    return cases


def main(quick: bool = False, only: set[str] | None = None,
         part: slice = slice(None)) -> dict:
    only = only or {"effect", "null", "outside", "two", "physics"}
    physics = "physics" in only
    chain = bool(only & {"effect", "null", "outside", "two"})  # bead and four-contact data
    bench = Bench(physics)
    cases = []
    if "effect" in only or not chain:
        cases += effect_cases(bench, quick, physics, chain, part)
    if "null" in only or not chain:
        cases += null_cases(bench, quick, physics, chain)
    if "outside" in only:
        cases += outside_cases(bench, quick)
    if "two" in only:
        cases += two_cases(bench, quick)

    def tally(kind: str) -> dict:
        sel = [c for c in cases if c["kind"] == kind]
        return {"cases": len(sel), "right": sum(c["right"] for c in sel),
                "rate": (sum(c["right"] for c in sel) / len(sel)) if sel else None}

    multi = [c["seconds"] for c in cases if c.get("shots", 1) == 8]
    eff = [c for c in cases if c["kind"] == "effect"]
    return {
        "tolerance": TOLERANCE,
        "effects_covered": sorted({c["effect"] for c in eff}),
        "effect": tally("effect"), "null": tally("null"),
        "false_positives": sum(c["named"] != "none" for c in cases if c["kind"] == "null"),
        "outside": tally("outside"), "two": tally("two"),
        "max_seconds_8_shots": max(multi) if multi else None,
        "median_seconds": float(np.median([c["seconds"] for c in cases])) if cases else None,
        "cases": cases,
    }


if __name__ == "__main__":
    args = sys.argv[1:]
    only = None
    if "--only" in args:
        only = set(args[args.index("--only") + 1].split(","))
    part = slice(None)
    if "--cases" in args:  # a slice A:B of the effect cases, to share them among processes
        a, b = args[args.index("--cases") + 1].split(":")
        part = slice(int(a) if a else None, int(b) if b else None)
    print(json.dumps(main("--quick" in args, only, part), indent=1, default=float))

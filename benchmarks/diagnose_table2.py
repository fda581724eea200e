"""The paper's Table 2 diagnosed jointly (issue 21 item 5): calibrate on the bead rows only,
then predict the rod and MsS rows that were not fitted.

1. Baseline: ``studies/paper-table2.toml`` with gamma_c from paper Eq. 10 on the bead
   sensors' ARs (the study's ``[calibration.dissipation]``).
2. Diagnosis of the bead rows alone (feature mode: TOF and AR at beads 13 and 18 against the
   published means and shot-to-shot std), up to ``PASSES`` passes; only physically plausible
   effects above their significance floors can be named (:mod:`msens.diagnose`).
3. The named effects, with the parameters fitted on the bead rows, are applied to the rod and
   MsS setups (an effect that does not apply to a setup, e.g. ``sensor_mass`` on rods, is
   left out there and listed), and each row's TOF and AR are compared with the experiment,
   beside the paper's own model and msens without the effects.

Prints JSON (``rows``: per setup and sensor the measured TOF/AR, the paper's, msens's
baseline's and the improved model's values and errors) and, with ``--markdown``, the README
table. Run: ``python benchmarks/diagnose_table2.py [--markdown]``.
"""

from __future__ import annotations

import json
import sys

from msens.config.schema import PAPER_TABLE2, MssModel
from msens.config.study import builtin_study_path, load_study
from msens.diagnose import diagnose_reference
from msens.diagnose.effects import Context, get
from msens.diagnose.predict import (
    Predictor,
    baseline_state,
    feature_records,
    model_features_of,
    positions,
)
from msens.diagnose.workflow import baseline_dissipation
from msens.pipeline import calibrate_dissipation, output_times

PASSES = 2


def _features(study, setup, state, predictor) -> dict[str, tuple[float, float]]:
    """(TOF us, AR) per sensor position of a state."""
    physics = [s.model is MssModel.PHYSICS for s in setup.sensors]
    rec = predictor.records([state])[0]
    f = model_features_of(feature_records(rec, physics, predictor.t), predictor.t)
    where = positions([s.particle for s in setup.sensors])
    return {pos: (float(f.tof[j]) * 1e6, float(f.ar[j])) for j, pos in enumerate(where)}


def main() -> dict:
    study = load_study(builtin_study_path(PAPER_TABLE2))
    fit = calibrate_dissipation(study, output_times(study))
    gc, gw = baseline_dissipation(study, fit)
    passes = []
    added: list[tuple[str, dict]] = []
    for _ in range(PASSES):
        d = diagnose_reference(study, "bead", fit=fit, added=tuple(added))
        passes.append({"effect": d.effect, "parameters": d.parameters,
                       "explained": d.explained, "summary": d.summary(),
                       "misfit_before": d.misfit_before, "misfit_after": d.misfit_after,
                       "candidates": [c.to_json() for c in d.candidates]})
        if d.effect == "none":
            break
        added.append((d.effect, d.parameters))
    predictor = Predictor(output_times(study))
    rows, skipped = [], []
    for setup in study.setups:
        ctx = Context(study, setup)
        base = baseline_state(ctx, gc, gw)
        state = base
        for name, params in added:
            effect = get(name)
            if effect.applies(ctx):
                state = effect.apply(ctx, state, params)
            else:
                skipped.append({"setup": setup.name, "effect": name})
        f0 = _features(study, setup, base, predictor)
        f1 = _features(study, setup, state, predictor)
        for ref in (r for r in study.reference if r.setup == setup.name):
            t0, a0 = f0[ref.position]
            t1, a1 = f1[ref.position]
            rows.append({
                "setup": setup.name, "position": ref.position, "fitted": setup.name == "bead",
                "measured": {"tof_us": ref.tof_us, "tof_std_us": ref.tof_std_us,
                             "ar": ref.ar, "ar_std": ref.ar_std},
                "paper": {"tof_us": ref.model_tof_us, "ar": ref.model_ar,
                          "tof_error_pct": 100 * (ref.model_tof_us / ref.tof_us - 1),
                          "ar_error": ref.model_ar - ref.ar},
                "msens_baseline": {"tof_us": t0, "ar": a0,
                                   "tof_error_pct": 100 * (t0 / ref.tof_us - 1),
                                   "ar_error": a0 - ref.ar},
                "msens_improved": {"tof_us": t1, "ar": a1,
                                   "tof_error_pct": 100 * (t1 / ref.tof_us - 1),
                                   "ar_error": a1 - ref.ar}})
    return {"calibration": {"gamma_c_kg_per_s": gc, "gamma_w_kg_per_s": gw,
                            "on": "bead rows (paper Eq. 10)"},
            "passes": passes, "named": [{"effect": n, "parameters": p} for n, p in added],
            "not_applicable": skipped, "rows": rows}


def markdown(out: dict) -> str:
    """The README table: TOF error (%) and AR error per row, paper / msens / improved."""
    lines = ["| setup | sensor | fitted | TOF meas. (us) | TOF error: paper / msens / "
             "improved (%) | AR meas. | AR error: paper / msens / improved |",
             "|---|---|---|---|---|---|---|"]
    for r in out["rows"]:
        p, b, i = r["paper"], r["msens_baseline"], r["msens_improved"]
        lines.append(f"| {r['setup']} | {r['position']} | {'yes' if r['fitted'] else 'no'} | "
                     f"{r['measured']['tof_us']:.1f} ± {r['measured']['tof_std_us']:.1f} | "
                     f"{p['tof_error_pct']:+.1f} / {b['tof_error_pct']:+.1f} / "
                     f"{i['tof_error_pct']:+.1f} | "
                     f"{r['measured']['ar']:.2f} ± {r['measured']['ar_std']:.2f} | "
                     f"{p['ar_error']:+.2f} / {b['ar_error']:+.2f} / {i['ar_error']:+.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    result = main()
    print(json.dumps(result, indent=1))
    if "--markdown" in sys.argv:
        print(markdown(result))

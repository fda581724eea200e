"""synth -> compare on the main study's physics MsS data: what compare recovers (prints JSON).

For each seed, ``msens synth`` data of ``studies/paper-mss.toml`` (both coils; unknown
amplifier gain 0.5-2, offset, trigger delay and jitter) without noise (1 shot) and with 1 %
noise (5 shots) are compared with the model (``msens compare``): per coil the TOF and AR
errors (measured mean minus model), the lowest correlation and the gain error
(measured gain / true gain - 1, one convention: measured = gain x model), and the speed
error; the worst case over the seeds.

Run: ``python benchmarks/compare_mss.py [--seeds N]`` (default 20).
"""

from __future__ import annotations

import json
import sys

from msens.compare import compare
from msens.config.study import default_study_path, load_study
from msens.pipeline import run_study
from msens.synth import RigEffects, synthesize, truth_gain_key


def case(result, seed: int, noise: float, shots: int) -> dict:
    setup = result.setups[0]
    wf = synthesize(setup, RigEffects(seed=seed, noise=noise, shots=shots))
    report = compare(result, wf)
    out = {}
    for ch in report["channels"]:
        m, model = ch["measured"], ch["model"]
        truth = float(wf.metadata[truth_gain_key("mss", ch["particle"])])
        out[ch["channel"]] = {
            "tof_error_us": m["tof_us"]["mean"] - model["tof_us"],
            "ar_error": m["ar"]["mean"] - model["ar"],
            "correlation": m["correlation"]["mean"],
            "gain_error": m["gain_measured_per_model"]["mean"] / truth - 1.0}
    speed = report["speed"]
    out["speed_error"] = speed["measured_m_per_s"]["mean"] / speed["model_m_per_s"] - 1.0
    return out


def main(seeds: int = 20) -> dict:
    result = run_study(load_study(default_study_path()))
    table = {}
    for label, noise, shots in (("noise 0, 1 shot", 0.0, 1), ("noise 1 %, 5 shots", 0.01, 5)):
        cases = [case(result, s, noise, shots) for s in range(seeds)]
        chans = [k for k in cases[0] if k != "speed_error"]
        table[label] = {
            "max_abs_tof_error_us": max(abs(c[k]["tof_error_us"]) for c in cases for k in chans),
            "max_abs_ar_error": max(abs(c[k]["ar_error"]) for c in cases for k in chans),
            "min_correlation": min(c[k]["correlation"] for c in cases for k in chans),
            "max_abs_gain_error": max(abs(c[k]["gain_error"]) for c in cases for k in chans),
            "max_abs_speed_error": max(abs(c["speed_error"]) for c in cases)}
    return {"study": "paper-mss", "seeds": seeds, "worst": table}


if __name__ == "__main__":
    n = int(sys.argv[sys.argv.index("--seeds") + 1]) if "--seeds" in sys.argv else 20
    print(json.dumps(main(n), indent=1))

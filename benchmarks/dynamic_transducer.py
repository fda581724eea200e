"""Eddy-current transducer of the main study: S_c(ω), D_c(ω), Z(ω) and the read-out resonance.

Usage: ``python benchmarks/dynamic_transducer.py [study.toml]`` (default
``studies/paper-mss.toml``). The eddy-current model is the one ``msens run`` uses with
``[field] eddy_currents = true`` (mesh graded into every conducting surface, cached). Prints JSON:
per coil, for the two contacts next to the coil's bead (12–13 for coil 13, 17–18 for coil
18), |D|/|D_0| and the phase of the contact-approach sensitivity and the same for Villari (the
bead bulk), at every solved
frequency (10, 30, 100 kHz among them); the Villari sum over all contacts; Z(ω) as R(ω) and
L(ω); the read-out's resonance (frequency and peak gain) with the study's cable for R + jωL
(static) and for Z(ω); the reciprocity and power-balance checks; timings and dofs.

``--rebuild`` also builds the model again in an empty cache folder, without and with the
coil-offset profiles that diagnose reads (``dynamic_report(offsets=True)``), and prints each
build's wall time, stages and the eddy mesh's Newton iterations (``rebuild``).
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from msens.config.fieldsetup import eddy_settings, geometry_from_study
from msens.config.study import load_study
from msens.magnetics.dynamic_cache import dynamic_report
from msens.readout.electronics import peak_gain, transfer_function
from msens.readout.mss import readout
from msens.store import Store

ROOT = Path(__file__).resolve().parents[1]


def _ratio(values: np.ndarray) -> dict:
    """|v/v0| and phase (deg) per frequency of one sensitivity column."""
    r = values / values[0]
    return {"abs": np.round(np.abs(r), 4).tolist(),
            "phase_deg": np.round(np.degrees(np.angle(r)), 2).tolist()}


def _peak(circuit, impedance=None) -> dict:
    f, gain = peak_gain(circuit, impedance)
    return {"f_peak_Hz": f, "gain_peak": gain,
            "gain_dc": float(np.abs(transfer_function(circuit, [0.0])[0]))}


def rebuild(geometry, eddy) -> dict:
    """Wall time of building the eddy-current model from an empty cache (its stages' seconds
    are in the log at DEBUG: msens.magnetics.dynamic)."""
    out = {}
    for offsets in (False, True):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            rep = dynamic_report(geometry, options=eddy.options, steel=eddy.steel,
                                 store=Store.at(tmp), offsets=offsets)
            out["with_offsets" if offsets else "plain"] = {
                "seconds": round(time.perf_counter() - t0, 1),
                "bias_newton_iterations": rep.details.get("bias_newton_iterations")}
    return out


def main(path: str | None = None, rebuild_models: bool = False) -> dict:
    study = load_study(path or ROOT / "studies" / "paper-mss.toml")
    geometry = geometry_from_study(study)
    # the run's eddy-current model: its mesh graded into every conducting surface, its cache
    eddy = eddy_settings(study)
    options = eddy.options
    t0 = time.perf_counter()
    rep = dynamic_report(geometry, options=options, steel=eddy.steel)
    out: dict = {"study": str(path or "studies/paper-mss.toml"),
                 "skin_size_m": options.skin_size, "dofs": rep.details["dofs"],
                 "elements": rep.details["elements"],
                 "frequencies_Hz": rep.details["frequencies_Hz"],
                 "seconds_this_call": time.perf_counter() - t0,
                 "coils": {}}
    for p, r in rep.responses.items():
        unit = next(u for u in geometry.iter_units() if u.coil.particle == p)
        w = 2 * np.pi * np.asarray(r.frequencies)
        contacts = [p - 1, p]
        k = np.searchsorted(r.contacts, contacts)
        vil_sum = np.sum(r.villari, axis=1)
        circuit = readout(unit.coil, r.resistance_ohm, r.static_inductance_H, study.electronics)
        chk = rep.details["coils"][str(p)]
        out["coils"][str(p)] = {
            "contacts": contacts,
            "approach": {str(c): _ratio(r.approach[:, j]) for c, j in zip(contacts, k,
                                                                          strict=True)},
            "villari": {str(c): _ratio(r.villari[:, j]) for c, j in zip(contacts, k,
                                                                       strict=True)},
            "villari_sum_all_contacts": _ratio(vil_sum),
            "static": {"approach_Wb_per_m": r.approach[0, k].real.tolist(),
                       "villari_Wb_per_N": r.villari[0, k].real.tolist()},
            "R_ohm": np.round(r.impedance.real, 3).tolist(),
            "L_H": [r.static_inductance_H, *(r.impedance[1:].imag / w[1:]).tolist()],
            "readout_static_RL": _peak(circuit),
            "readout_eddy_Z": _peak(circuit, r.impedance_at),
            "capacitance_F": circuit.total_capacitance,
            "max_reciprocity_rel_error": max(chk["reciprocity_rel_error"], default=None),
            "max_power_balance_rel_error": max(chk["power_balance_rel_error"])}
    if rebuild_models:
        out["rebuild"] = rebuild(geometry, eddy)
    return out


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--rebuild"]
    print(json.dumps(main(*args[:1], rebuild_models="--rebuild" in sys.argv[1:]), indent=1))

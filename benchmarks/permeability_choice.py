"""The main study under each small-signal permeability, without and with eddy currents.

The physics MsS sees the steel's permeability for small signals about the bias point. msens
offers the differential slope of the B–H curve (default) and its reversible part
(``[field] small_signal_permeability = "reversible"``, c = 0.1 by default: see
:data:`msens.params.materials.STEEL_REVERSIBILITY`). This runs ``studies/paper-mss.toml`` four
ways, each permeability with eddy currents (the study's default) and magnetostatic
and prints, per coil, the peak DAQ voltage and its time, the peak EMF, the incremental
inductance, the read-out resonance, and (with eddy currents) the contact approach of the
coil's lower contact at 10, 30 and 100 kHz relative to static (magnitude, phase in degrees);
and the closed-form screening of a bead-size conducting sphere at 10 kHz for both
permeabilities (:func:`sphere_screening`).

Run: ``python benchmarks/permeability_choice.py [--figure PATH]`` (seconds with the caches;
the field models of the reversible variants are built and cached on first use, about 4 minutes
on 2 cores). ``--figure`` also plots coil 13's DAQ voltage of the four variants (the README's
``docs/permeability_choice.png``).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from msens import api
from msens.config.study import default_study_path
from msens.field.eddy_sphere import conducting_sphere
from msens.field.geometry import BEAD_DIAMETER
from msens.params.materials import SIGMA_1018
from msens.vocabulary import TIME_LABEL, coil_name

VARIANTS = {  # the main study computes with eddy currents; each variant says which it takes
    "differential, eddy currents (default)": {"field.eddy_currents": True},
    "reversible, eddy currents": {"field.small_signal_permeability": "reversible",
                                  "field.eddy_currents": True},
    "differential, magnetostatic": {"field.eddy_currents": False},
    "reversible, magnetostatic": {"field.small_signal_permeability": "reversible",
                                  "field.eddy_currents": False},
}


def coil_figures(coil: dict) -> dict:
    out = {"peak_voltage_V": coil["peak_voltage_V"],
           "peak_voltage_time_us": coil["peak_voltage_time_us"],
           "peak_emf_V": coil["peak_emf_V"], "inductance_H": coil["inductance_H"],
           "resonance_Hz": coil["resonance_Hz"], "quality_factor": coil["quality_factor"]}
    fr = coil.get("frequency_response")
    if fr:
        freqs = fr["frequencies_Hz"]
        out["approach_vs_static"] = {
            f"{f / 1e3:g} kHz": [fr["approach_ratio_magnitude"][freqs.index(f)][1],
                                  fr["approach_ratio_phase_deg"][freqs.index(f)][1]]
            for f in (1e4, 3e4, 1e5) if f in freqs}
    return out


def main(figure: str | None = None) -> dict:
    base = api.load(default_study_path())
    report, records = {}, {}
    for name, changes in VARIANTS.items():
        study = api.replace(base, changes) if changes else base
        result = api.run(study)
        summary = api.physics_summary(result)
        report[name] = {str(c["particle"]): coil_figures(c) for c in summary["coils"]}
        records[name] = next(r.mss for r in result.setups[0].sensors
                             if r.sensor.particle == 13)
    if figure:
        plot(records, figure)
    report["conducting sphere, moment at 10 kHz / static"] = sphere_screening()
    return report


def sphere_screening(frequency: float = 1e4) -> dict:
    """Why a lower permeability screens more: the closed-form moment of a conducting sphere
    of bead size (R = 2.38 mm, AISI 1018 conductivity) relative to its static moment, for a
    relative permeability like the reversible (90) and the differential (900) one."""
    radius = BEAD_DIAMETER / 2
    out = {}
    for mu_r in (90.0, 900.0):
        m = conducting_sphere(radius, mu_r, SIGMA_1018, frequency)[0]
        m0 = conducting_sphere(radius, mu_r, SIGMA_1018, 0.0)[0]
        out[f"mu_r {mu_r:g}"] = [abs(m / m0), float(np.degrees(np.angle(m / m0)))]
    return out


def plot(records: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 3.6))
    styles = {"differential, eddy currents (default)": ("C0", "-"),
              "reversible, eddy currents": ("C1", "-"),
              "differential, magnetostatic": ("C0", "--"),
              "reversible, magnetostatic": ("C1", "--")}
    for name, rec in records.items():
        keep = rec.t_daq <= 200e-6
        color, ls = styles[name]
        ax.plot(rec.t_daq[keep] * 1e6, rec.voltage[keep] * 1e3, color=color, ls=ls, lw=1.3,
                label=name)
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel(f"DAQ voltage, {coil_name(13)} (mV)")
    ax.set_title("Small-signal permeability of the steel and eddy currents (main study)",
                 fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, title="field model", title_fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", default=None, help="also write the figure here (.png)")
    print(json.dumps(main(parser.parse_args().figure), indent=1))

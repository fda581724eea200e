"""Magnet sweeps: one nonlinear bias solve per design, run through the executor.

Per design (a pure function of its payload, so local and Dask runs agree): mesh (cached by
content hash), bias solve, Villari potentials of the beads around the sensor, the design
coil's sensitivity by exact mesh quadrature over its winding, its incremental inductance at
the bias point, the magnetic precompression and the wave with it.

Model size: the field model holds every MsS sensor of the study (the other sensor's magnet
changes the forces near this one) but only ``bead_padding`` beads beyond the outermost
sensors (:func:`msens.design.sweep.base_geometry`); the default 4 is the smallest padding
that keeps the Villari beads (± 4) inside the model.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from msens.coil import wheeler_inductance, winding_capacitance, winding_from_coil
from msens.design.coil_sweep import coil_inductances, wave_summary
from msens.design.metrics import circuit_metrics, peak_emf
from msens.design.physics import bias_state
from msens.design.reciprocity import contact_sensitivities, region_linkage
from msens.field.geometry import SensorGeometry
from msens.study import Study


@dataclass(frozen=True)
class MagnetTask:
    """Payload of one magnet design (picklable)."""

    study: Study
    geometry: SensorGeometry
    particle: int
    mesh_dir: str | None


def evaluate_design(task: MagnetTask) -> dict:
    """Metrics of one magnet (and coil) design; raises on failure (the runner records it)."""
    g, p = task.geometry, task.particle
    unit = next(u for u in g.sensors if u.coil.particle == p)
    c = unit.coil
    state = bias_state(g, p, Path(task.mesh_dir) if task.mesh_dir else None)
    beads = region_linkage(state.solution, state.potentials, f"coil_{p}", c.turns, c.area)
    sens = contact_sensitivities(beads)[None, :]
    l_inc, _ = coil_inductances(state.solution, g, unit)
    w = winding_from_coil(c.turns, c.length, c.inner_radius, c.wire.name, c.packing_factor,
                          insulated_diameter=c.wire.insulated_diameter)
    r, l_air, cw = w.resistance(), wheeler_inductance(w), winding_capacitance(w)
    circ = circuit_metrics(np.array([r]), np.array([l_inc]), np.array([cw]),
                           task.study.electronics)
    wave = wave_summary(task.study, state.solution, g, p, state.contacts)
    emf = float(peak_emf(sens, wave["force_rate"])[0])
    return {
        "outer_radius_m": c.outer_radius, "resistance_ohm": r, "inductance_H": l_inc,
        "inductance_air_H": l_air, "winding_capacitance_F": cw,
        "resonance_Hz": float(circ["resonance_Hz"][0]),
        "quality_factor": float(circ["quality_factor"][0]),
        "bandwidth_Hz": float(circ["bandwidth_Hz"][0]),
        "noise_rms_V": float(circ["noise_rms_V"][0]),
        "sensitivity_Wb_per_N": float(np.sum(sens)), "peak_emf_V": emf,
        "snr": emf * float(circ["dc_gain"][0]) / float(circ["noise_rms_V"][0]),
        "precompression_N": wave["precompression_N"],
        "precompression_max_N": wave["precompression_max_N"],
        "wave_speed_change": wave["wave_speed_change"],
        "contacts": [int(k) for k in state.contacts],
        "dLambda_dF_Wb_per_N": [float(v) for v in sens[0]],
        "newton_iterations": state.solution.iterations,
    }


__all__ = ["MagnetTask", "evaluate_design"]

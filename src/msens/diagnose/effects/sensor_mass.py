"""``sensor_mass``: the instrumented sensor beads are heavier than the plain beads.

Parameter ``sensor_mass_kg``: the mass of each instrumented bead sensor (the particles the
bead sensors read), kg. Baseline: the plain bead's mass (the paper neglects the difference,
§4.1). An instrumented bead is two half spheres around a piezo disc with its electrodes,
wires and epoxy: a heavier particle reflects part of the incident pulse, transmits a slower,
longer pulse and changes the force it reads itself.

Physical range: 0.8 to 2.5 times the plain bead (the cut and the disc, of a density close to
steel's, cannot make it much lighter; electrodes, solder and wires add at most about a bead's
mass). Floor: 5 % of the plain bead (~20 mg for the paper's 0.45 g: a drop of epoxy).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.readout.sensors import SensorKind

NAME = "sensor_mass"
PARAM = "sensor_mass_kg"


def _applies(ctx: Context) -> bool:
    return any(s.kind is SensorKind.BEAD for s in ctx.setup.sensors)


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    m = float(ctx.study.chain.bead_mass_kg)
    return (Parameter(PARAM, 0.5 * m, 3.0 * m, log=True, plausible=(0.8 * m, 2.5 * m),
                      reason="0.8-2.5 x the plain bead: two half spheres around a piezo disc "
                      "of near-steel density, plus electrodes, wires and epoxy",
                      floor=0.05 * m, floor_reason="5 % of a bead's mass: a drop of epoxy"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: float(ctx.study.chain.bead_mass_kg)}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    mass = np.array(state.chain.mass)
    for kind, p in zip(state.kinds, state.particles, strict=True):
        if kind is SensorKind.BEAD:
            mass[p - 1] = float(params[PARAM])
    return dataclasses.replace(state, chain=dataclasses.replace(state.chain, mass=mass))


EFFECT = Effect(name=NAME, description="mass of each instrumented bead sensor (kg)",
                space=_space, baseline=_baseline, apply=_apply, applies=_applies)

"""``cable_capacitance``: the read-out cable is longer (or of another type) than the study says.

Parameter ``cable_capacitance_f``: the capacitance across each physics MsS coil's read-out
from its cable, F (RG-58 has about 100 pF/m: 30 pF is a short lead, 5 nF 50 m). With the
coil's inductance it sets the resonance of the read-out (77 kHz with 1 m of cable for the
paper's coil), which is inside the signal band: more capacitance lowers the resonance and
rings the record longer. Only the read-out changes; no new simulation is needed.
"""

from __future__ import annotations

import dataclasses

from msens.config.schema import MssModel
from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter

NAME = "cable_capacitance"
PARAM = "cable_capacitance_f"


def _applies(ctx: Context) -> bool:
    return any(s.model is MssModel.PHYSICS for s in ctx.setup.sensors)


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    c0 = float(ctx.study.electronics.cable_capacitance_f)
    return (Parameter(PARAM, 30e-12, 5e-9, log=True, plausible=(0.0, 10e-9),
                      reason="up to 100 m of RG-58 (100 pF/m)", floor=max(0.2 * c0, 20e-12),
                      floor_reason="20 % of the nominal capacitance (at least 20 pF: a "
                      "connector or a lead's worth)"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: ctx.study.electronics.cable_capacitance_f}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    c = float(params[PARAM])
    physics = tuple(None if p is None else dataclasses.replace(
        p, electronics=dataclasses.replace(p.electronics, cable_capacitance_f=c))
        for p in state.physics)
    return dataclasses.replace(state, physics=physics)


# The ringing of the read-out makes the misfit multimodal in the capacitance: a fine start
# grid (cheap: no new simulation) finds the right basin.
EFFECT = Effect(name=NAME, description="cable capacitance of the MsS read-out (F)",
                space=_space, baseline=_baseline, apply=_apply, applies=_applies,
                grid_points=48)

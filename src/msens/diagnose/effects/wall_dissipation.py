"""``wall_dissipation``: a dashpot in the last bead's contact with the wall.

Parameter ``gamma_wall_kg_per_s`` replaces the wall contact's dissipation coefficient
(paper Eq. 8, gamma_w; units of the chain's damping law, kg/s for the linear dashpot).
Baseline: the study's (calibrated) gamma_w, 0 for the paper. It lowers the reflected pulse
at every sensor by about the same factor and leaves the incident pulse untouched.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter

NAME = "wall_dissipation"
PARAM = "gamma_wall_kg_per_s"


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    # critical damping of the wall contact at a ~5 N pulse: 2 sqrt(k m), k = 1.5 A_w
    # delta^(1/2) ~ 1.2e7 N/m for a steel bead on steel, m = 0.45 g: ~150 kg/s
    return (Parameter(PARAM, 0.05, 30.0, log=True, plausible=(0.0, 150.0),
                      reason="0 to the critical damping of the wall contact (~150 kg/s)",
                      floor=0.2, floor_reason="below 0.2 kg/s the reflected pulse drops by "
                      "less than ~1 %, inside its shot-to-shot scatter"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: float(state.chain.damping[-1])}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    damping = np.array(state.chain.damping)
    damping[-1] = float(params[PARAM])
    return dataclasses.replace(state, chain=dataclasses.replace(state.chain, damping=damping))


EFFECT = Effect(name=NAME, description="dissipation in the wall contact (gamma_w, kg/s)",
                space=_space, baseline=_baseline, apply=_apply)

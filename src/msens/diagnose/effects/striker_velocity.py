"""``striker_velocity``: the striker hits at another speed than sqrt(2 g h).

Parameter ``striker_velocity_m_per_s``. Baseline: the study's striker (the paper: 7.2 mm drop,
0.376 m/s). Amplitude scales ~ v^(6/5), which the calibrated gains absorb; what remains is the
speed (V_s ~ F_m^(1/6) ~ v^(1/5)): every time of flight and the delay between the sensors.
"""

from __future__ import annotations

import dataclasses

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter

NAME = "striker_velocity"
PARAM = "striker_velocity_m_per_s"


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    v0 = float(ctx.study.striker.velocity_m_per_s)
    return (Parameter(PARAM, 0.3 * v0, 3.0 * v0, log=True),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: float(ctx.study.striker.velocity_m_per_s)}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    return dataclasses.replace(state, velocity=float(params[PARAM]))


EFFECT = Effect(name=NAME, description="striker impact speed (m/s)",
                space=_space, baseline=_baseline, apply=_apply)

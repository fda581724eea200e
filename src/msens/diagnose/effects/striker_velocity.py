"""``striker_velocity``: the striker hits at another speed than sqrt(2 g h).

Parameter ``striker_velocity_m_per_s``. Baseline: the study's striker (the paper: 7.2 mm drop,
0.376 m/s). Amplitude scales ~ v^(6/5), which the calibrated gains absorb; what remains is the
speed (V_s ~ F_m^(1/6) ~ v^(1/5)): every time of flight and the delay between the sensors.

Physical range: a dropped striker cannot hit faster than free fall from its drop height plus
the height's tolerance, sqrt(2 g (h + dh)); friction in the guide tube can only slow it, so
any lower speed is possible. Floor: the speed change that the drop-height tolerance itself
makes, v (sqrt(1 + dh / h) - 1) (3.4 % for the paper's 7.2 mm); a smaller change is within
what the rig sets. A study that gives the speed instead of a height has no free-fall limit;
its tolerance is taken as ``VELOCITY_TOLERANCE``.
"""

from __future__ import annotations

import dataclasses
import math

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.params.units import G0

NAME = "striker_velocity"
PARAM = "striker_velocity_m_per_s"
#: Tolerance of a drop height set by hand with a ruler or gauge, m.
DROP_HEIGHT_TOLERANCE_M = 0.5e-3
#: Relative tolerance of a striker speed given directly (no drop height), and the largest
#: plausible excess over it (a launcher's spread).
VELOCITY_TOLERANCE = 0.03


def limits(ctx: Context) -> tuple[float, float, str, str]:
    """(largest plausible speed m/s, floor m/s, reason, floor reason) of the study's striker."""
    v0 = float(ctx.study.striker.velocity_m_per_s)
    h = ctx.study.striker.drop_height_m
    if h is None:
        return (v0 * (1.0 + 2 * VELOCITY_TOLERANCE), v0 * VELOCITY_TOLERANCE,
                f"a given striker speed within twice its assumed {VELOCITY_TOLERANCE:.0%} "
                "tolerance", f"assumed {VELOCITY_TOLERANCE:.0%} tolerance of the speed")
    g = G0  # as the study turns the drop height into a speed
    dh = DROP_HEIGHT_TOLERANCE_M
    vmax = math.sqrt(2.0 * g * (h + dh))
    return (vmax, v0 * (math.sqrt(1.0 + dh / h) - 1.0),
            f"free fall from the drop height {h * 1e3:.2g} mm + {dh * 1e3:.2g} mm tolerance: "
            f"at most {vmax:.4g} m/s; friction can only slow the striker",
            f"speed change of the drop-height tolerance +-{dh * 1e3:.2g} mm")


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    v0 = float(ctx.study.striker.velocity_m_per_s)
    vmax, floor, why, why_floor = limits(ctx)
    return (Parameter(PARAM, 0.3 * v0, 3.0 * v0, log=True, plausible=(0.0, vmax), reason=why,
                      floor=floor, floor_reason=why_floor),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: float(ctx.study.striker.velocity_m_per_s)}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    return dataclasses.replace(state, velocity=float(params[PARAM]))


EFFECT = Effect(name=NAME, description="striker impact speed (m/s)",
                space=_space, baseline=_baseline, apply=_apply)

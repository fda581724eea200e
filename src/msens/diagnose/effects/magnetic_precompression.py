"""``magnetic_precompression``: the bias magnet pulls the beads under each coil together.

Parameter ``precompression_force_n``: a static compression (N) on the four contacts around
each MsS sensor, c_{p-2}..c_{p+1} (the contacts the four-contact model averages; paper §4.1,
its estimate 1.8 N). It replaces the setup's declared precompression. Baseline: the setup's
declared value (0 when none is declared). A precompressed stretch is faster and stiffer: the
pulse speeds up under the coil and its shape at the sensor changes.
"""

from __future__ import annotations

import dataclasses

from msens.config.assemble import precompression_forces
from msens.config.schema import PrecompressionSpec
from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.diagnose.effects.static_precompression import (
    FLOOR_N,
    FLOOR_REASON,
    PLAUSIBLE_MAX_N,
    PLAUSIBLE_REASON,
)
from msens.readout.sensors import SensorKind

NAME = "magnetic_precompression"
PARAM = "precompression_force_n"


def _mss_particles(ctx: Context) -> list[int]:
    return [s.particle for s in ctx.setup.sensors if s.kind is SensorKind.MSS]


def _applies(ctx: Context) -> bool:
    return bool(_mss_particles(ctx))


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    return (Parameter(PARAM, 0.0, 10.0, plausible=(0.0, PLAUSIBLE_MAX_N),
                      reason=PLAUSIBLE_REASON, floor=FLOOR_N, floor_reason=FLOOR_REASON),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    forces = [p.force_n for p in ctx.setup.precompression]
    return {PARAM: float(max(forces)) if forces else 0.0}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    n = state.chain.n_particles
    force = float(params[PARAM])
    specs = tuple(PrecompressionSpec(first=p - 2, last=p + 1, force_n=force)
                  for p in _mss_particles(ctx))
    static = (state.chain.static_force - precompression_forces(n, ctx.setup.precompression)
              + precompression_forces(n, specs))
    return dataclasses.replace(state,
                               chain=dataclasses.replace(state.chain, static_force=static))


EFFECT = Effect(name=NAME, description="static magnetic compression of the contacts "
                "around each MsS (N)", space=_space, baseline=_baseline, apply=_apply,
                applies=_applies)

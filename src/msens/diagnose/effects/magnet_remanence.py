"""``magnet_remanence``: the bias magnets are stronger or weaker than the study says.

Parameter ``remanence_factor``: every bias magnet's remanence over its nominal value (another
batch or grade, ageing, temperature: ceramic grades lose ~0.2 %/K). It changes the bias
state, hence both the magnets' pull on the beads (the chain's precompression: the pulse
speeds up under the coils) and every contact's sensitivity (the signal's size and shape).
Both come from field models solved at a few factors and interpolated
(:class:`msens.magnetics.variants.RemanenceFamily`; with eddy currents also the coils'
frequency responses, :class:`~msens.magnetics.variants.RemanenceResponses`), solved once per
geometry and cached.
"""

from __future__ import annotations

import dataclasses

from msens.config.schema import MssModel
from msens.diagnose import physics
from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.magnetics.variants import NODES

NAME = "magnet_remanence"
PARAM = "remanence_factor"


def _applies(ctx: Context) -> bool:
    # other remanences have field models of their own (with eddy currents their frequency
    # responses too, RemanenceResponses); contact maps carry over
    # (Transducer.reading_maps_of)
    return any(s.model is MssModel.PHYSICS for s in ctx.setup.sensors)


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    return (Parameter(PARAM, NODES[0], NODES[-1],
                      reason="the field models' span of remanences (another grade or batch, "
                      "ageing, temperature)", floor=0.03,
                      floor_reason="3 %: the remanence tolerance of one magnet grade, about "
                      "the same as 15 K of temperature change for ceramic grades"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: 1.0}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    factor = float(params[PARAM])
    before = physics.magnetic_force(state.physics)
    specs = physics.with_physics(state.physics, remanence_factor=factor)
    static = state.chain.static_force - before + physics.magnetic_force(specs)
    return dataclasses.replace(state, physics=specs,
                               chain=dataclasses.replace(state.chain, static_force=static))


EFFECT = Effect(name=NAME, description="remanence of the bias magnets (x nominal)",
                space=_space, baseline=_baseline, apply=_apply, applies=_applies)

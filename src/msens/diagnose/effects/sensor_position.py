"""``sensor_position``: a sensor sits at another particle than the study says.

Parameters ``particle_<position>`` (``particle_top``, ``particle_bottom``; ``particle_single``
for one sensor): the 1-based particle each sensor actually reads, searched exhaustively within
``SPAN`` particles of the nominal one. Baseline: the study's particles. A sensor one bead lower
sees the incident pulse ~9 us later and the reflection ~9 us earlier. Changing only the
observation, it needs no new simulation.
"""

from __future__ import annotations

import dataclasses

from msens.config.schema import MssModel
from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.readout.sensors import SensorKind

NAME = "sensor_position"
#: Largest displacement searched, particles.
SPAN = 3


def names(ctx: Context) -> list[str]:
    """Parameter name of each sensor, in the order of ``setup.sensors``."""
    sensors = ctx.setup.sensors
    if len(sensors) == 1:
        return ["particle_single"]
    order = sorted(s.particle for s in sensors)
    labels = ["top" if s.particle == order[0] else "bottom" if s.particle == order[-1]
              else f"middle_{s.particle}" for s in sensors]
    return [f"particle_{x}" for x in labels]


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    n = state.chain.n_particles
    out = []
    for name, p, kind in zip(names(ctx), state.particles, state.kinds, strict=True):
        lo, hi = (3, n - 1) if kind is SensorKind.MSS else (2, n)
        out.append(Parameter(name, max(lo, p - SPAN), min(hi, p + SPAN), integer=True,
                             reason="a particle of the chain (an MsS needs a contact on each "
                             "side)", floor=1.0, floor_reason="one particle"))
    return tuple(out)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return dict(zip(names(ctx), (float(p) for p in state.particles), strict=True))


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    particles = tuple(round(params[k]) for k in names(ctx))
    return dataclasses.replace(state, particles=particles)


def _applies(ctx: Context) -> bool:
    return not any(s.model is MssModel.PHYSICS for s in ctx.setup.sensors)


EFFECT = Effect(name=NAME, description="particle each sensor actually reads",
                space=_space, baseline=_baseline, apply=_apply, applies=_applies)

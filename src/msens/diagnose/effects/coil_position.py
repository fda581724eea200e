"""``coil_position``: a physics MsS coil sits off its nominal axial position.

Parameters ``coil_offset_m_<position>`` (``_top``, ``_bottom``; ``_single`` for one coil):
the axial offset of each physics MsS coil from where the study puts it, m (+ toward the
striker); magnets and beads stay. The coil is air, so the moved coil's sensitivities come
from the same field solution (the transducer's offset profiles,
:meth:`msens.magnetics.transducer.Transducer.shifted`; with eddy currents also the frequency
response's, :meth:`msens.magnetics.frequency_response.FrequencyResponse.shifted`); no new
simulation is needed. A coil
moved toward the striker sees the pulse earlier and weights the contacts above it more.
Bounds ±2.5 mm (the transducer tabulates ±3 mm; the default pole pieces leave ±6 mm).
"""

from __future__ import annotations

import dataclasses

from msens.config.schema import MssModel
from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter
from msens.diagnose.effects.sensor_position import names as position_names

NAME = "coil_position"
#: Largest offset searched, m.
SPAN_M = 2.5e-3


def names(ctx: Context) -> list[str]:
    """Parameter name of each physics MsS coil, in the order of ``setup.sensors``."""
    return [f"coil_offset_m_{n.removeprefix('particle_')}"
            for n, s in zip(position_names(ctx), ctx.setup.sensors, strict=True)
            if s.model is MssModel.PHYSICS]


def _applies(ctx: Context) -> bool:
    return any(s.model is MssModel.PHYSICS for s in ctx.setup.sensors)


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    return tuple(Parameter(n, -SPAN_M, SPAN_M, reason="within half a bead diameter of the "
                           "nominal position", floor=0.25e-3,
                           floor_reason="0.25 mm: a coil placed by eye on the tube")
                 for n in names(ctx))


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return dict.fromkeys(names(ctx), 0.0)


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    offsets = iter(float(params[n]) for n in names(ctx))
    physics = tuple(None if p is None else dataclasses.replace(p, offset_m=next(offsets))
                    for p in state.physics)
    return dataclasses.replace(state, physics=physics)


EFFECT = Effect(name=NAME, description="axial offset of each physics MsS coil (m)",
                space=_space, baseline=_baseline, apply=_apply, applies=_applies)

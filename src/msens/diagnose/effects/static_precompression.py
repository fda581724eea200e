"""``static_precompression``: a static compression on some run of contacts, anywhere.

Parameters ``first_contact`` (1-based contact number c_k, between particles k and k + 1),
``contact_count`` (how many consecutive contacts) and ``precompression_force_n`` (N): a force
+F on particle ``first_contact`` and -F on particle ``first_contact + contact_count``
compresses c_first..c_last by F and no other contact
(:func:`msens.config.assemble.precompression_forces`, the same forces a study's
``[[setup.precompression]]`` declares). A magnet or a clamp near a sensor does this; the
run can sit anywhere between the striker's contact and the wall's.
Baseline: no added compression (force 0). The compressed run is faster and stiffer: the pulse
arrives early below it and its shape changes where a sensor sits inside it.

The MsS form (the same force on the four contacts around every MsS coil at once) is
:mod:`msens.diagnose.effects.magnetic_precompression`, which applies these same forces. On
physics MsS data (the magnets' pull from the field model) a static compression elsewhere on
the chain is searched too, coarse to fine: each trial state there needs the MsS read-out
(~0.1-0.4 s, against milliseconds for a chain alone), so the 27 x 6 x 6 = 972 combinations
of the exhaustive grid are replaced by every second first contact, the shortest and longest
run and the 6 forces (14 x 2 x 6 = 168), then the contacts within two of the best of them
with every count and force (<= 5 x 6 x 6 = 180; count and force trade off along a ridge, so
no count is skipped there, and a run of three contacts can look best as one contact at its
end): about 350 states and the refinement.

Why every second contact and every force in the coarse stage: the chi^2 is sharp in the
run's place and has several basins. One contact away from the true first contact a run's
chi^2 drop falls to less than half, three away to almost nothing, and a run at the other
end of the chain can reach a quarter of it. A coarse stage must therefore try a first
contact next to the true one, with a force near the true one: with every third contact and
three forces over the searched decades (0.05, 1.2 and 30 N) it tried nothing like a 0.5 N
run near the striker and picked another basin (the independent campaign in the
validation pages).
"""

from __future__ import annotations

import dataclasses

from msens.config.assemble import precompression_forces
from msens.config.schema import MssModel, PrecompressionSpec
from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter

NAME = "static_precompression"
FIRST, COUNT, FORCE = "first_contact", "contact_count", "precompression_force_n"
#: Longest run searched, contacts: a bias magnet's pole pieces span about four (design.md
#: §5); a clamp or a magnet beside the tube reaches a few more.
MAX_COUNT = 6
#: Physical range of the force, N, and why.
PLAUSIBLE_MAX_N = 20.0
PLAUSIBLE_REASON = ("0 to 20 N: a magnet or clamp on the tube (the paper estimates 1.8 N); "
                    "20 N is over twice the ~8 N pulse, which would then be a linear wave")
#: Practical-significance floor of the force, N, and why.
FLOOR_N = 0.15
FLOOR_REASON = ("0.15 N: the weight of the chain (29 beads: 0.13 N) already compresses the "
                "lowest contacts that much")


def specs(params) -> tuple[PrecompressionSpec, ...]:
    """The run of compressed contacts that ``params`` describe, as a study would declare it."""
    first = round(params[FIRST])
    return (PrecompressionSpec(first=first, last=first + round(params[COUNT]) - 1,
                               force_n=float(params[FORCE])),)


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    n = state.chain.n_particles
    return (Parameter(FIRST, 2, n - 1, integer=True, reason="a contact below the striker's "
                      "and above the wall's", floor=0.0),
            Parameter(COUNT, 1, MAX_COUNT, integer=True,
                      reason=f"1 to {MAX_COUNT} contacts (a magnet or clamp)"),
            Parameter(FORCE, 0.05, 30.0, log=True, plausible=(0.0, PLAUSIBLE_MAX_N),
                      reason=PLAUSIBLE_REASON, floor=FLOOR_N, floor_reason=FLOOR_REASON))


#: Strides of the coarse stage on physics MsS data (module docstring): every second first
#: contact, the shortest and longest run.
STRIDES = {FIRST: 2, COUNT: MAX_COUNT}


def _strides(ctx: Context) -> dict[str, int]:
    # a physics MsS's read-out makes each state costly: coarse to fine there
    # (count and force trade off along a ridge: the fine stage takes every count)
    return (dict(STRIDES)
            if any(s.model is MssModel.PHYSICS for s in ctx.setup.sensors) else {})


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {FIRST: None, COUNT: None, FORCE: 0.0}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    n = state.chain.n_particles
    first = round(params[FIRST])
    count = min(round(params[COUNT]), n - first)  # the run ends above the wall contact
    added = precompression_forces(n, specs({**params, COUNT: count}))
    static = state.chain.static_force + added
    return dataclasses.replace(state,
                               chain=dataclasses.replace(state.chain, static_force=static))


EFFECT = Effect(name=NAME, description="static compression of a run of contacts "
                "(first contact, count, N)", space=_space, baseline=_baseline, apply=_apply,
                strides=_strides, grid_points=6)

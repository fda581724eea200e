"""``contact_damping_law``: Hertz–Kuwabara–Kono dissipation in place of the linear dashpot.

Parameter ``gamma_hkk_kg_per_s_m05``: the coefficient gamma of F_d = gamma delta^(1/2)
d(delta)/dt (Kuwabara & Kono, Jpn. J. Appl. Phys. 26 (1987) 1230), kg/(s m^(1/2)), on every
bead-bead contact. The wall contact's coefficient is scaled by the same factor
gamma / gamma_c (it stays 0 when gamma_w = 0). Baseline: the linear dashpot (the parameter has
no baseline value). The viscoelastic law damps strong contacts more and weak ones less than
the linear dashpot, which changes the attenuation along the chain and the pulse tails.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from msens.chain.model import DampingLaw
from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter

NAME = "contact_damping_law"
PARAM = "gamma_hkk_kg_per_s_m05"


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    # a linear gamma_c of 1-5 kg/s at the ~1 um approach of a 5-10 N pulse is ~1e3-5e3
    return (Parameter(PARAM, 50.0, 5e4, log=True,
                      reason="the range of a linear gamma_c of 0.05-50 kg/s at the ~1 um "
                      "approach of the pulse; a law change has no baseline value to floor"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: None}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    gamma = float(params[PARAM])
    old = np.array(state.chain.damping)
    gc = float(np.max(old[:-1])) if old.size > 1 else 0.0
    damping = np.full(old.shape, gamma)
    damping[-1] = old[-1] * gamma / gc if gc > 0 else 0.0
    chain = dataclasses.replace(state.chain, damping=damping,
                                damping_law=DampingLaw.HERTZ_KUWABARA_KONO)
    return dataclasses.replace(state, chain=chain)


def _applies(ctx: Context) -> bool:
    return ctx.study.chain.damping is not DampingLaw.HERTZ_KUWABARA_KONO


EFFECT = Effect(name=NAME, description="Hertz-Kuwabara-Kono contact dissipation "
                "(kg/(s m^0.5)) instead of the linear dashpot", space=_space,
                baseline=_baseline, apply=_apply, applies=_applies)

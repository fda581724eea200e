"""``tube_friction``: viscous drag of each bead on the wall of the tube that guides the chain.

Parameter ``tube_drag_n_s_per_m``: the drag coefficient c of every particle (force -c v,
v relative to the fixed tube; :attr:`msens.chain.model.Chain.drag`), N s/m = kg/s. Baseline:
the study's chain (no drag). The striker slides in the same tube after the impact and is
included. Drag takes momentum out of the pulse as it travels: the incident and reflected
amplitudes fall by about exp(-c t / m) with the travel time t, and the pulse slows slightly.

Physical range, from lubrication of the band where a bead of radius R comes closest to a
tube of radial clearance h: Couette drag c ~ mu 2 pi R w / h over a band of width
w ~ 2 sqrt(2 R h). For R = 2.38 mm and h = 10 um (a slightly oversized tube) that is
c ~ 0.66 mu s: 1.2e-5 kg/s in air (mu = 1.8e-5 Pa s), ~0.07 kg/s for a light oil film
(0.1 Pa s), ~0.7 kg/s for grease (~1 Pa s, the stickiest film a rig would have). Plausible:
0 to three times the grease estimate of the study's bead (a tighter clearance or a bead
rubbing on one side). Floor: the drag that lowers a pulse by 1 % over 300 us of travel,
c = 0.01 m / 300 us (0.015 kg/s for the paper's 0.45 g bead), about the shot-to-shot scatter
of the amplitudes.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from msens.diagnose.effects.base import Context, Effect, ModelState, Parameter

NAME = "tube_friction"
PARAM = "tube_drag_n_s_per_m"
#: Radial clearance (m) and film viscosity (Pa s) of the stickiest plausible tube: grease.
CLEARANCE_M = 10e-6
GREASE_VISCOSITY_PA_S = 1.0
#: Travel time of the floor's 1 % amplitude loss, s (impact to the lower sensor and back).
FLOOR_TRAVEL_S = 300e-6


def couette_drag(viscosity: float, radius: float, clearance: float) -> float:
    """Lubrication drag coefficient of a sphere in a tube, c = mu 2 pi R w / h, N s/m.

    Parameters
    ----------
    viscosity : float
        Film viscosity mu, Pa s.
    radius : float
        Sphere radius R, m.
    clearance : float
        Radial clearance h, m; the film band has width w = 2 sqrt(2 R h).

    Returns
    -------
    float
    """
    width = 2.0 * np.sqrt(2.0 * radius * clearance)
    return float(viscosity * 2.0 * np.pi * radius * width / clearance)


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    chain = ctx.study.chain
    upper = 3.0 * couette_drag(GREASE_VISCOSITY_PA_S, 0.5 * chain.bead_diameter_m, CLEARANCE_M)
    floor = 0.01 * float(chain.bead_mass_kg) / FLOOR_TRAVEL_S
    return (Parameter(PARAM, 1e-3, 2.0 * upper, log=True, plausible=(0.0, upper),
                      reason=f"0 to {upper:.2g} kg/s: three times the Couette drag of a grease "
                      "film (1 Pa s) in a 10 um clearance around the bead",
                      floor=floor, floor_reason="the drag that lowers a pulse by 1 % over "
                      "300 us of travel, about the amplitudes' shot-to-shot scatter"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: float(np.mean(state.chain.drag))}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    drag = np.full(state.chain.n_particles, float(params[PARAM]))
    return dataclasses.replace(state, chain=dataclasses.replace(state.chain, drag=drag))


EFFECT = Effect(name=NAME, description="viscous drag of each bead on the tube (N s/m)",
                space=_space, baseline=_baseline, apply=_apply)

"""``daq_lowpass``: the acquisition low-passes the sensor signal (first order).

Parameter ``lowpass_tau_s``: time constant (s) of a causal first-order low-pass applied to
each model record (e.g. an RC input, or a coil's L/R with a resistive load; cut-off
1 / (2 pi tau)). Baseline: no filter. It delays every pulse by ~tau (absorbed by the time
offset), rounds the peaks and stretches the falling edges, equally at every sensor.
"""

from __future__ import annotations

import dataclasses

from msens.diagnose.effects.base import Context, Effect, FirstOrderLowpass, ModelState, Parameter

NAME = "daq_lowpass"
PARAM = "lowpass_tau_s"


def _space(ctx: Context, state: ModelState) -> tuple[Parameter, ...]:
    dt = 1.0 / float(ctx.study.simulation.sample_rate_hz)
    return (Parameter(PARAM, 0.05e-6, 20e-6, log=True, plausible=(0.0, 50e-6),
                      reason="a DAQ or amplifier band above 3 kHz (the pulses last ~20 us)",
                      floor=dt, floor_reason="one sample interval: a shorter time constant "
                      "is not resolved by the sampling"),)


def _baseline(ctx: Context, state: ModelState) -> dict[str, float | None]:
    return {PARAM: 0.0}


def _apply(ctx: Context, state: ModelState, params) -> ModelState:
    return dataclasses.replace(state,
                               post=(*state.post, FirstOrderLowpass(float(params[PARAM]))))


EFFECT = Effect(name=NAME, description="first-order low-pass of the acquisition (s)",
                space=_space, baseline=_baseline, apply=_apply)

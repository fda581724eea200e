"""Synthetic data with a hidden effect: the test bench of the diagnosis (issue 7 item 4).

:func:`hidden_case` draws an effect's parameter at random (seeded) within a plausible range,
simulates the baseline model *with* the effect, and dresses the records as a measurement
(:func:`msens.synth.synthesize`: unknown gain and trigger delay, offset, noise). The channels
keep the study's nominal labels (a displaced sensor is still called ``bead@13``). The truth is
returned to the caller, never written where the diagnosis could read it.

Plausible ranges (paper setup: 0.376 m/s striker, steel wall, gamma_c ~ 2.2 kg/s):

- ``wall_dissipation``: gamma_w uniform in [1, 8] kg/s;
- ``wall_stiffness``: E_w log-uniform in [20, 120] GPa (polymer composites to brass);
- ``striker_velocity``: nominal x (1 +- u), u uniform in [0.1, 0.3] (drop height off by
  20-70 %);
- ``magnetic_precompression``: uniform in [0.5, 3] N (paper's estimate 1.8 N);
- ``contact_damping_law``: gamma_HKK log-uniform in [1000, 4000] kg/(s m^0.5) (the linear
  gamma_c ~ 2.2 kg/s at a ~1.2 um approach);
- ``daq_lowpass``: tau log-uniform in [0.5, 3] us (cut-off 53-320 kHz);
- ``sensor_position``: one sensor (random) displaced by 1 or 2 particles (random sign);
- ``magnet_remanence``: nominal x (1 +- u), u uniform in [0.1, 0.4] (another grade or batch);
- ``coil_position``: one physics MsS coil (random) off by 0.5-2 mm (random sign);
- ``cable_capacitance``: log-uniform in [0.3, 3] nF (3-30 m of RG-58).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from msens.diagnose.effects import Context, ModelState, get
from msens.diagnose.effects.coil_position import names as coil_names
from msens.diagnose.effects.sensor_position import names as position_names
from msens.diagnose.predict import Predictor, setup_result
from msens.io.waveform import Waveform
from msens.study import Study
from msens.synth import RigEffects, synthesize


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def draw(effect: str, ctx: Context, base: ModelState, rng: np.random.Generator) -> dict:
    """A random plausible parameter set of ``effect`` (see the module docstring)."""
    if effect == "wall_dissipation":
        return {"gamma_wall_kg_per_s": float(rng.uniform(1.0, 8.0))}
    if effect == "wall_stiffness":
        return {"wall_youngs_modulus_pa": _log_uniform(rng, 20e9, 120e9)}
    if effect == "striker_velocity":
        sign = rng.choice([-1.0, 1.0])
        return {"striker_velocity_m_per_s":
                float(base.velocity * (1.0 + sign * rng.uniform(0.1, 0.3)))}
    if effect == "magnetic_precompression":
        return {"precompression_force_n": float(rng.uniform(0.5, 3.0))}
    if effect == "contact_damping_law":
        return {"gamma_hkk_kg_per_s_m05": _log_uniform(rng, 1000.0, 4000.0)}
    if effect == "daq_lowpass":
        return {"lowpass_tau_s": _log_uniform(rng, 0.5e-6, 3e-6)}
    if effect == "magnet_remanence":
        return {"remanence_factor": float(1.0 + rng.choice([-1.0, 1.0])
                                          * rng.uniform(0.1, 0.4))}
    if effect == "coil_position":
        params = dict.fromkeys(coil_names(ctx), 0.0)
        key = str(rng.choice(sorted(params)))
        params[key] = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.5e-3, 2e-3))
        return params
    if effect == "cable_capacitance":
        return {"cable_capacitance_f": _log_uniform(rng, 0.3e-9, 3e-9)}
    if effect == "sensor_position":
        params = dict(zip(position_names(ctx), (int(p) for p in base.particles), strict=True))
        space = {p.name: p for p in get(effect).space(ctx, base)}
        key = str(rng.choice(sorted(params)))
        step = int(rng.choice([-2, -1, 1, 2]))
        moved = int(np.clip(params[key] + step, space[key].lower, space[key].upper))
        if moved == params[key] or moved in params.values():
            moved = params[key] - step  # stay in the chain and apart from the other sensor
        params[key] = moved
        return params
    raise ValueError(f"no plausible range defined for effect {effect!r}")


def hidden_case(ctx: Context, base: ModelState, predictor: Predictor,
                effects: Mapping[str, Mapping[str, float]] | None = None, *, seed: int = 0,
                draw_effects: tuple[str, ...] = (), rig: RigEffects | None = None
                ) -> tuple[Waveform, dict[str, dict]]:
    """Synthetic measurement of ``base`` with hidden effects.

    Parameters
    ----------
    ctx : Context
    base : ModelState
        The baseline (the model the diagnosis starts from).
    predictor : Predictor
    effects : mapping, optional
        Effects with given parameters, applied in order.
    seed : int
        Seeds both the parameter draw and the rig (gain, delay, noise).
    draw_effects : tuple of str
        Effects whose parameters are drawn at random (after ``effects``).
    rig : RigEffects, optional
        Acquisition effects; default ``RigEffects(seed=seed)`` (1 % noise, one shot).

    Returns
    -------
    waveform : Waveform
    truth : dict
        Effect name -> parameters actually used.
    """
    rng = np.random.default_rng(seed)
    truth = {k: dict(v) for k, v in (effects or {}).items()}
    for name in draw_effects:
        truth[name] = draw(name, ctx, base, rng)
    state = base
    for name, params in truth.items():
        state = get(name).apply(ctx, state, params)
    rig = rig if rig is not None else RigEffects(seed=seed)
    return synthesize(setup_result(ctx, state, predictor), rig), truth


def parameters_recovered(found: Mapping[str, float], truth: Mapping[str, float],
                         tolerance: float) -> bool:
    """Whether every true parameter is recovered within ``tolerance`` (relative); a
    parameter whose truth is 0 (e.g. the offset of a coil that did not move) within
    ``tolerance`` of the largest true value instead."""
    scale = max((abs(v) for v in truth.values()), default=0.0)
    return all(k in found and abs(found[k] - v) <= tolerance * (abs(v) if v else scale)
               for k, v in truth.items())


def without_precompression(study: Study) -> Study:
    """The study with every setup's declared precompression removed (the baseline of
    ``magnetic_precompression``)."""
    setups = tuple(dataclasses.replace(s, precompression=()) for s in study.setups)
    return dataclasses.replace(study, setups=setups)

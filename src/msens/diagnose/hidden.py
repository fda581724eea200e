"""Synthetic data with a hidden effect: the test bench of the diagnosis.

:func:`hidden_case` draws an effect's parameter at random (seeded) within a plausible range,
simulates the baseline model *with* the effect, and dresses the records as a measurement
(:func:`msens.synth.synthesize`: unknown gain and trigger delay, offset, noise). The channels
keep the study's nominal labels (a displaced sensor is still called ``bead@13``). The truth is
returned to the caller, never written where the diagnosis could read it.

Plausible ranges (paper setup: 0.376 m/s striker, steel wall, gamma_c ~ 2.2 kg/s):

- ``wall_dissipation``: gamma_w uniform in [1, 8] kg/s;
- ``wall_stiffness``: E_w log-uniform in [20, 120] GPa (polymer composites to brass);
- ``striker_velocity``: nominal x (1 - u), u uniform in [0.1, 0.3] (friction in the guide;
  a faster striker than free fall is not physical);
- ``magnetic_precompression``: uniform in [0.5, 3] N (paper's estimate 1.8 N);
- ``contact_damping_law``: gamma_HKK log-uniform in [1000, 4000] kg/(s m^0.5) (the linear
  gamma_c ~ 2.2 kg/s at a ~1.2 um approach);
- ``daq_lowpass``: tau log-uniform in [0.5, 3] us (cut-off 53-320 kHz);
- ``sensor_position``: one sensor (random) displaced by 1 or 2 particles (random sign);
- ``magnet_remanence``: nominal x (1 +- u), u uniform in [0.1, 0.4] (another grade or batch);
- ``coil_position``: one physics MsS coil (random) off by 0.5-2 mm (random sign);
- ``cable_capacitance``: log-uniform in [0.3, 3] nF (3-30 m of RG-58);
- ``static_precompression``: a run of 2-5 contacts starting anywhere from c_3 to c_24,
  force uniform in [0.5, 3] N;
- ``sensor_mass``: the bead mass x uniform in [1.15, 1.8];
- ``tube_friction``: drag log-uniform in [0.05, 0.5] N s/m (a light oil film to grease).

:func:`hidden_shots` makes a multi-shot file whose shots differ in striker speed (the
rig's shot-to-shot jitter) besides noise and trigger; :func:`outside_case` makes data with an
effect that the library does not hold (:data:`OUTSIDE`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import signal

from msens.config.study import Study
from msens.diagnose.effects import Context, ModelState, get
from msens.diagnose.effects.coil_position import names as coil_names
from msens.diagnose.effects.sensor_position import names as position_names
from msens.diagnose.predict import Predictor, setup_result
from msens.io.waveform import Channel, Waveform
from msens.mechanics.hertz import hertz_sphere_flat, hertz_sphere_sphere
from msens.synth import RigEffects, synthesize, truth_gain_key


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def draw(effect: str, ctx: Context, base: ModelState, rng: np.random.Generator) -> dict:
    """A random plausible parameter set of ``effect`` (see the module docstring)."""
    if effect == "wall_dissipation":
        return {"gamma_wall_kg_per_s": float(rng.uniform(1.0, 8.0))}
    if effect == "wall_stiffness":
        return {"wall_youngs_modulus_pa": _log_uniform(rng, 20e9, 120e9)}
    if effect == "striker_velocity":
        return {"striker_velocity_m_per_s":
                float(base.velocity * (1.0 - rng.uniform(0.1, 0.3)))}
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
    if effect == "static_precompression":
        return {"first_contact": int(rng.integers(3, 25)), "contact_count": int(rng.integers(2, 6)),
                "precompression_force_n": float(rng.uniform(0.5, 3.0))}
    if effect == "sensor_mass":
        return {"sensor_mass_kg": float(ctx.study.chain.bead_mass_kg * rng.uniform(1.15, 1.8))}
    if effect == "tube_friction":
        return {"tube_drag_n_s_per_m": _log_uniform(rng, 0.05, 0.5)}
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


def _with_effects(ctx: Context, base: ModelState, effects: Mapping | None,
                  draw_effects: Sequence[str], rng: np.random.Generator
                  ) -> tuple[dict, ModelState]:
    """The given ``effects`` plus one random draw of each of ``draw_effects``, applied to
    ``base``: (effect name -> parameters, the resulting state)."""
    truth = {k: dict(v) for k, v in (effects or {}).items()}
    for name in draw_effects:
        truth[name] = draw(name, ctx, base, rng)
    state = base
    for name, params in truth.items():
        state = get(name).apply(ctx, state, params)
    return truth, state


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
    truth, state = _with_effects(ctx, base, effects, draw_effects, rng)
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


# ------------------------------------------------------------------ shot ensembles

def hidden_shots(ctx: Context, base: ModelState, predictor: Predictor,
                 effects: Mapping[str, Mapping[str, float]] | None = None, *, seed: int = 0,
                 shots: int = 8, velocity_jitter: float = 0.01, noise: float = 0.01,
                 draw_effects: tuple[str, ...] = (),
                 state_of=None) -> tuple[Waveform, dict[str, dict]]:
    """A multi-shot file whose shots differ as a rig's do: each shot its own striker speed
    (nominal x (1 + e), e normal with std ``velocity_jitter``), trigger delay, offset and
    noise; one gain per channel for all shots (the same sensor and amplifier).

    Parameters
    ----------
    ctx, base, predictor, effects, seed, draw_effects
        As in :func:`hidden_case`.
    shots : int
    velocity_jitter : float
        Relative std of the striker speed between shots.
    noise : float
        White noise std as a fraction of each channel's peak.
    state_of : callable (ModelState) -> (ModelState, Predictor), optional
        A change outside the library applied last (:func:`outside_case`).

    Returns
    -------
    waveform : Waveform
        Channels ``<kind>@<particle>#k``, k = 1..shots, on a common time axis.
    truth : dict
        Effect name -> parameters; ``"velocities"`` -> the shots' striker speeds.
    """
    rng = np.random.default_rng(seed)
    truth, state = _with_effects(ctx, base, effects, draw_effects, rng)
    sim = predictor
    if state_of is not None:
        state, sim = state_of(state)
    speeds = state.velocity * (1.0 + velocity_jitter * rng.standard_normal(shots))
    waves = []
    for k in range(shots):
        shot = dataclasses.replace(state, velocity=float(speeds[k]))
        waves.append(synthesize(setup_result(ctx, shot, sim),
                                RigEffects(seed=seed * 1000 + k, noise=noise)))
    # one gain per channel: every shot rescaled to the first shot's gains
    n = min(w.time.size for w in waves)
    first = waves[0]
    columns, channels = [], []
    for k, w in enumerate(waves):
        for j, ch in enumerate(w.channels):
            key = truth_gain_key(ch.kind, ch.particle)
            scale = float(first.metadata[key]) / float(w.metadata[key])
            columns.append(w.data[:n, j] * scale)
            channels.append(Channel(ch.kind, ch.particle, k + 1))
    truth["velocities"] = {f"shot_{k + 1}": float(v) for k, v in enumerate(speeds)}
    meta = {"units": "V", "synthetic": "true", "shots": str(shots)}
    return Waveform(time=first.time[:n], data=np.column_stack(columns),
                    channels=tuple(channels), metadata=meta), truth


# ------------------------------------------------------------------ outside the library

#: Effects the library does not hold, for checking that the diagnosis says so.
OUTSIDE = {
    "foreign_bead": "a glass bead (2500 kg/m^3, 63 GPa) in place of bead 8",
    "heavy_striker": "a striker twice a bead's mass",
    "small_wall_bead": "a 3.97 mm bead (5/32 in) in place of the last bead on the wall",
    "worn_contact": "contact c_9 at 0.3 of its Hertz stiffness (a flattened, yielded contact)",
    "clipping": "the amplifiers clip at 70 % of each channel's peak",
    "ac_coupling": "AC-coupled amplifiers: a first-order high-pass at 1 kHz on every channel",
}


@dataclass(frozen=True)
class _Clip:
    """Saturation of each record at ``level`` times its own peak."""

    level: float

    def __call__(self, records: np.ndarray, dt: float) -> np.ndarray:
        peak = np.max(np.abs(records), axis=-1, keepdims=True)
        return np.clip(records, -self.level * peak, self.level * peak)


@dataclass(frozen=True)
class _HighPass:
    """AC coupling of each record (a charge amplifier's finite time constant): the
    first-order high-pass H(s) = s / (s + w_c), discretised by the bilinear transform."""

    corner_hz: float

    def __call__(self, records: np.ndarray, dt: float) -> np.ndarray:
        b, a = signal.bilinear([1.0, 0.0], [1.0, 2.0 * np.pi * self.corner_hz], fs=1.0 / dt)
        return signal.lfilter(b, a, records, axis=-1)


def outside_state(name: str, ctx: Context, state: ModelState, predictor: Predictor
                  ) -> tuple[ModelState, Predictor]:
    """The model state (and the predictor to run it) with the outside effect ``name``."""
    c = ctx.study.chain
    chain = state.chain
    mass, stiff = np.array(chain.mass), np.array(chain.stiffness)
    r = 0.5 * c.bead_diameter_m
    if name == "foreign_bead":
        k = 7  # bead 8 (0-based 7), between the striker and the first sensor
        mass[k] *= 2500.0 / (c.bead_mass_kg / (np.pi / 6 * c.bead_diameter_m**3))
        a = hertz_sphere_sphere(c.youngs_modulus_pa, c.poisson_ratio, r, 63e9, 0.24, r)
        stiff[k - 1] = stiff[k] = a
    elif name == "heavy_striker":
        mass[0] *= 2.0
    elif name == "small_wall_bead":
        rs = 0.5 * 3.97e-3
        mass[-1] *= (rs / r) ** 3
        stiff[-2] = hertz_sphere_sphere(c.youngs_modulus_pa, c.poisson_ratio, r,
                                        c.youngs_modulus_pa, c.poisson_ratio, rs)
        stiff[-1] = hertz_sphere_flat(c.youngs_modulus_pa, c.poisson_ratio, rs,
                                      c.wall.youngs_modulus_pa, c.wall.poisson_ratio)
    elif name == "worn_contact":
        stiff[8] *= 0.3
    elif name == "clipping":
        return dataclasses.replace(state, post=(*state.post, _Clip(0.7))), predictor
    elif name == "ac_coupling":
        return dataclasses.replace(state, post=(*state.post, _HighPass(1e3))), predictor
    else:
        raise ValueError(f"unknown outside effect {name!r}; known: {', '.join(OUTSIDE)}")
    chain = dataclasses.replace(chain, mass=mass, stiffness=stiff)
    return dataclasses.replace(state, chain=chain), predictor


def outside_case(name: str, ctx: Context, base: ModelState, predictor: Predictor, *,
                 seed: int = 0, shots: int = 1, velocity_jitter: float = 0.0,
                 noise: float = 0.01) -> Waveform:
    """Synthetic data of ``base`` with the outside effect ``name`` (:data:`OUTSIDE`)."""
    if shots > 1:
        return hidden_shots(ctx, base, predictor, seed=seed, shots=shots,
                            velocity_jitter=velocity_jitter, noise=noise,
                            state_of=lambda s: outside_state(name, ctx, s, predictor))[0]
    state, sim = outside_state(name, ctx, base, predictor)
    return synthesize(setup_result(ctx, state, sim), RigEffects(seed=seed, noise=noise))

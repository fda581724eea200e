"""The effect library: names, bounds, baselines, and that each effect changes what it says."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from msens.chain.model import DampingLaw
from msens.config.assemble import build_chain
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, default_study_path, load_study
from msens.diagnose.effects import NAMES, Context, FirstOrderLowpass, get, registry
from msens.diagnose.predict import _sim_key, baseline_state

#: Effects of a physics MsS (its field model): tried on the main study.
PHYSICS_EFFECTS = ("magnet_remanence", "coil_position", "cable_capacitance")


@pytest.fixture(scope="module")
def study():
    return load_study(builtin_study_path(PAPER_TABLE2))


@pytest.fixture(scope="module")
def mss_study():
    return load_study(default_study_path())


def _base(study, setup):
    ctx = Context(study, study.setup(setup))
    return ctx, baseline_state(ctx, 4.8, 0.0)


def _fingerprint(state):
    return (_sim_key(state), state.particles, state.post, state.physics)


def test_registry_holds_the_fixed_names_in_order():
    assert tuple(registry())[:len(NAMES)] == NAMES


@pytest.mark.parametrize("name", NAMES)
def test_every_effect_has_bounded_si_parameters_and_a_baseline(study, mss_study, name):
    ctx, base = (_base(mss_study, mss_study.setups[0].name) if name in PHYSICS_EFFECTS
                 else _base(study, "bead" if name == "sensor_mass" else "mss"))
    effect = get(name)
    assert effect.applies(ctx)
    space = effect.space(ctx, base)
    assert space and all(p.lower < p.upper for p in space)
    baseline = effect.baseline(ctx, base)
    assert set(baseline) == {p.name for p in space}
    # every parameter states its physical range and why; the search reaches it or beyond
    for p in space:
        lo, hi = p.physical
        assert p.reason and lo <= hi and p.floor >= 0.0
        assert p.floor == 0.0 or p.floor_reason
        if baseline[p.name] is not None:
            assert p.is_plausible(baseline[p.name]), p.name  # the study itself is physical
    # applying any in-bounds value gives a new, valid state (chains validate themselves)
    # a point off the middle (a symmetric range has its baseline there)
    mid = {p.name: p.lower ** 0.7 * p.upper ** 0.3 if p.log else p.lower + 0.3 * (p.upper -
                                                                                    p.lower)
           for p in space}
    if all(p.integer for p in space):
        mid = {p.name: int(p.upper) for p in space}  # the middle would be the nominal
    state = effect.apply(ctx, base, mid)
    assert _fingerprint(state) != _fingerprint(base)
    # at its baseline values an effect changes nothing (where the baseline is exactly a value
    # of the parameters: not a zero-width filter, nor forces rebuilt in floating point)
    if name in ("wall_dissipation", "wall_stiffness", "striker_velocity", "coil_position",
                "cable_capacitance"):
        same = effect.apply(ctx, base, baseline)
        assert _fingerprint(same) == _fingerprint(base)


@pytest.mark.parametrize("name", PHYSICS_EFFECTS)
def test_physics_effects_apply_to_physics_mss_only(study, mss_study, name):
    assert get(name).applies(Context(mss_study, mss_study.setups[0]))
    assert not get(name).applies(Context(study, study.setup("mss")))
    assert not get("sensor_position").applies(Context(mss_study, mss_study.setups[0]))


def test_unknown_effect_is_an_input_error():
    from msens.errors import InputError

    with pytest.raises(InputError, match="known: wall_dissipation"):
        get("gravity_waves")


@pytest.mark.parametrize("name", ["wall_dissipation", "wall_stiffness", "striker_velocity",
                                  "magnetic_precompression", "sensor_position"])
def test_baseline_value_reproduces_the_baseline(study, name):
    ctx, base = _base(study, "mss")
    effect = get(name)
    again = effect.apply(ctx, base, effect.baseline(ctx, base))
    for field in ("mass", "stiffness", "damping", "static_force"):
        np.testing.assert_allclose(getattr(again.chain, field), getattr(base.chain, field),
                                   rtol=1e-14, atol=1e-15)
    assert again.velocity == base.velocity and again.particles == base.particles


def test_wall_stiffness_is_the_hertz_sphere_flat_prefactor(study):
    ctx, base = _base(study, "bead")
    soft = get("wall_stiffness").apply(ctx, base, {"wall_youngs_modulus_pa": 70e9})
    wall = dataclasses.replace(study.chain.wall, youngs_modulus_pa=70e9)
    ref = build_chain(dataclasses.replace(study, chain=dataclasses.replace(study.chain,
                                                                          wall=wall)),
                      ctx.setup, gamma_contact=4.8, gamma_wall=0.0)
    np.testing.assert_allclose(soft.chain.stiffness, ref.stiffness, rtol=1e-14)
    assert soft.chain.stiffness[-1] < base.chain.stiffness[-1]


def test_magnetic_precompression_matches_the_declared_four_contacts(study):
    # the paper's mss setup declares 1.8 N on contacts 11-14 and 16-19; the effect put on a
    # setup without it must give the same static forces
    mss = study.setup("mss")
    bare = dataclasses.replace(mss, precompression=())
    ctx = Context(study, bare)
    base = baseline_state(ctx, 4.8, 0.0)
    state = get("magnetic_precompression").apply(ctx, base, {"precompression_force_n": 1.8})
    ref = build_chain(study, mss, gamma_contact=4.8, gamma_wall=0.0)
    np.testing.assert_allclose(state.chain.static_force, ref.static_force, atol=1e-15)
    assert get("magnetic_precompression").baseline(Context(study, mss), base) == \
        {"precompression_force_n": 1.8}
    assert not get("magnetic_precompression").applies(Context(study, study.setup("bead")))


def test_contact_damping_law_switches_to_kuwabara_kono(study):
    ctx, base = _base(study, "bead")
    state = get("contact_damping_law").apply(ctx, base, {"gamma_hkk_kg_per_s_m05": 2000.0})
    assert state.chain.damping_law is DampingLaw.HERTZ_KUWABARA_KONO
    np.testing.assert_array_equal(state.chain.damping[:-1], 2000.0)
    assert state.chain.damping[-1] == 0.0  # gamma_w = 0 stays 0


def test_sensor_position_moves_only_the_observation(study):
    ctx, base = _base(study, "bead")
    state = get("sensor_position").apply(ctx, base, {"particle_top": 14, "particle_bottom": 18})
    assert state.particles == (14, 18) and state.chain is base.chain


def test_first_order_lowpass_step_response_is_exact():
    dt, tau = 1e-7, 1.3e-6
    y = FirstOrderLowpass(tau)(np.ones(200), dt)
    k = np.arange(200)
    # zero-order-hold discretisation: exact at the end of each hold interval
    np.testing.assert_allclose(y, 1.0 - np.exp(-(k + 1) * dt / tau), rtol=1e-12)


def test_first_order_lowpass_gain_at_the_corner_frequency():
    dt, tau = 1e-7, 2e-6
    f = 1.0 / (2 * np.pi * tau)
    t = np.arange(200000) * dt
    y = FirstOrderLowpass(tau)(np.sin(2 * np.pi * f * t), dt)
    amp = np.max(np.abs(y[-20000:]))
    assert amp == pytest.approx(1 / np.sqrt(2), rel=5e-3)  # -3 dB, continuous-time value

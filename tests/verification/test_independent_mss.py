"""The independent physics-MsS simulator (benchmarks/independent) against ``msens run``, and
the hidden-effect campaign of ``msens diagnose`` on its data (issue 35, item 5).

The fast tests are the evidence that the simulator is an independent implementation of the
same physics: without the field perturbation it reproduces msens's run of the undisturbed
main study's magnetostatic variant (bead velocity peaks, both coils' DAQ voltage), and with
the 1 % perturbation it stays as close as a 1 % field model error allows. The slow tests
diagnose four of the campaign's files (a null, two effects, one outside the library); the
campaign test (about 50 min: ~1-2 min of ``msens diagnose`` per file) asserts the issue's
acceptance numbers on all 36.
"""

from __future__ import annotations

import numpy as np
import pytest
from benchmarks.independent import field, sim


@pytest.fixture(scope="module")
def runs():
    from msens.chain.integrate import simulate
    from msens.diagnose.effects import Context
    from msens.diagnose.predict import baseline_state
    from msens.pipeline import run_study

    study = field.main_study()  # magnetostatic, as the simulator
    s = sim.study_numbers(study)
    t = np.arange(round(s.t_end * s.sample_rate) + 1) / s.sample_rate
    result = run_study(study).setups[0]
    msens_v = np.array([r.mss.voltage for r in result.sensors])
    base = baseline_state(Context(study, study.setups[0]), study.chain.gamma_contact,
                          study.chain.gamma_wall)
    msens_vel = simulate(base.chain, base.velocity, t, states=True).velocity
    exact = field.read_tables(study)
    ours = {}
    for acc in (0.0, field.FIELD_ACCURACY):
        tables = field.perturbed(exact, acc)
        v, h = sim.coil_voltages(sim.nominal(s, tables), tables, t)
        ours[acc] = (v, h.velocity)
    return t, msens_v, msens_vel, ours, s


def _peak_time(t: np.ndarray, x: np.ndarray) -> float:
    """Time of the first maximum of ``x`` (parabola through the peak sample), s."""
    k = int(np.argmax(x))
    a, b, c = x[k - 1], x[k], x[k + 1]
    return float(t[k] + 0.5 * (a - c) / (a - 2 * b + c) * (t[1] - t[0]))


@pytest.mark.parametrize("accuracy", [0.0, field.FIELD_ACCURACY])
def test_bead_velocity_tofs(runs, accuracy):
    """Time of the velocity peak of the coils' beads (13, 18) from impact within 0.5 % of
    msens's chain (DOP853 at rtol 1e-10 against msens's fixed-step kernel; with the field
    perturbation the magnets' pull differs by 1 %, which moves the static preload and so
    the wave speed by a fraction of that)."""
    t, _, msens_vel, ours, s = runs
    vel = ours[accuracy][1]
    for p in s.particles:
        mine, theirs = _peak_time(t, vel[:, p - 1]), _peak_time(t, msens_vel[:, p - 1])
        assert abs(mine / theirs - 1) < 0.005, (p, mine, theirs)
        if accuracy == 0.0:  # the same physics: far closer than the tolerance
            assert abs(mine / theirs - 1) < 1e-3, (p, mine, theirs)


def test_coil_voltage_exact_tables(runs):
    """With msens's own field tables the two implementations agree on each coil's DAQ
    voltage to 0.2 % of its peak at every sample (measured 8e-5 and 3e-5): integrator,
    equilibrium, contact-map interpolation (linear on a 5 nm grid) and the read-out's
    discretisation (first-order hold of the flux) differ, the physics does not."""
    _, msens_v, _, ours, _ = runs
    v = ours[0.0][0]
    for j in range(2):
        peak = np.max(np.abs(msens_v[j]))
        assert np.max(np.abs(v[j] - msens_v[j])) < 2e-3 * peak, j


def test_coil_voltage_perturbed_tables(runs):
    """With the field tables perturbed by 1 % (per contact and quantity) each coil's
    largest excursion stays within 3 % of msens's and the whole record within 8 % of the
    peak: the per-contact errors of 1 % do not average out where contacts of opposite
    sign cancel (coil 13's negative lobe moves by ~5 %), which is the model-form error the
    diagnosis must tolerate. The perturbation must show (> 0.5 % of the peak somewhere)."""
    _, msens_v, _, ours, _ = runs
    v = ours[field.FIELD_ACCURACY][0]
    for j in range(2):
        peak = np.max(np.abs(msens_v[j]))
        assert abs(np.max(np.abs(v[j])) / peak - 1) < 0.03, j
        dev = np.max(np.abs(v[j] - msens_v[j]))
        assert 0.005 * peak < dev < 0.08 * peak, (j, dev / peak)


def test_rig_record_is_the_run_read_at_the_trigger(runs):
    """The rig's record (what the campaign diagnoses) is the same voltage read from the
    trigger on: with no noise, offset, jitter or speed spread, unit gains and exact tables
    it equals msens's run at the record's instants (impact = trigger - delay) to 0.2 % of
    the peak at every sample. (The read-out once
    started at the first recorded instant, after the impact: the coil's resonance then
    rang through the whole record at 5-10 % of the peak.)"""
    t, msens_v, _, _, s = runs
    tables = field.read_tables(field.main_study())
    rig = sim.Rig(noise=0.0, gain=(1.0, 1.0), offset=0.0, jitter=0.0, speed_spread=0.0)
    tau, data, names, truth = sim.record(sim.nominal(s, tables), tables, s, rig, seed=5)
    delay = truth["trigger_delays_s"][0]
    for j in range(2):
        peak = np.max(np.abs(msens_v[j]))
        expected = np.interp(tau + delay, t, msens_v[j], left=0.0)
        assert np.max(np.abs(data[:, j] - expected)) < 2e-3 * peak, names[j]


#: Files of the campaign: one of each kind the acceptance counts; the 0.5 N run on c3-c4
#: that the static compression's coarse search once missed for a run at c6 or c27; and the
#: sensor resonance, which a wall 8 % softer imitates within the field model's errors of
#: the wall's 5 % floor (named before the floor was weighed under the final interval)
#: (their diagnosis: 50-160 s each, two at a time on the 2 cores).
CASES = ("null-1", "striker_velocity-1", "magnetic_precompression-1", "outside-brass_bead",
         "static_precompression-1", "outside-sensor_resonance")


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_independent_case(tmp_path, case):
    """One file of the independent simulator's campaign, diagnosed as ``msens diagnose``
    does: a null is ``none`` and explained; an effect is named with the true parameter
    inside its interval and not at a bound; an effect outside the library is not named
    with confidence."""
    from benchmarks.independent_mss import run

    r = run(case, out=tmp_path, reuse=False)["cases"][0]
    assert not r["named_at_bound"], r
    if r["kind"] == "null":
        assert r["right"], r["summary"]
    elif r["kind"] == "effect":
        assert r["right"] and r["inside_all"], (r["truth_parameters"], r["parameters"],
                                                r["intervals"])
    else:
        assert not r["named_confidently"], r["summary"]


@pytest.mark.campaign
def test_independent_campaign(tmp_path):
    """The issue's acceptance on the independent simulator's set (36 files: 24 effect
    cases over the 11 library effects that apply to the physics MsS, 6 nulls with 1-8
    shots, 6 outside the library)."""
    from benchmarks.independent_mss import run

    res = run(out=tmp_path, reuse=False)
    t = res["totals"]
    assert t["effect_cases"] >= 24 and t["null_cases"] >= 6 and t["outside_cases"] >= 5
    assert t["right_effect_fraction"] >= 0.90, t
    assert t["inside_fraction"] >= 0.80, t
    assert t["nulls_none_and_explained"] >= 5, t
    assert t["outside_named_confidently"] == 0, t
    assert t["named_at_bound"] == 0, t

"""The field model's accuracy in the likelihood: record modes and their profiled amplitudes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from msens.config.study import default_study_path, load_study
from msens.diagnose import physics
from msens.diagnose.effects import Context
from msens.diagnose.field_modes import FIELD_ACCURACY, PULL_DRAWS, field_draws, record_modes
from msens.diagnose.objective import ModeBasis, WaveformObjective, _fit_many
from msens.diagnose.predict import Predictor, baseline_state
from msens.diagnose.verdict import verdict
from msens.diagnose.where import window_residuals
from msens.diagnose.workflow import baseline_dissipation
from msens.pipeline import output_times
from msens.synth import RigEffects, synthesize


def _profiled(w, y, m, basis):
    """One model signal's profile: (g, b, chi2, a)."""
    g, b, chi2, a = _fit_many(w, y, m[None], basis)
    return g[0], b[0], chi2[0], None if a is None else a[0]


def test_profiled_modes_are_the_low_rank_covariance():
    """Profiling k mode amplitudes with a unit Gaussian prior gives the generalised least
    squares chi^2 against the covariance diag(1/w) + u^T u (gain and offset fitted)."""
    rng = np.random.default_rng(4)
    n, k = 150, 4
    x = np.linspace(0.0, 1.0, n)
    m = np.sin(7 * x) * np.exp(-3 * x)
    u = 0.05 * rng.normal(size=(k, n))
    w = 1.0 / rng.uniform(0.5, 2.0, n) / 0.01**2
    y = 1.3 * m + 0.2 + rng.normal(size=k) @ u + rng.normal(size=n) / np.sqrt(w)
    basis = ModeBasis.of(u, w, y)
    np.testing.assert_allclose(basis.u.T @ basis.u, u.T @ u, atol=1e-12)  # compressed
    g, b, chi, a = _profiled(w, y, m, basis)
    cov = np.diag(1.0 / w) + u.T @ u
    ci = np.linalg.inv(cov)
    design = np.column_stack([m, np.ones(n)])
    theta = np.linalg.solve(design.T @ ci @ design, design.T @ ci @ y)
    r = y - design @ theta
    assert g == pytest.approx(theta[0], rel=1e-9)
    assert b == pytest.approx(theta[1], rel=1e-9)
    assert chi == pytest.approx(float(r @ ci @ r), rel=1e-9)
    # the profiled shift is the conditional mean of the modes' sum given the residual
    np.testing.assert_allclose(a @ basis.u, u.T @ (u @ ci @ r), rtol=1e-7, atol=1e-12)
    # a negative gain is refused: the model column is dropped
    g2, _, chi2, _ = _profiled(w, -y, m, ModeBasis.of(u, w, -y))
    assert g2 == 0.0 and chi2 > chi


def test_profiled_in_a_batch_is_profiled_one_by_one():
    """The batched profile (the alignment's whole-sample comparison) gives each model
    signal's chi^2 as the one-by-one profile does, with and without modes, a refused
    negative gain included."""
    rng = np.random.default_rng(5)
    n, k = 120, 3
    x = np.linspace(0.0, 1.0, n)
    shapes = np.array([np.sin(7 * (x - d)) * np.exp(-3 * x) for d in np.linspace(-0.05, 0.05, 7)])
    ms = np.vstack([shapes, -shapes[:2]])  # the last two want a negative gain
    u = 0.05 * rng.normal(size=(k, n))
    w = 1.0 / rng.uniform(0.5, 2.0, n) / 0.01**2
    y = 1.3 * shapes[3] + 0.2 + rng.normal(size=k) @ u + rng.normal(size=n) / np.sqrt(w)
    basis = ModeBasis.of(u, w, y)
    one = [_profiled(w, y, m, basis) for m in ms]
    g, b, chi2, a = _fit_many(w, y, ms, basis)
    for got, want in zip((g, b, chi2, a), zip(*one, strict=True), strict=True):
        np.testing.assert_allclose(got, np.array(want), rtol=1e-9, atol=1e-12)
    assert g[-1] == 0.0 and g[-2] == 0.0  # the refused case is exercised
    # without modes: the weighted gain-and-offset fit
    design = [np.column_stack([m, np.ones(n)]) for m in shapes]
    fits = [np.linalg.lstsq(a * np.sqrt(w)[:, None], y * np.sqrt(w), rcond=None)[0]
            for a in design]
    plain = [float(w @ (y - a @ f) ** 2) for a, f in zip(design, fits, strict=True)]
    g, b, chi2, a = _fit_many(w, y, shapes, None)
    assert a is None
    np.testing.assert_allclose(chi2, plain, rtol=1e-9)
    np.testing.assert_allclose(g, [f[0] for f in fits], rtol=1e-9)
    # one data set per signal (the channels of one alignment) as each alone
    ws, ys = np.vstack([w, 2 * w]), np.vstack([y, -y + 0.1])
    rows = _fit_many(ws, ys, shapes[:2], None)
    for i in range(2):
        alone = _fit_many(ws[i], ys[i], shapes[i:i + 1], None)
        for got, want in zip(rows[:3], alone[:3], strict=True):
            assert got[i] == pytest.approx(want[0], rel=1e-12, abs=1e-15)


def md_particle(state, j):
    return state.particles[j]


@pytest.fixture(scope="module")
def modes(mss):
    _, base, predictor, _, _ = mss
    return record_modes(base, predictor)


def test_modes_of_the_main_study(mss, modes):
    """The contact modes are the contacts' own contributions: they add up to the record
    (the read-out is linear in the sensitivities); the circuit's and the pull's modes are
    there, and each is of the field model's accuracy. With eddy currents (the main study)
    the coil's impedance Z(ω) is one mode in place of R and L."""
    ctx, base, _, _, records0 = mss
    assert len(modes) == len(ctx.setup.sensors)
    circuit = {"Z", "C_winding"} if ctx.study.field.eddy_currents else {"R", "L", "C_winding"}
    for j, md in enumerate(modes):
        assert circuit <= set(md.names)
        assert not ({"R", "L", "Z"} - circuit) & set(md.names)
        assert sum(n.startswith("pull@") for n in md.names) >= 20
        assert sum(n.startswith("pull-nonlinear#") for n in md.names) == PULL_DRAWS
        mapped = base.physics[j].model.transducers[md_particle(base, j)].approach_map
        assert sum(n.startswith("map@") for n in md.names) == len(mapped.contacts)
        contact = [i for i, n in enumerate(md.names) if n.startswith(("villari@", "approach@"))]
        total = md.records[contact].sum(axis=0) / FIELD_ACCURACY
        peak = np.max(np.abs(records0[j]))
        assert np.max(np.abs(total - records0[j])) < 1e-5 * peak
        # a mode is a 1 % change of one quantity: below the record (a 1 % change of one
        # bead's pull moves the pulse's timing and reaches a few per cent), above zero
        sizes = np.max(np.abs(md.records), axis=1)
        assert sizes.max() < 0.1 * peak and sizes.max() > 1e-3 * peak



def test_modes_span_a_joint_pull_error(mss, modes):
    """Every bead's pull off by its own 1 % draw (another seed than the modes'): near the
    lightly loaded contacts 10 and 20 the records move by several per cent of their peak,
    much of it not linear in the errors. Against a noise of 0.3 % of the peak the draws'
    nonlinear remainders cut what the linear modes leave by 4x or more, to chi^2 per
    sample < 0.1 (measured: 0.17 -> 0.016 on coil 13 for this draw; 1.6 -> 0.011 for the
    independent simulator's)."""
    _, base, predictor, _, records0 = mss
    magnets = np.asarray(physics.magnetic_force(base.physics))
    e = np.random.default_rng(123).standard_normal(magnets.size)
    chain = dataclasses.replace(base.chain, static_force=base.chain.static_force
                                + FIELD_ACCURACY * e * magnets)
    moved = predictor.records([dataclasses.replace(base, chain=chain)])[0]
    for j, md in enumerate(modes):
        peak = np.max(np.abs(records0[j]))
        assert np.max(np.abs(moved[j] - records0[j])) > 0.01 * peak
        w = np.full(moved.shape[1], 1.0 / (0.003 * peak) ** 2)
        chis = {}
        for label in ("linear", "all"):
            keep = np.array([label == "all" or not n.startswith("pull-nonlinear")
                             for n in md.names])
            basis = ModeBasis.of(md.records[keep], w, moved[j])
            chis[label] = _profiled(w, moved[j], records0[j], basis)[2] / moved.shape[1]
        assert chis["all"] < 0.1 and chis["all"] < 0.25 * chis["linear"], chis


def test_a_model_off_by_field_model_errors_is_explained(mss, modes):
    """8 shots at 1 % noise of the undisturbed model. The model's record moved by a random
    combination of its field-model modes (each quantity off by one standard deviation, as a
    second field solver would be): against the noise and the diagonal model variance alone
    it is far from explained; with the modes profiled its chi^2 exceeds that of the exact
    model by a few per mode (their prior), and the verdict says explained."""
    _, _, _, result, records0 = mss
    rng = np.random.default_rng(11)
    off = records0 + np.array([rng.choice([-1.0, 1.0], len(md.names)) @ md.records
                               for md in modes])
    wf = synthesize(result, RigEffects(noise=0.01, seed=3, shots=8))
    chis = {}
    for with_modes in (False, True):
        obj = WaveformObjective(wf, result, np.zeros(8, int))
        obj.add_model_uncertainty(records0, modes if with_modes else None)
        n = float(obj.n_obs.sum())
        exact, moved = float(obj.rss(records0).sum()), float(obj.rss(off).sum())
        chis[with_modes] = (exact / n, moved / n)
        v = verdict(moved, n, window_residuals(obj, off, off, result), obj.ensemble.dof)
        assert v["explained"] is with_modes
    assert chis[False][1] > 5 * chis[False][0]
    # with the modes the moved model costs about its prior, one per mode (each amplitude is
    # one standard deviation), plus what collinear modes do not recover: a few per mode
    k = sum(len(md.names) for md in modes)
    assert chis[True][1] - chis[True][0] < 3 * k / n


def test_field_draws_are_the_modes_drawn_jointly(mss, modes):
    """Joint draws of the field model's errors: none at zero accuracy; at a small one
    about linear in it (same seed: twice the accuracy, twice the change, to 10 %: 3-5 %
    measured at 1e-4, 12-32 % at 1e-3, the pull's nonlinearity near the light contacts);
    at 1 % their mean square per sample is the modes' summed variance (the map modes and
    the pull's nonlinear ones aside) within the scatter of 16 draws."""
    _, base, predictor, _, records = mss
    zero = field_draws(base, predictor, draws=2, accuracy=0.0)
    assert zero.shape == (2, 2, predictor.t.size)
    assert np.abs(zero).max() < 1e-12 * np.abs(records).max()
    a = field_draws(base, predictor, draws=2, accuracy=1e-4)
    b = field_draws(base, predictor, draws=2, accuracy=2e-4)
    assert np.abs(b - 2 * a).max() < 0.1 * np.abs(b).max()
    draws = field_draws(base, predictor)
    for j, md in enumerate(modes):
        linear = [not n.startswith(("map@", "pull-nonlinear")) for n in md.names]
        expected = float(np.sum(md.records[np.array(linear)] ** 2))
        got = float(np.mean(np.sum(draws[:, j] ** 2, axis=1)))
        assert 0.5 < got / expected < 2.0


@pytest.mark.slow
def test_modes_with_eddy_currents(tmp_path):
    """With eddy currents the contact modes go through the frequency-domain read-out (the
    coil's S_c(ω), D_c(ω) scaled per contact): they still add up to the record exactly; the
    coil's impedance replaces R and L as a mode (slow: 101 modes by FFT, ~15 s)."""
    study = load_study(default_study_path())  # eddy currents: the main study's default
    assert study.field.eddy_currents
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    predictor = Predictor(output_times(study))
    records = predictor.records([base])[0]
    for j, md in enumerate(record_modes(base, predictor)):
        assert "Z" in md.names and "R" not in md.names and "L" not in md.names
        contact = [i for i, n in enumerate(md.names) if n.startswith(("villari@", "approach@"))]
        total = md.records[contact].sum(axis=0) / FIELD_ACCURACY
        assert np.max(np.abs(total - records[j])) < 1e-9 * np.max(np.abs(records[j]))

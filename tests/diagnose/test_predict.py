"""The batched predictor: records from the sensors' contacts only equal those observed on
all contact forces, for shared and separate simulations and any batch split."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from msens.chain import simulate_batch
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, load_study
from msens.diagnose import predict
from msens.diagnose.effects import Context, FirstOrderLowpass
from msens.diagnose.predict import Predictor, baseline_state
from msens.readout.sensors import observe, read_contacts

T = np.linspace(0.0, 3e-4, 3001)  # 10 MHz, the incident pulse past both sensors


@pytest.fixture(scope="module")
def states():
    study = load_study(builtin_study_path(PAPER_TABLE2))
    bead = baseline_state(Context(study, study.setup("bead")), 4.8, 0.0)
    mss = baseline_state(Context(study, study.setup("mss")), 2.5, 1.0)
    return [
        bead,
        # the same simulation read elsewhere and filtered: shares bead's run
        dataclasses.replace(bead, particles=(9, 22), post=(FirstOrderLowpass(1e-6),)),
        mss,
        dataclasses.replace(bead, velocity=0.9 * bead.velocity),
    ]


def _expected(state) -> np.ndarray:
    # Observed on all contact forces of the state's own run.
    force = simulate_batch([state.chain], [state.velocity], T).force[0]
    out = np.array([observe(k, force, p) for k, p in zip(state.kinds, state.particles,
                                                         strict=True)])
    for op in state.post:
        out = op(out, float(T[1] - T[0]))
    return out


@pytest.mark.parametrize("batch_bytes", [predict.BATCH_BYTES, 1])
def test_records_from_sensor_contacts_equal_records_from_all(states, batch_bytes, monkeypatch):
    # batch_bytes = 1: every run a call of its own (the split must not change a value).
    monkeypatch.setattr(predict, "BATCH_BYTES", batch_bytes)
    predictor = Predictor(T)
    got = predictor.records(states)
    assert predictor.simulations == 3  # states 0 and 1 share a run
    for s, g in zip(states, got, strict=True):
        np.testing.assert_array_equal(g, _expected(s))


def test_batches_are_bounded_by_their_output_memory(states, monkeypatch):
    # Room for 5 contact columns of one run: bead's 4 fit, the union with mss's 4 others
    # does not, so mss and the slower-striker bead run go in calls of their own.
    calls = []

    def spy(chains, v, t, **kw):
        calls.append((len(chains), kw["contacts"].tolist()))
        return simulate_batch(chains, v, t, **kw)

    monkeypatch.setattr(predict, "simulate_batch", spy)
    monkeypatch.setattr(predict, "BATCH_BYTES", 5 * 16 * T.size)
    Predictor(T).records([states[0], states[2], states[3]])
    mss = read_contacts(zip(states[2].kinds, states[2].particles, strict=True), 30).tolist()
    assert calls == [(1, [11, 12, 16, 17]), (1, mss), (1, [11, 12, 16, 17])]


def test_a_coil_is_read_once_per_run_and_spec(mss, monkeypatch):
    """States that differ only in one coil's offset share their chain run and the other
    coil's read-out: each coil spec is read once per run, and every record is what a state
    read alone gives."""
    from msens.diagnose import physics
    from msens.diagnose.effects import get as get_effect

    ctx, base, predictor, _, _ = mss
    effect = get_effect("coil_position")
    names = [p.name for p in effect.space(ctx, base)]
    grid = [(a, b) for a in (-1e-3, 0.0, 1e-3) for b in (-1e-3, 0.0, 1e-3)]
    states = [effect.apply(ctx, base, dict(zip(names, g, strict=True))) for g in grid]
    calls = []
    real = physics.signals
    monkeypatch.setattr(physics, "signals", lambda *a, **k: calls.append(1) or real(*a, **k))
    together = predictor.records(states)
    assert len(calls) == 6  # three offsets of each of the two coils
    alone = np.array([predictor.records([s])[0] for s in states[::4]])
    np.testing.assert_array_equal(together[::4], alone)

"""Tests of the sensor observation operators (msens.readout.sensors)."""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.readout.sensors import (
    SensorKind,
    bead_sensor,
    contact_mean,
    dynamic_force,
    mss_four_contact,
    mss_four_contact_rate,
    observe,
    read_contacts,
    rod_sensor,
    sensor_contacts,
    time_derivative,
    time_integral,
)

N = 30


def _labelled_force(nt=5, runs=None):
    """force[..., j, k] = 1000 k + j + 7 (k contact index, j time index), distinct per contact."""
    j = np.arange(nt)[:, None]
    k = np.arange(N)[None, :]
    f = 1000.0 * k + j + 7.0
    return f if runs is None else np.broadcast_to(f, (runs, nt, N)) * np.arange(1, runs + 1)[
        :, None, None]


def test_contacts_match_paper_numbering():
    # Paper §4.2: bead/rod at 13 -> c12, c13; MsS at 13 -> c11..c14 (1-based c_i -> index i-1).
    np.testing.assert_array_equal(sensor_contacts(SensorKind.BEAD, 13, N), [11, 12])
    np.testing.assert_array_equal(sensor_contacts(SensorKind.ROD, 18, N), [16, 17])
    np.testing.assert_array_equal(sensor_contacts(SensorKind.MSS, 13, N), [10, 11, 12, 13])
    # The last bead's lower contact is the wall (index n-1).
    np.testing.assert_array_equal(sensor_contacts(SensorKind.BEAD, N, N), [N - 2, N - 1])


@pytest.mark.parametrize(("kind", "particle"), [("bead", 1), ("bead", N + 1), ("mss", 2),
                                                 ("mss", N), ("rod", 0), ("bead", 2.5)])
def test_sensor_outside_chain_raises(kind, particle):
    with pytest.raises(InputError, match="outside the chain"):
        sensor_contacts(SensorKind(kind), particle, N)


def test_total_and_dynamic_means():
    f = _labelled_force()
    total = bead_sensor(f, 13, dynamic=False)
    np.testing.assert_allclose(total, 1000 * 11.5 + np.arange(5) + 7.0)
    np.testing.assert_allclose(bead_sensor(f, 13), np.arange(5.0))  # minus the t=0 sample
    np.testing.assert_allclose(rod_sensor(f, 13), bead_sensor(f, 13))
    np.testing.assert_allclose(mss_four_contact(f, 13, dynamic=False),
                               1000 * 11.5 + np.arange(5) + 7.0)  # mean of 10..13 is 11.5
    # An explicit static force is subtracted instead of the first sample.
    static = np.full(N, 7.0) + 1000.0 * np.arange(N)
    np.testing.assert_allclose(mss_four_contact(f, 13, static=static), np.arange(5.0))


def test_batched_shapes_and_values_match_single_runs():
    fb = _labelled_force(nt=6, runs=3)
    for kind in ("bead", "rod", "mss"):
        out = observe(kind, fb, 13)
        assert out.shape == (3, 6)
        for r in range(3):
            np.testing.assert_allclose(out[r], observe(kind, fb[r], 13))
    assert dynamic_force(fb).shape == (3, 6, N)
    np.testing.assert_allclose(dynamic_force(fb)[:, 0, :], 0.0)
    assert contact_mean(fb, [0, 1]).shape == (3, 6)


def test_read_contacts_is_the_sorted_union_of_the_sensors():
    np.testing.assert_array_equal(read_contacts([("bead", 13), ("bead", 18)], N),
                                  [11, 12, 16, 17])
    np.testing.assert_array_equal(read_contacts([("mss", 13), (SensorKind.ROD, 13)], N),
                                  [10, 11, 12, 13])
    with pytest.raises(InputError, match="outside the chain"):
        read_contacts([("bead", 13), ("bead", 31)], N)


@pytest.mark.parametrize("kind", ["bead", "rod", "mss"])
def test_observe_on_some_contacts_equals_observe_on_all(kind):
    fb = _labelled_force(nt=6, runs=3)
    some = np.array([17, 16, 9, 10, 11, 12, 13])  # any order, more than the sensor reads
    np.testing.assert_array_equal(observe(kind, fb[..., some], 12, contacts=some),
                                  observe(kind, fb, 12))


def test_observe_without_the_sensors_contacts_raises():
    some = np.array([11, 12, 16])
    with pytest.raises(InputError, match=r"must include the contacts \[16, 17\]"):
        observe("bead", _labelled_force()[..., some], 18, contacts=some)
    with pytest.raises(InputError, match="one per column"):
        observe("bead", _labelled_force()[..., some[:2]], 13, contacts=some)


def test_bad_force_shape_raises():
    with pytest.raises(InputError, match=r"\(\.\.\., nt, n\)"):
        bead_sensor(np.zeros(10), 3)


def test_time_derivative_second_order():
    # d/dt sin(w t) on a uniform grid: np.gradient (edge_order=2) is O(dt^2) everywhere.
    w = 2 * np.pi * 5e3
    errs, dts = [], []
    for nt in (101, 201, 401, 801):
        t = np.linspace(0.0, 4e-4, nt)
        d = time_derivative(np.sin(w * t), t)
        errs.append(np.max(np.abs(d - w * np.cos(w * t))) / w)
        dts.append(t[1] - t[0])
    order = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert 1.9 < order < 2.1


def test_time_integral_inverts_derivative_and_is_exact_for_linear():
    t = np.linspace(0.0, 1e-3, 2001)
    np.testing.assert_allclose(time_integral(np.full((2, t.size), 3.0), t)[:, -1], 3e-3)
    f = np.exp(-(((t - 4e-4) / 5e-5) ** 2))  # a pulse, N
    back = time_integral(time_derivative(f, t), t) + f[0]
    assert np.max(np.abs(back - f)) < 1e-4


def test_mss_rate_is_derivative_of_mean_force():
    t = np.linspace(0.0, 1e-3, 1001)
    rng = np.random.default_rng(3)
    amp = rng.uniform(1, 2, N)
    f = amp[None, :] * np.exp(-(((t[:, None] - 5e-4) / 5e-5) ** 2))  # (nt, n)
    mean_amp = amp[10:14].mean()
    exact = mean_amp * (-2 * (t - 5e-4) / 5e-5**2) * np.exp(-(((t - 5e-4) / 5e-5) ** 2))
    got = mss_four_contact_rate(f, t, 13)
    assert np.max(np.abs(got - exact)) / np.max(np.abs(exact)) < 2e-3


def test_time_axis_checks():
    with pytest.raises(InputError, match="strictly increasing"):
        time_derivative(np.zeros(4), np.array([0.0, 1.0, 1.0, 2.0]))
    with pytest.raises(InputError, match="matching signal"):
        time_integral(np.zeros(4), np.arange(5.0))

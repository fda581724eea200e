"""Result objects: short reprs (arrays by shape) and pandas DataFrames of rows and records."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import msens.api as ms
from msens.config.study import parse_study
from msens.pipeline import run_study

pd = pytest.importorskip("pandas")

# Two beads and a four-contact MsS on a short chain: a run takes a fraction of a second.
SMALL = """
schema = "msens.study/1"
name = "small"
[chain]
beads = 12
damping = "linear"
gamma_contact_kg_per_s = 2.0
[striker]
drop_height_m = 0.0072
[simulation]
t_end_s = 4e-4
sample_rate_hz = 1e6
[[sensor]]
kind = "bead"
particle = 4
[[sensor]]
kind = "bead"
particle = 9
[[sensor]]
kind = "mss"
particle = 6
"""


@pytest.fixture(scope="module")
def small():
    return run_study(parse_study(SMALL))


@pytest.fixture(scope="module")
def physics():
    return ms.run(ms.load_default())


def test_reprs_are_short_and_name_what_matters(small, physics):
    for result in (small, physics):
        text = repr(result)
        assert len(text) < 1000, len(text)  # was 19,678 characters for the default study
        assert result.study.name in text and "TOF" in text and "AR" in text
        assert "array([" not in text
        for setup in result.setups:
            assert len(repr(setup)) < 400
            assert f"array{setup.history.force.shape}" in repr(setup)
            for sensor in setup.sensors:
                assert len(repr(sensor)) < 300
                assert f"array{sensor.force.shape}" in repr(sensor)
    assert "mss@13 physics top" in repr(physics.setups[0].sensors[0])
    assert "transducers at 13, 18" in repr(physics.setups[0])
    assert "bead@4 top" in repr(small) and "mss@6 middle-6" in repr(small.setups[0])
    assert "mss@6 four-contact middle-6" in repr(small.setups[0].sensors[2])


def test_rows_frame_is_the_rows(physics):
    frame = physics.rows_frame()
    rows = physics.rows()
    assert len(frame) == len(rows) == 2
    assert list(frame["tof_us"]) == [r["tof_us"] for r in rows]
    # the published comparison is spread into columns of its own
    assert list(frame["experiment_tof_us"]) == [r["reference"]["experiment_tof_us"]
                                                for r in rows]
    assert "reference" not in frame.columns


def test_records_frame_long_format(small, physics):
    frame = small.records_frame()
    assert list(frame.columns) == ["time_s", "setup", "sensor", "quantity", "value"]
    nt = small.setups[0].history.t.size
    counts = frame.groupby(["sensor", "quantity"], observed=True).size()
    assert counts.to_dict() == {("bead@4", "force_N"): nt, ("bead@9", "force_N"): nt,
                                ("mss@6", "dforce_dt_N_per_s"): nt, ("mss@6", "force_N"): nt}
    bead = frame[(frame.sensor == "bead@9") & (frame.quantity == "force_N")]
    np.testing.assert_array_equal(bead["value"], small.setups[0].sensors[1].force)
    np.testing.assert_array_equal(bead["time_s"], small.setups[0].history.t)
    assert isinstance(frame["quantity"].dtype, pd.CategoricalDtype)

    frame = physics.records_frame()
    sensor = physics.setups[0].sensors[0]
    assert set(frame.quantity.unique()) == {"force_N", "voltage_V", "emf_V", "flux_Wb"}
    wide = frame[frame.quantity == "emf_V"].pivot(index="time_s", columns="sensor",
                                                  values="value")
    np.testing.assert_array_equal(wide["mss@13"], sensor.mss.emf)


def test_missing_pandas_says_how_to_install(small, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas now fails
    for method in (small.rows_frame, small.records_frame):
        with pytest.raises(ImportError, match=r'pip install "msens\[notebook\]"'):
            method()

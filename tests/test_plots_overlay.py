"""The compare overlay (plots.overlay): each channel's measurement is drawn against the model
record it was calibrated with, in that record's unit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from msens import api, plots
from msens.compare import model_record, shot_records
from msens.synth import RigEffects, synthesize
from msens.vocabulary import TIME_LABEL, sensor_name

STUDY = Path(__file__).resolve().parents[1] / "studies" / "paper-mss.toml"


@pytest.fixture(scope="module")
def physics_setup():
    return api.run(api.load(STUDY)).setups[0]


@pytest.fixture(scope="module")
def bead_setup():
    result = api.run(api.load_paper_table2())
    return next(s for s in result.setups if s.setup.name == "bead")


def _artist(ax, gid):
    return next(a for a in ax.get_children() if a.get_gid() == gid)


def _legend(fig) -> list[str]:
    return [t.get_text() for t in fig.legends[0].get_texts()]


def _panels(fig, sensors, per_channel: int) -> list[tuple]:
    """The figure's axes grouped per channel."""
    axes = fig.axes
    assert len(axes) == per_channel * len(sensors)
    return [tuple(axes[per_channel * k: per_channel * (k + 1)]) for k in range(len(sensors))]


def test_physics_mss_overlay_is_integrated_voltage(physics_setup):
    """Before the fix the measured trace (V s) sat flat at 0 on an axis of newtons."""
    shots = shot_records(physics_setup, synthesize(physics_setup,
                                                   RigEffects(shots=3, seed=1)))
    fig = plots.overlay(physics_setup, shots)
    try:
        t = physics_setup.history.t
        for (volts, ax, res), sensor in zip(_panels(fig, physics_setup.sensors, 3),
                                            physics_setup.sensors, strict=True):
            assert ax.get_ylabel() == "integrated DAQ voltage\n(µV s)"
            assert volts.get_title(loc="left") == \
                sensor_name(sensor.sensor.kind, sensor.sensor.particle)
            assert volts.get_title(loc="right").endswith(" V/V")
            model = _artist(ax, "model").get_ydata()
            np.testing.assert_allclose(model, model_record(sensor, t) * 1e6)
            measured = _artist(ax, "measured").get_ydata()
            ok = np.isfinite(measured)
            # same scale as the model, not a flat line
            assert np.ptp(measured[ok]) == pytest.approx(np.ptp(model[ok]), rel=0.05)
            # the residual panel is measured − model, small beside the record
            residual = _artist(res, "residual").get_ydata()
            np.testing.assert_allclose(residual[ok], measured[ok] - model[ok])
            assert np.nanmax(np.abs(residual)) < 0.2 * np.ptp(model)
            # the DAQ voltage panel: the calibrated measured voltage over the model's
            assert volts.get_ylabel() == "DAQ voltage\n(mV)"
            v_model = _artist(volts, "model voltage").get_ydata()
            np.testing.assert_allclose(v_model, sensor.voltage_shape * 1e3)
            v_meas = _artist(volts, "measured").get_ydata()
            ok = np.isfinite(v_meas)
            assert np.corrcoef(v_meas[ok], v_model[ok])[0, 1] > 0.95
            assert res.get_xlabel() in ("", TIME_LABEL)
        assert fig.axes[-1].get_xlabel() == TIME_LABEL
        assert _legend(fig) == ["measured, mean ± 1 s.d. of 3 shots", "model",
                                "measured − model", "±1 s.d. of the shots' mean (noise)"]
    finally:
        plots.close(fig)


def test_bead_overlay_is_force(bead_setup, tmp_path):
    shots = shot_records(bead_setup, synthesize(bead_setup, RigEffects(seed=2)))
    fig = plots.overlay(bead_setup, shots)
    try:
        for (ax, res), sensor in zip(_panels(fig, bead_setup.sensors, 2), bead_setup.sensors,
                                     strict=True):
            assert ax.get_ylabel() == "force\n(N)"
            assert res.get_ylabel() == "residual\n(N)"
            assert ax.get_title(loc="right").endswith(" N/V")
            np.testing.assert_allclose(_artist(ax, "model").get_ydata(), sensor.force)
        assert _legend(fig) == ["measured", "model", "measured − model"]  # one shot: no band
        fig.savefig(tmp_path / "overlay.png", dpi=72)
    finally:
        plots.close(fig)


@pytest.mark.parametrize(("x", "text"), [(28.997, "29.00"), (0.6585, "0.6585"),
                                         (6.966e5, "6.966×10⁵"), (9.99995e5, "1.000×10⁶"),
                                         (-1.2e-5, "-1.200×10⁻⁵")])
def test_gain_number_format(x, text):
    assert plots._overlay_number(x) == text

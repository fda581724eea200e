"""Figures of `msens run` on the main study (issue 22, item 7): every figure function runs and
writes a file of each format, axis labels carry units, and what the reviewer asked of each
figure holds."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from msens import api, plots, plots_mss
from msens.config.study import default_study_path
from msens.io.output import DPI, OutputDir

# a file's first bytes, by format
MAGIC = {"png": b"\x89PNG", "pdf": b"%PDF", "svg": b"<?xml"}
# a label ends in its unit in parentheses: "time (µs)", "|B| (T)", "AR (..., –)"
UNIT = re.compile(r"\([^()]+\)\s*$")


@pytest.fixture(scope="module")
def result():
    return api.run(api.load(default_study_path()))


@pytest.fixture(scope="module")
def table2_result():
    return api.run(api.load_paper_table2())


def _labels(fig) -> list[str]:
    out = [fig.get_supylabel()]
    for ax in fig.axes:
        if ax.get_visible():
            out += [ax.get_xlabel(), ax.get_ylabel()]
    return [t for t in out if t]


def _texts(fig) -> list[str]:
    return [t.get_text() for ax in fig.axes for t in ax.texts]


@pytest.mark.parametrize("name", ["contact_forces.png", "sensor_records.png", "table2.png",
                                  "mss_voltage.png", "mss_integrated.png",
                                  "sensitivity_profile.png", "magnetic_precompression.png"])
def test_every_run_figure_writes_each_format_with_units(result, tmp_path, name):
    makers = api._figure_makers(result)
    assert name in makers
    fig = makers[name]()
    try:
        labels = _labels(fig)
        assert labels, name
        for label in labels:
            assert UNIT.search(label), f"{name}: axis label {label!r} has no unit"
        d = OutputDir(tmp_path)
        for fmt in plots.FORMATS:
            path = d.savefig(name, fig, fmt=fmt, dpi=DPI)
            assert path.name == name.replace(".png", f".{fmt}")
            assert path.read_bytes()[:5].startswith(MAGIC[fmt])
    finally:
        plots.close(fig)


def test_sensitivity_profile_villari_on_its_own_scale_parts_marked(result):
    fig = plots_mss.sensitivity_profile(result)
    try:
        a_app, a_vil = fig.axes
        tr = result.setups[0].transducers[13]
        span = np.ptp(a_vil.get_ylim())
        # the Villari panel is scaled to the Villari sensitivity, not to the approach's
        assert span < 3 * np.ptp(tr.sensitivity_villari) * 1e9
        assert np.ptp(a_app.get_ylim()) > 20 * span
        assert "contact approach" in a_app.get_title(loc="left")
        assert "Villari" in a_vil.get_title(loc="left")
        assert {"coil @13", "coil @18"} <= set(_texts(fig))
        legend = [t.get_text() for t in a_app.get_legend().get_texts()]
        assert "magnet pole pieces" in legend
    finally:
        plots.close(fig)


def test_part_spans_put_each_coil_on_its_particle(result):
    spans = plots_mss._part_spans(result, result.setups[0])
    coils = {p: (c0, c1) for kind, p, c0, c1 in spans if kind == "coil"}
    for p, (c0, c1) in coils.items():
        # particle p's centre lies between contacts p-1 and p
        assert (c0 + c1) / 2 == pytest.approx(p - 0.5, abs=1e-9)
    poles = [(p, c0, c1) for kind, p, c0, c1 in spans if kind == "pole"]
    assert len(poles) == 4
    # the README's sign change of coil 13 sits just outside its upper pole piece (c10..c11)
    assert any(p == 13 and 10 < c0 < c1 < 11 for p, c0, c1 in poles)


def test_contact_forces_show_the_sensors_contacts_over_the_whole_record(result,
                                                                        table2_result):
    for res, expected in ((result, {11, 12, 13, 14, 16, 17, 18, 19}),
                          (table2_result, {11, 12, 13, 14, 16, 17, 18, 19})):
        fig = plots.contact_profiles(res)
        try:
            shown = {int(re.match(r"c(\d+)", t).group(1)) for t in _texts(fig)}
            assert shown == expected
            t_end = res.setups[0].history.t[-1] * 1e6
            for ax in fig.axes:
                if ax.get_visible():
                    # the reflected pulse is in: the lines run to the record's end
                    assert max(line.get_xdata()[-1] for line in ax.lines) == \
                        pytest.approx(t_end)
        finally:
            plots.close(fig)


def test_sensor_records_label_each_kind(result, table2_result):
    fig = plots.sensor_records(result)
    try:
        (ax,) = fig.axes
        assert ax.get_ylabel() == "DAQ voltage\n(mV)"
        peak = np.max(np.abs(result.setups[0].sensors[0].voltage_shape)) * 1e3
        assert np.max(np.abs(ax.lines[0].get_ydata())) == pytest.approx(peak)
    finally:
        plots.close(fig)
    fig = plots.sensor_records(table2_result)
    try:
        labels = [ax.get_ylabel().replace("\n", " ") for ax in fig.axes]
        assert labels == ["bead sensor force (N)", "rod sensor force (N)",
                          "four-contact mean force (N)"]
    finally:
        plots.close(fig)


def test_table2_shows_every_setups_rows(table2_result):
    rows = table2_result.rows()
    fig = plots.table2(rows)
    try:
        for ax in fig.axes:
            ticks = [t.get_text() for t in ax.get_xticklabels()]
            assert ticks == [f"{r['setup']} {r['position']}" for r in rows]
            assert {r["setup"] for r in rows} == {"bead", "rod", "mss"}
    finally:
        plots.close(fig)


def test_magnetic_precompression_bars_match_the_summary(result):
    summary = api.physics_summary(result)["magnetic_precompression_N"]
    fig = plots_mss.magnetic_precompression(result)
    try:
        ax = fig.axes[0]
        (container,) = ax.containers  # one setup: one set of bars
        bars = {round(p.get_x() + p.get_width() / 2): p.get_height() for p in container}
        for row in summary:
            assert bars[row["contact"]] == pytest.approx(row["force_N"])
        # the paper's 1.8 N guess, over the four contacts around each coil
        guess = [c for c in ax.collections if np.allclose(
            np.asarray(c.get_segments())[:, :, 1], plots_mss.PAPER_PRECOMPRESSION_N)]
        assert guess
        assert {"coil @13", "coil @18"} <= set(_texts(fig))
    finally:
        plots.close(fig)


def test_field_map_smooth_parts_named_units(tmp_path):
    from msens.config.fieldsetup import geometry_from_study
    from msens.field.sensor_model import run_field_model
    from msens.field_outputs import field_map_figure, plot_field_map

    study = api.load(default_study_path())
    report = run_field_model(geometry_from_study(study), inductance=False)
    fig = field_map_figure(report)
    try:
        ax, cbar = fig.axes
        assert cbar.get_ylabel() == "|B| (T)"
        assert UNIT.search(ax.get_xlabel()) and UNIT.search(ax.get_ylabel())
        texts = set(_texts(fig))
        assert {"beads", "tube", "magnet", "pole piece", "coil @13", "coil @18"} <= texts
        # smooth shading: Gouraud triangle meshes, not flat-coloured facets
        assert any(type(c).__name__ == "TriMesh" for c in ax.collections)
    finally:
        plots.close(fig)
    for fmt in plots.FORMATS:
        path = plot_field_map(report, tmp_path / f"field_B.{fmt}")
        assert path.read_bytes()[:5].startswith(MAGIC[fmt])


def test_diagnosis_figure_says_no_effect_named():
    from msens.diagnose import diagnose_reference
    from msens.diagnose.report import figure

    d = diagnose_reference(api.load_paper_table2(), "bead")
    none = dataclasses.replace(d, effect="none", parameters={})
    fig = figure(none)
    try:
        ax = fig.axes[0]
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert legend == ["baseline (no effect named)"]
        assert "no effect named" in ax.get_title()
        assert not any("with none" in t for t in legend)
    finally:
        plots.close(fig)

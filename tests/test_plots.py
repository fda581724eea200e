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
from msens.vocabulary import TIME_LABEL, sensor_name
from msens.workflows.run import figure_makers

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
    """Texts drawn in the axes, a name broken over two lines read as one."""
    return [t.get_text().replace("\n", " ") for ax in fig.axes for t in ax.texts]


def _time_axes(fig) -> list[str]:
    """x labels of the axes whose unit is a time (µs)."""
    return [ax.get_xlabel() for ax in fig.axes if ax.get_xlabel().endswith("(µs)")]


@pytest.mark.parametrize("name", ["contact_forces.png", "sensor_records.png", "table2.png",
                                  "mss_voltage.png", "mss_integrated.png",
                                  "sensitivity_profile.png", "magnetic_precompression.png"])
def test_every_run_figure_writes_each_format_with_units(result, tmp_path, name):
    makers = figure_makers(result)
    assert name in makers
    fig = makers[name]()
    try:
        labels = _labels(fig)
        assert labels, name
        for label in labels:
            assert UNIT.search(label), f"{name}: axis label {label!r} has no unit"
            assert "_" not in re.sub(r"\$[^$]*\$", "", label), \
                f"{name}: literal underscore in {label!r}: write it as mathtext"
        # one time origin in every figure
        assert set(_time_axes(fig)) <= {TIME_LABEL}, name
        for text in _texts(fig) + [t.get_text() for ax in fig.axes
                                   for t in (ax.get_legend().get_texts()
                                             if ax.get_legend() else [])]:
            assert "@" not in text and not re.fullmatch(r"c\d+.*", text), \
                f"{name}: {text!r} is not the vocabulary's name"
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
        assert {"coil at particle 13", "coil at particle 18"} <= set(_texts(fig))
        legend = [t.get_text() for t in a_app.get_legend().get_texts()]
        assert "magnet pole pieces" in legend
        # the windings' legend entry is drawn as the bands are: each coil's colour
        assert "coil winding (in its coil's colour)" in legend
        spans = plots_mss._part_spans(result, result.setups[0])
        handles, names = plots_mss._parts_legend(spans, {13: "C0", 18: "C1"})
        winding = handles[names.index("coil winding (in its coil's colour)")]
        drawn = {tuple(np.round(p.get_facecolor(), 4)) for p in a_app.patches}
        legend_colours = {tuple(np.round(p.get_facecolor(), 4)) for p in winding}
        assert len(legend_colours) == 2 and legend_colours <= drawn
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
            shown = {int(re.fullmatch(r"contact (\d+) \(particles (\d+), (\d+)\)", t)
                         .group(1)) for t in _texts(fig)}
            assert shown == expected
            assert set(_time_axes(fig)) == {TIME_LABEL}
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


def test_table2_shows_per_cent_errors_with_visible_error_bars(table2_result, result):
    rows = table2_result.rows()
    fig = plots.table2(rows, table2_result.study.name)
    try:
        a_tof, a_ar = fig.axes
        ticks = [t.get_text() for t in a_tof.get_yticklabels()]
        assert ticks == [f"{sensor_name(r['sensor'], r['particle'])}\n{r['position']}, "
                         f"setup {r['setup']}" for r in rows]
        assert {r["setup"] for r in rows} == {"bead", "rod", "mss"}
        assert "paper-table2" in fig.get_suptitle() and "Table 2" not in fig.get_suptitle()
        for ax, key in ((a_tof, "tof"), (a_ar, "ar")):
            assert ax.get_xlabel().endswith("(%)")
            msens = next(line for line in ax.lines if line.get_label() == "model (msens)")
            expected = [r["reference"][f"{key}_error_pct"] for r in rows]
            np.testing.assert_allclose(msens.get_xdata(), expected)
            # the experiment's ±1 s.d. bars: centred on 0, as wide as 2 s.d. in %, and
            # no marker sits on the bar's row line
            (bars,) = ax.containers
            suffix = "_us" if key == "tof" else ""
            for bar, r in zip(bars, rows, strict=True):
                ref = r["reference"]
                std = 100 * ref[f"experiment_{key}_std{suffix}"] / ref[f"experiment_{key}{suffix}"]
                assert bar.get_width() == pytest.approx(2 * std)
                assert bar.get_x() == pytest.approx(-std)
                centre = bar.get_y() + bar.get_height() / 2
                for line in ax.lines:
                    if line.get_marker() not in ("None", None, ""):
                        assert np.all(np.abs(np.asarray(line.get_ydata()) - centre) > 0.1)
    finally:
        plots.close(fig)
    fig = plots.table2(result.rows(), result.study.name)  # a two-row study
    try:
        assert "paper-mss" in fig.get_suptitle()
        assert len(fig.axes[0].get_yticklabels()) == 2
    finally:
        plots.close(fig)


def test_table2_writes_a_rounded_zero_without_a_minus(result):
    rows = [dict(r) for r in result.rows()]
    rows[0]["tof_us"] = 0.9998 * rows[0]["reference"]["experiment_tof_us"]  # -0.02 %
    fig = plots.table2(rows, result.study.name)
    try:
        texts = [t.get_text() for t in fig.axes[0].texts]
        assert "+0.0 %" in texts and not any(t.startswith("-0.0") for t in texts)
    finally:
        plots.close(fig)


def test_mss_voltage_shows_what_the_readout_does(result):
    fig = plots_mss.mss_voltages(result)
    try:
        axes = fig.axes
        assert len(axes) == 4  # per coil: the voltages, and DAQ − EMF on its own scale
        for k, r in enumerate(s for s in result.setups[0].sensors if s.mss is not None):
            volts, diff = axes[2 * k], axes[2 * k + 1]
            assert volts.get_title(loc="left") == f"coil at particle {r.sensor.particle}"
            m = r.mss
            keep = m.t_daq <= 600e-6
            expected = (m.voltage[keep] - np.interp(m.t_daq[keep], m.t, m.emf)) * 1e3
            np.testing.assert_allclose(diff.lines[0].get_ydata(), expected)
            # the difference is small beside the voltage: its own axis shows it
            assert np.ptp(diff.get_ylim()) < 0.5 * np.ptp(volts.get_ylim())
            assert np.max(np.abs(expected)) > 1.0  # mV: the read-out changes the signal
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
        assert {"coil at particle 13", "coil at particle 18"} <= set(_texts(fig))
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
        assert {"beads", "tube", "magnet", "pole piece", "coil at particle 13",
                "coil at particle 18"} <= texts
        assert "$r\\,A_\\varphi$" in ax.get_title() and "_φ" not in ax.get_title()
        # smooth shading: Gouraud triangle meshes, not flat-coloured facets
        assert any(type(c).__name__ == "TriMesh" for c in ax.collections)
    finally:
        plots.close(fig)
    for fmt in plots.FORMATS:
        path = plot_field_map(report, tmp_path / f"field_B.{fmt}")
        assert path.read_bytes()[:5].startswith(MAGIC[fmt])
    _check_flux_function(report)
    _check_3d_parts(report)


def _check_flux_function(report):
    """The refined flux function is the P2 potential's r A_φ, exactly, at the vertices and
    edge midpoints; the flux lines are equally spaced in flux."""
    from msens.field_outputs import (
        FLUX_SUBDIVISION,
        _element_fields,
        _flux_levels,
        _lattice,
        _refined_psi,
    )

    sol = report.solution
    mesh = sol.basis.mesh
    keep = np.zeros(mesh.t.shape[1], dtype=bool)
    keep[::97] = True
    r, z, tri, psi = _refined_psi(report, keep)
    lam, sub = _lattice(FLUX_SUBDIVISION)
    assert sub.shape == (FLUX_SUBDIVISION**2, 3)
    assert tri.shape == (keep.sum() * FLUX_SUBDIVISION**2, 3)
    k = lam.shape[0]
    a = sol.a[sol.basis.nodal_dofs[0]]
    am = sol.a[sol.basis.facet_dofs[0]]
    t, t2f = mesh.t[:, keep], mesh.t2f[:, keep]
    corner = [int(np.flatnonzero(np.all(lam == np.eye(3)[v], axis=1))[0]) for v in range(3)]
    for v in range(3):
        np.testing.assert_allclose(r[corner[v]::k], mesh.p[0, t[v]])
        np.testing.assert_allclose(z[corner[v]::k], mesh.p[1, t[v]])
        np.testing.assert_allclose(psi[corner[v]::k], mesh.p[0, t[v]] * a[t[v]], rtol=1e-12,
                                   atol=1e-18)
    # skfem's edge order (0, 1), (1, 2), (0, 2)
    for edge, (i, j) in enumerate(((0, 1), (1, 2), (0, 2))):
        mid = int(np.flatnonzero(np.all(np.isclose(lam, (np.eye(3)[i] + np.eye(3)[j]) / 2),
                                        axis=1))[0])
        r_mid = 0.5 * (mesh.p[0, t[i]] + mesh.p[0, t[j]])
        np.testing.assert_allclose(psi[mid::k], r_mid * am[t2f[edge]], rtol=1e-12,
                                   atol=1e-18)
    # the levels are equally spaced
    b_mean, _, _ = _element_fields(report)
    everything = np.ones(mesh.t.shape[1], dtype=bool)
    _, _, _, psi_all = _refined_psi(report, everything, n=1)
    levels = _flux_levels(report, psi_all, everything, np.linalg.norm(b_mean, axis=1))
    assert np.allclose(np.diff(levels), np.diff(levels)[0])


def _check_3d_parts(report):
    """The 3-D view keeps every bead whole (no half-shells at its ends) and no air; its
    image is cut to the parts."""
    from msens.field_outputs import _crop_white, _sensor_z_span, _solid_triangles

    z0, z1 = _sensor_z_span(report)
    keep = _solid_triangles(report, z0 - 0.01, z1 + 0.01, 0.03)
    subdomains = report.solution.problem.mesh.subdomains
    beads = [n for n in subdomains if n.startswith("bead_")]
    whole = [n for n in beads if keep[subdomains[n]].all()]
    assert len(whole) >= 10
    assert all(keep[subdomains[n]].all() or not keep[subdomains[n]].any() for n in beads)
    assert not keep[subdomains["air"]].any()
    img = np.full((100, 80, 3), 255, dtype=np.uint8)
    img[30:60, 20:40] = 10
    assert _crop_white(img, margin=2).shape == (34, 24, 3)


def test_diagnosis_figure_says_no_effect_named():
    from msens.diagnose import diagnose_reference
    from msens.diagnose.report import figure

    d = diagnose_reference(api.load_paper_table2(), "bead")
    none = dataclasses.replace(d, effect="none", parameters={})
    fig = figure(none)
    try:
        ax = fig.axes[0]
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert legend == ["baseline model (no effect named)"]
        title = fig.get_suptitle()
        assert "no effect" in title and "bead" in title
        assert "_" not in title and "@" not in title
        assert not any("with none" in t for t in legend)
    finally:
        plots.close(fig)


def test_diagnosis_and_run_figures_share_the_time_origin(result, tmp_path):
    """The same MsS pulse peaks at the same time since striker impact in diagnosis.png and
    in sensor_records.png (the diagnosis used to plot record time: 45 µs against 89 µs)."""
    from msens.diagnose.report import figure, title
    from msens.diagnose.workflow import diagnose
    from msens.io.read import read_waveform

    study = api.load(default_study_path())
    data = tmp_path / "shots.npz"
    api.synth(study, data, shots=2)
    d = diagnose(read_waveform(data), study, effects=["daq_lowpass"])
    diag, run = figure(d), plots.sensor_records(result)
    try:
        for k, sensor in enumerate(result.setups[0].sensors):
            ax = diag.axes[1 + k]
            assert ax.get_title(loc="left") == sensor_name(sensor.sensor.kind,
                                                           sensor.sensor.particle)
            measured = ax.lines[0]
            t_diag = measured.get_xdata()[np.argmax(np.abs(measured.get_ydata()))]
            line = next(ln for ln in run.axes[0].lines
                        if ln.get_label() == ax.get_title(loc="left"))
            t_run = line.get_xdata()[np.argmax(np.abs(line.get_ydata()))]
            assert t_diag == pytest.approx(t_run, abs=1.0)  # µs
        assert diag.axes[-1].get_xlabel() == run.axes[-1].get_xlabel() == TIME_LABEL
        # one verdict, in words
        text = title(d)
        assert diag.get_suptitle() == text
        assert "_" not in text and "@" not in text
        if d.explained and d.effect == "none":
            assert "explains the measurement within the noise" in text
            assert "mostly" not in text and "residual is" not in text
    finally:
        plots.close(diag)
        plots.close(run)


def _sweep(n_turns=(400, 600, 800, 1000, 1200), lengths=(7e-3, 8e-3, 9e-3, 10e-3)):
    """A coil sweep whose SNR is set by the turns (five clusters) with a little scatter."""
    import itertools

    from msens.design.sweep import Design

    rng = np.random.default_rng(3)
    designs, rows = [], []
    for i, (n, length) in enumerate(itertools.product(n_turns, lengths)):
        designs.append(Design(i, (("coil.length_m", length), ("coil.turns", n))))
        rows.append({"status": "ok", "snr": 4e4 * (n / 400) * (1 + 0.05 * rng.random()),
                     "precompression_N": 2.0,
                     "bandwidth_Hz": 3e5 * 400 / n * (1 + 0.05 * rng.random()),
                     "resonance_Hz": 2e5 * 400 / n})
    return designs, rows


def test_pareto_snr_in_db_clusters_named_star_open():
    from msens.design.report import groups, parameter_text, pareto_figure

    designs, rows = _sweep()
    snr = np.array([r["snr"] for r in rows])
    key, values = groups(designs, 20 * np.log10(snr))
    assert key == "coil.turns" and values == [d.values[1][1] for d in designs]
    assert parameter_text("coil.length_m", 7e-3) == "coil length = 7 mm"
    best = int(np.argmax(snr))
    fig = pareto_figure(designs, rows, best)
    try:
        ax = fig.axes[0]
        assert ax.get_ylabel().endswith("(dB)")
        assert ax.get_ylim()[1] < 200  # dB, not a ratio of 40 000 .. 200 000
        points = np.concatenate([np.asarray(c.get_offsets())[:, 1] for c in ax.collections])
        np.testing.assert_allclose(np.sort(points), np.sort(20 * np.log10(snr)))
        legend = [t.get_text() for t in fig.legends[0].get_texts()]
        assert [f"coil turns = {n}" for n in (400, 600, 800, 1000, 1200)] == legend[:5]
        assert f"recommended (design {best})" in legend
        (star,) = [ln for ln in ax.lines if ln.get_marker() == "*"]
        (front,) = [ln for ln in ax.lines if ln.get_label() == "Pareto front"]
        # open, and over the front's point it marks, which stays visible inside it
        assert star.get_markerfacecolor() == "none"
        assert star.get_zorder() > front.get_zorder()
        assert star.get_ydata()[0] in front.get_ydata()
    finally:
        plots.close(fig)


@pytest.mark.parametrize(("tag", "name"), [
    ("mss@13", "coil at particle 13"), ("bead@18", "bead sensor at particle 18"),
    ("rod@13 (top)", "rod sensor at particle 13 (top)"), ("elsewhere", "elsewhere")])
def test_vocabulary_names_data_keys(tag, name):
    from msens.vocabulary import channel_name, contact_name

    assert channel_name(tag) == name
    assert contact_name(11) == "contact 11 (particles 11, 12)"
    assert contact_name(11, particles=False) == "contact 11"
    assert TIME_LABEL == "time since striker impact (µs)"


def test_table2_rows_without_tof_or_reference_draw_no_marks():
    """A row whose record holds no reflected pulse (TOF and AR None) or without a reference
    shows no marks instead of failing."""
    rows = [{"setup": "a", "sensor": "bead", "position": "top", "particle": 13,
             "tof_us": None, "ar": None,
             "reference": {"experiment_tof_us": 300.0, "experiment_tof_std_us": 2.0,
                           "experiment_ar": 0.5, "experiment_ar_std": 0.02}},
            {"setup": "a", "sensor": "mss", "position": "bottom", "particle": 18,
             "tof_us": 210.0, "ar": 0.7, "reference": {}}]
    fig = plots.table2(rows, "x")
    try:
        for ax in fig.axes:
            msens = next(ln for ln in ax.lines if ln.get_label() == "model (msens)")
            assert np.all(np.isnan(msens.get_xdata()))
    finally:
        plots.close(fig)

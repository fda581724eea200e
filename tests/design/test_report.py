"""Recommendation among verified designs (pure functions of the rows)."""

from __future__ import annotations

import pytest

from msens.design.report import (
    METRICS,
    above_verified,
    csv_text,
    ranked,
    recommend,
    verification,
)
from msens.design.sweep import Design, Recommend


def _row(snr: float, pre: float = 1.0, maps: bool = False) -> dict:
    return {"status": "ok", **dict.fromkeys(METRICS, 1.0), "snr": snr,
            "peak_emf_V": snr / 100, "peak_voltage_V": snr / 90,
            "bandwidth_Hz": 5e4, "resonance_Hz": 7e4, "precompression_N": pre,
            "precompression_max_N": pre, "wave_speed_change": 0.0, "contact_maps": maps}


DESIGNS = [Design(i, (("magnet.radial_gap_m", g),)) for i, g in
           enumerate((0.1e-3, 0.5e-3, 1e-3, 2e-3, 3e-3))]


def test_ranked_orders_feasible_designs_by_objective():
    rows = [_row(10), _row(30), _row(20, pre=9.0), {"status": "failed", "reason": "x"},
            _row(30)]
    assert ranked(rows, Recommend(max_precompression_n=5.0)) == [1, 4, 0]
    assert ranked(rows, Recommend()) == [1, 4, 2, 0]


def test_recommendation_among_verified_designs_and_its_warning():
    """Screened 10, 30, 25, 5, 28; the best two verified read 24 and 26 with their maps: the
    recommendation is design 2 (26) among the verified, and design 4 (screened 28, not
    verified) lies above it, so the reasons ask to verify more."""
    screened = [_row(10), _row(30), _row(25), _row(5), _row(28)]
    rule = Recommend()
    best2 = ranked(screened, rule)[:2]
    assert best2 == [1, 4]
    rows = list(screened)
    rows[1], rows[4] = _row(24, maps=True), _row(29, maps=True)
    screening = {i: screened[i] for i in best2}
    rec = verification(recommend(DESIGNS, rows, rule, among=best2), DESIGNS, rows,
                       screening, rule)
    assert rec["design"] == 4 and rec["designs_feasible"] == 2
    assert rec["verified_designs"] == [1, 4]
    (a, b) = rec["verification"]
    assert a["screening_snr"] == 30 and a["verified_snr"] == 24
    assert a["objective_change"] == pytest.approx(-0.2)
    assert b["objective_change"] == pytest.approx(29 / 28 - 1)
    assert "off by up to 20 %" in rec["reasons"][0]
    assert not any("verify more" in r for r in rec["reasons"])
    # the second verified design loses too: design 2 (screened 25) now screens above both
    rows[4] = _row(22, maps=True)
    rec = verification(recommend(DESIGNS, rows, rule, among=best2), DESIGNS, rows,
                       screening, rule)
    assert rec["design"] == 1
    assert "design 2" in rec["reasons"][1] and "verify more" in rec["reasons"][1]


def test_csv_says_which_rows_read_the_contact_maps():
    rows = [_row(10), _row(30, maps=True), {"status": "failed", "reason": "boom"}]
    lines = csv_text(DESIGNS[:3], rows).splitlines()
    head = lines[0].split(",")
    k = head.index("contact_maps")
    assert [ln.split(",")[k] for ln in lines[1:]] == ["false", "true", ""]


def test_failed_verification_recommends_nothing_and_says_why():
    screened = [_row(10), _row(30)]
    rows = [screened[0], {"status": "failed", "reason": "maps: Newton did not converge"}]
    rule = Recommend()
    rec = verification(recommend(DESIGNS[:2], rows, rule, among=[1]), DESIGNS[:2], rows,
                       {1: screened[1]}, rule)
    assert rec["design"] is None and rec["designs_failed"] == 1
    assert rec["verification"] == [{"design": 1, "status": "failed"}]
    assert "none of them evaluated" in rec["reasons"][0]


def test_designs_above_the_best_verified_one():
    """Screened 10, 30, 25, 5, 28: with design 1 verified at 24, designs 4 and 2 screen above
    it (best first); with design 2 verified at 26 too, design 4; with design 4 verified at
    22, none; with no verified design meeting the limits, every feasible one left."""
    rule = Recommend()
    rows = [_row(10), _row(24, maps=True), _row(25), _row(5), _row(28)]
    assert above_verified(rows, {1}, rule) == [4, 2]
    rows[2] = _row(26, maps=True)
    assert above_verified(rows, {1, 2}, rule) == [4]
    rows[4] = _row(22, maps=True)
    assert above_verified(rows, {1, 2, 4}, rule) == []
    rows[1] = _row(24, pre=9.0, maps=True)
    limited = Recommend(max_precompression_n=5.0)
    assert above_verified(rows, {1}, limited) == [2, 4, 0, 3]


def test_auto_verification_stops_when_no_design_screens_above(tmp_path, monkeypatch):
    """``verify = "auto"`` through :func:`msens.design.run_design` (a stand-in design
    function: screened SNR 10, 30, 25, 5, 28; verified 24, 26 and 22 for designs 1, 2, 4):
    design 1 first (30 → 24), then design 4 (28 → 22), then design 2 (25 → 26), and no
    unverified design screens above 26: three verified, design 2 recommended."""
    from msens import api
    from msens.config.fieldsetup import geometry_from_study
    from msens.design import magnet_sweep, run_design
    from msens.design.sweep import design_geometry, parse_sweep, sweep_sensor

    gaps = (0.1e-3, 0.5e-3, 1e-3, 2e-3, 3e-3)
    screened, verified = (10, 30, 25, 5, 28), {1: 24, 2: 26, 4: 22}
    calls = []

    def fake(task):
        i = geometries.index(task.geometry)
        maps = task.study.field.contact_map
        calls.append((i, maps))
        return _row(verified[i] if maps else screened[i], maps=maps)

    monkeypatch.setattr(magnet_sweep, "evaluate_design", fake)
    study = api.load("tests/data/tiny-mss.toml").replace({"field.contact_map": True})
    spec = parse_sweep('schema = "msens.sweep/1"\nname = "auto"\n[magnet]\nradial_gap_m = ['
                       + ", ".join(map(repr, gaps)) + ']\n[model]\ncontact_map = false\n'
                       'verify = "auto"\n')
    base = geometry_from_study(study)
    particle = sweep_sensor(study, spec).particle
    geometries = [design_geometry(base, particle, d) for d in spec.designs()]
    result = run_design(study, spec, tmp_path / "out", workers=1, progress=False)
    assert [c for c in calls if c[1]] == [(1, True), (4, True), (2, True)]
    rec = result.recommendation
    assert rec["design"] == 2 and rec["verified_designs"] == [1, 4, 2]
    assert not any("verify more" in r for r in rec["reasons"])

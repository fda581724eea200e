"""The main study's contact maps (``[field] contact_map = true``) through run, design and
diagnose (slow: the main study's contact maps are committed in ``meshes/``; the chain runs a
few times).

One transducer core: the study's own coil and magnet designed in a coil and a magnet sweep
read the run's EMF, and diagnose's baseline record is the run's DAQ voltage, all through the
nonlinear maps.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from msens import api
from msens.config.study import default_study_path

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The main study (its contact maps on): its file, the study and its run; and the run
    with the maps off (the linear approach sources)."""
    path = default_study_path()
    study = api.load(path)
    assert study.field.contact_map
    return path, study, api.run(study), api.run(study.replace({"field.contact_map": False}))


def _coil(result, particle=13) -> dict:
    return next(c for c in api.physics_summary(result)["coils"] if c["particle"] == particle)


def _design(study, folder, body: str) -> list[dict]:
    """``designs.csv`` rows of a sweep of ``study`` given by ``body`` (after the header)."""
    spec = folder / "sweep.toml"
    spec.write_text('schema = "msens.sweep/1"\nname = "t"\n' + body)
    api.design(study, spec, folder / "out", progress=False, workers=1)
    with (folder / "out" / "designs.csv").open() as fh:
        return list(csv.DictReader(fh))


def test_design_of_the_papers_coil_with_contact_maps_equals_msens_run(runs, tmp_path):
    _, study, mapped, linear = runs
    rows = _design(study, tmp_path, "sensor = 13\n[coil]\nturns = [1100]\n"
                                    "axial_offset_m = [0.0, 1e-3]\n")
    assert [r["status"] for r in rows] == ["ok", "ok"]
    run = _coil(mapped)
    assert float(rows[0]["peak_emf_V"]) == pytest.approx(run["peak_emf_V"], rel=1e-5)
    # the maps change the pulse (0.69 -> 0.67 V DAQ at coil 13): the design sees them
    assert abs(run["peak_voltage_V"] / _coil(linear)["peak_voltage_V"] - 1) > 0.01
    assert float(rows[0]["peak_voltage_V"]) == pytest.approx(run["peak_voltage_V"], rel=1e-2)
    assert float(rows[1]["peak_emf_V"]) != pytest.approx(run["peak_emf_V"], rel=1e-3)


def test_design_of_the_papers_magnet_with_contact_maps_equals_msens_run(runs, tmp_path):
    """A magnet design has its own maps; for the study's own magnet they are the committed
    ones, so the design equals the run (its own field model)."""
    _, study, mapped, linear = runs
    (row,) = _design(study, tmp_path, 'sensor = 13\n[magnet]\ngrade = ["ceramic8"]\n')
    assert row["status"] == "ok"
    run = _coil(mapped)
    assert float(row["peak_emf_V"]) == pytest.approx(run["peak_emf_V"], rel=1e-4)
    # FFT transfer function against the run's sampled DAQ model (as the coil design)
    assert float(row["peak_voltage_V"]) == pytest.approx(run["peak_voltage_V"], rel=1e-3)
    assert abs(float(row["peak_voltage_V"]) / _coil(linear)["peak_voltage_V"] - 1) > 0.01


def test_diagnose_baseline_with_contact_maps_is_the_run(runs):
    from msens.diagnose.effects import Context
    from msens.diagnose.predict import Predictor, baseline_state, setup_result
    from msens.diagnose.workflow import baseline_dissipation
    from msens.pipeline import output_times

    _, study, mapped, linear = runs
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    predicted = setup_result(ctx, base, Predictor(output_times(study)))
    for p, r, lin in zip(predicted.sensors, mapped.setups[0].sensors,
                         linear.setups[0].sensors, strict=True):
        if r.mss is None:
            continue
        peak = np.max(np.abs(r.mss.voltage))
        np.testing.assert_allclose(p.mss.voltage, r.mss.voltage, rtol=0, atol=1e-9 * peak)
        # the maps change the record (with eddy currents coil 13 by 4.1 % of its peak, coil
        # 18, which the pulse reaches through weakly nonlinear contacts, by 0.65 %)
        assert np.max(np.abs(r.mss.voltage - lin.mss.voltage)) > 0.003 * peak


def test_remanence_variants_read_the_contact_maps(runs):
    """magnet_remanence with contact maps: a variant next to the study's magnets reads the
    maps (Transducer.reading_maps_of), so its record joins the baseline continuously; read
    linearly it would differ by the maps' effect (> 0.5 % of the peak)."""
    import dataclasses

    from msens.diagnose.effects import Context
    from msens.diagnose.physics import with_physics
    from msens.diagnose.predict import Predictor, baseline_state, setup_result
    from msens.diagnose.workflow import baseline_dissipation
    from msens.pipeline import output_times

    study = runs[1]
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    near = dataclasses.replace(base, physics=with_physics(base.physics,
                                                          remanence_factor=1.0 + 1e-9))
    predictor = Predictor(output_times(study))
    for a, b in zip(setup_result(ctx, near, predictor).sensors,
                    setup_result(ctx, base, predictor).sensors, strict=True):
        if b.mss is not None:
            peak = np.max(np.abs(b.mss.voltage))
            assert np.max(np.abs(a.mss.voltage - b.mss.voltage)) < 1e-6 * peak


def test_reversible_permeability_reads_the_same_maps(runs):
    """The maps are full nonlinear solves, which the small-signal permeability does not
    enter: the reversible choice reads the committed tables through its own (smaller)
    sensitivities."""
    import msens.magnetics.contact_map as cm
    from msens.config.fieldsetup import geometry_from_study
    from msens.magnetics.transducer_cache import transducers_for

    def no_solve(*args, **kwargs):
        raise AssertionError("the reversible study solved contact maps again")

    _, study, _, _ = runs
    rev = study.replace({"field.small_signal_permeability": "reversible"})
    a = transducers_for(geometry_from_study(study), contact_maps=True)[13]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(cm, "run_tasks", no_solve)
        b = transducers_for(geometry_from_study(rev), contact_maps=True)[13]
    assert all(
        np.array_equal(x.steel_flux, y.steel_flux) and np.array_equal(x.air_flux, y.air_flux)
        for x, y in zip(a.approach_map.maps, b.approach_map.maps, strict=True))
    assert np.max(np.abs(b.dlambda_dapproach)) < 0.8 * np.max(np.abs(a.dlambda_dapproach))


def test_magnet_design_solves_its_own_maps_and_equals_msens_run(tmp_path, monkeypatch):
    """A magnet design other than the study's (the tiny study's magnet as N38) solves its
    own contact maps; its row equals ``msens run`` of the study with that magnet (which
    reads the same maps), and differs from the linear screening of the same design."""
    from pathlib import Path

    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp_path / "cache"))  # cold, and kept apart
    tiny = (Path(__file__).parents[1] / "data" / "tiny-mss.toml").read_text()
    path = tmp_path / "tiny.toml"
    path.write_text(tiny + "\n[field]\ncontact_map = true\n")
    study = api.load(path)
    rows = {}
    for name, model in (("maps", ""), ("linear", "[model]\ncontact_map = false\n")):
        (tmp_path / name).mkdir()
        (rows[name],) = _design(study, tmp_path / name, '[magnet]\ngrade = ["N38"]\n' + model)
        assert rows[name]["status"] == "ok"
    # a design's own maps are stored with its sweep (the store writes new design artifacts
    # into the sweep folder), never into the user cache
    assert list((tmp_path / "maps").rglob("contact-map-*.json"))
    assert not list((tmp_path / "cache").glob("contact-map-*.json"))
    n38 = study.replace({"sensor[1].magnet.grade": "N38"})
    run = next(c for c in api.physics_summary(api.run(n38))["coils"] if c["particle"] == 6)
    assert float(rows["maps"]["peak_emf_V"]) == pytest.approx(run["peak_emf_V"], rel=1e-6)
    # the design's DAQ voltage is the circuit's transfer function by FFT, the run's the
    # sampled DAQ model (7e-5 apart here)
    assert float(rows["maps"]["peak_voltage_V"]) == pytest.approx(run["peak_voltage_V"],
                                                                   rel=1e-3)
    assert float(rows["linear"]["peak_emf_V"]) != pytest.approx(run["peak_emf_V"], rel=1e-4)
    # screening both magnets and verifying the best, the study's own ceramic 8 (its SNR
    # 1.09e5 against N38's 9.4e4): its row is then msens run of the study, which solves the
    # same maps; N38 keeps its screening row
    # as the msens command runs it: the verified design in this process, its maps on a pool
    from msens.parallel import allow_pools

    (tmp_path / "verify").mkdir()
    with allow_pools():
        both = _design(study, tmp_path / "verify", '[magnet]\ngrade = ["ceramic8", "N38"]\n'
                       "[model]\ncontact_map = false\nverify = 1\n")
    assert [r["contact_maps"] for r in both] == ["true", "false"]
    assert both[1] == {**rows["linear"], "design": "1"}
    own = next(c for c in api.physics_summary(api.run(study))["coils"] if c["particle"] == 6)
    assert float(both[0]["peak_emf_V"]) == pytest.approx(own["peak_emf_V"], rel=1e-6)
    assert float(both[0]["peak_voltage_V"]) == pytest.approx(own["peak_voltage_V"], rel=1e-3)
    rec = json.loads((tmp_path / "verify" / "out" / "recommendation.json").read_text())
    assert rec["design"] == 0 and rec["verified_designs"] == [0]
    (entry,) = rec["verification"]
    assert entry["verified_snr"] == pytest.approx(float(both[0]["snr"]), rel=1e-9)
    assert abs(entry["objective_change"]) > 1e-3  # the maps change the screened figure
    assert "own contact maps" in rec["reasons"][0]
    # verify = "auto": ceramic 8 first; N38 screens below its verified SNR, so it stops there
    (tmp_path / "auto").mkdir()
    with allow_pools():
        auto = _design(study, tmp_path / "auto", '[magnet]\ngrade = ["ceramic8", "N38"]\n'
                       '[model]\ncontact_map = false\nverify = "auto"\n')
    assert auto == both
    rec_auto = json.loads((tmp_path / "auto" / "out" / "recommendation.json").read_text())
    assert rec_auto["verified_designs"] == [0] and rec_auto["design"] == 0

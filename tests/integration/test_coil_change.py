"""A coil change on the main study is a read of its field model, not a rebuild: msens run,
synth and diagnose after the default run (cold user cache; the committed field model)."""

from __future__ import annotations

import json
import logging

import numpy as np
import pytest

import msens
from msens.cli import main
from msens.field.sensor_model import coil_resistance


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("coil-change")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MSENS_MESH_DIR", str(tmp / "cache"))
        assert main(["run", "--out", str(tmp / "default"), "-q", "--no-figures"]) == 0
        yield tmp, mp


def _coils(path):
    return {c["particle"]: c for c in json.loads(path.read_text())["coils"]}


def test_run_with_a_changed_coil_reads_the_field_model(cache, caplog):
    tmp, _ = cache
    out = tmp / "turns"
    with caplog.at_level(logging.INFO):
        assert main(["run", "--set", "sensor.1.coil.turns=1000", "--set",
                     "sensor.1.coil.length_m=8e-3", "--out", str(out), "--no-figures"]) == 0
    assert "read from the field model" in caplog.text
    assert "approach maps" not in caplog.text.lower().replace("contact maps", "")
    # no mesh or contact map of the changed geometry was made
    cache_dir = tmp / "cache"
    assert not list(cache_dir.glob("sensor-*.msh")) and not list(
        cache_dir.glob("contact-map-*.json"))
    default, changed = _coils(tmp / "default" / "summary.json"), _coils(out / "summary.json")
    study = msens.replace(msens.load_default(), {"sensor[1].coil.turns": 1000,
                                                 "sensor[1].coil.length_m": 8e-3})
    from msens.config.fieldsetup import coil_geometry

    spec = study.setups[0].sensors[0]
    coil = coil_geometry(spec.coil, spec.particle)
    assert changed[13]["resistance_ohm"] == pytest.approx(coil_resistance(coil), rel=1e-12)
    assert changed[13]["peak_voltage_V"] != default[13]["peak_voltage_V"]
    # the unchanged coil keeps its own transducer: its signal is the default run's, exactly
    assert changed[18] == default[18]


def _columns(path):
    from msens.io.read import read_waveform

    w = read_waveform(path)
    return {n: np.asarray(w.channel(n)) for n in w.names}


def test_synth_of_a_changed_coil_reads_it(cache, caplog):
    tmp, _ = cache
    default = msens.load_default()
    changed = msens.replace(default, {"sensor[2].coil.axial_offset_m": 0.5e-3})
    base = _columns(msens.synth(default, tmp / "default.csv", noise=0.0))
    with caplog.at_level(logging.INFO):
        moved = _columns(msens.synth(changed, tmp / "moved.csv", noise=0.0))
    assert "read from the field model" in caplog.text
    upper, lower = "mss@13", "mss@18"
    # same rig draws (seed 0): the coil that did not move records the same voltage; the one
    # moved 0.5 mm away from the magnet's centre another
    assert np.array_equal(base[upper], moved[upper])
    assert not np.allclose(base[lower], moved[lower], rtol=1e-4, atol=0)


@pytest.mark.slow
def test_diagnose_of_a_changed_coil_finds_nothing_missing(cache, tmp_path):
    del cache  # the default run before it
    changed = msens.replace(msens.load_default(), {"sensor[1].coil.turns": 900})
    record = msens.synth(changed, tmp_path / "turns900.csv", noise=0.01, seed=3)
    result = msens.diagnose(changed, record, tmp_path / "diagnosis")
    assert result.passes[0].effect == "none", result.passes[0]


@pytest.mark.slow
def test_a_designed_coil_equals_the_run_of_that_coil(cache, tmp_path):
    """One implementation: design's row of a coil and msens run of the study with that coil
    (read from the same field model) agree."""
    del cache  # the default run before it
    spec = tmp_path / "sweep.toml"
    spec.write_text('schema = "msens.sweep/1"\nname = "one-coil"\nsensor = 13\n[coil]\n'
                    'turns = [1000]\nlength_m = [8e-3]\ninner_radius_m = [7.95e-3]\n'
                    'wire = ["AWG36"]\naxial_offset_m = [0.0]\n')
    msens.design(msens.load_default(), spec, tmp_path / "design", progress=False)
    import csv

    with open(tmp_path / "design" / "designs.csv", newline="") as f:
        row = next(csv.DictReader(f))
    assert main(["run", "--set", "sensor.1.coil.turns=1000", "--set",
                 "sensor.1.coil.length_m=8e-3", "--out", str(tmp_path / "run"), "-q",
                 "--no-figures"]) == 0
    coil = _coils(tmp_path / "run" / "summary.json")[13]
    assert float(row["inductance_H"]) == pytest.approx(coil["inductance_H"], rel=1e-6)
    assert float(row["resistance_ohm"]) == pytest.approx(coil["resistance_ohm"], rel=1e-9)
    # the design's table spans its designs, the run's the coil window: both 0.1 mm grids
    assert float(row["peak_emf_V"]) == pytest.approx(coil["peak_emf_V"], rel=2e-4)

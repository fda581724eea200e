"""`msens field` and `msens verify` from the command line."""

from __future__ import annotations

import json

import pytest

from msens.cli import main
from msens.config.study import default_study_path

MSS = (default_study_path().parent / "paper-mss.toml").read_text()


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        ("turns = 1100", "turns = 0", "turns"),
        ('  grade = "ceramic8"\n\n[[sensor]]', '  grade = "ceramic8"\n  inner_radius_m = 3e-3\n'
         '  outer_radius_m = 5e-3\n\n[[sensor]]', "magnet"),
        ("inner_radius_m = 7.95e-3     # former", "inner_radius_m = 13e-3     # former",
         "overlap"),
        ("particle = 13", "particle = 31", "particle"),
    ],
)
def test_field_bad_geometry_exit_2(tmp_path, capsys, old, new, fragment):
    assert old in MSS
    study = tmp_path / "s.toml"
    study.write_text(MSS.replace(old, new, 1))
    code = main(["field", str(study), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert fragment in err.lower()
    assert "Traceback" not in err


def test_field_writes_outputs(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text(MSS)
    out = tmp_path / "out"
    assert main(["field", str(study), "--out", str(out)]) == 0
    data = json.loads((out / "field.json").read_text())
    assert [c["particle"] for c in data["coils"]] == [13, 18]
    assert data["newton_iterations"] <= 15
    assert (out / "field.vtu").stat().st_size > 0
    assert "magnetic compression" in capsys.readouterr().out


def test_verify_prints_passing_table(capsys):
    assert main(["verify"]) == 0
    out = capsys.readouterr().out
    assert "PASS" in out and "FAIL" not in out


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        ('  grade = "ceramic8"\n\n[[sensor]]',
         '  remanence_T = 3.0\n  recoil_permeability = 1.05\n\n[[sensor]]', "remanence_T"),
        ("youngs_modulus_pa = 200e9\npoisson_ratio = 0.29\ngravity",
         "youngs_modulus_pa = 200e9\npoisson_ratio = 0.7\ngravity", "poisson_ratio"),
        ("inner_radius_m = 7.95e-3     # former", "inner_radius_m = 13e-3     # former",
         "overlap"),
        ("particle = 18", "particle = 40", "particle"),
    ],
)
def test_physics_run_bad_input_exit_2(tmp_path, capsys, old, new, fragment):
    """The main job rejects a coil overlapping the magnet, a coil outside the chain and
    material data out of range before any work."""
    assert old in MSS
    study = tmp_path / "s.toml"
    study.write_text(MSS.replace(old, new, 1))
    code = main(["run", str(study), "--out", str(tmp_path / "out"), "--no-figures"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert fragment in err
    assert "Traceback" not in err

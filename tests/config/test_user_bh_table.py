"""User B–H table ``[field] steel_bh``: parsing, bad tables via ``msens field``, cache keys."""

from __future__ import annotations

import numpy as np
import pytest

from msens.cli import main
from msens.config.fieldsetup import geometry_from_study
from msens.config.study import default_study_path, load_study
from msens.field.cache import geometry_key
from msens.field.geometry import SensorGeometry
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import cache_key
from msens.params.materials import BEAD_STEEL, STEEL_1018_BH

MSS = default_study_path().read_text()

#: The 1018 table written out as a study would give it.
TABLE_1018 = ", ".join(f"[{float(b)!r}, {float(h)!r}]"
                       for b, h in zip(STEEL_1018_BH.b, STEEL_1018_BH.h, strict=True))


def study_with(tmp_path, steel_bh: str):
    path = tmp_path / "s.toml"
    # into the main study's own [field] table
    path.write_text(MSS.replace("[field]", f"[field]\nsteel_bh = {steel_bh}", 1))
    return path


@pytest.mark.parametrize(
    ("table", "fragments"),
    [
        # B falls at the third point
        ("[[0, 0], [0.5, 300], [0.4, 800], [1.5, 4000]]",
         ["field.steel_bh[2]", "B must be strictly increasing"]),
        # H repeats at the third point
        ("[[0, 0], [0.5, 300], [1.0, 300], [1.5, 4000]]",
         ["field.steel_bh[2]", "H must be strictly increasing"]),
        ("[[0.1, 0], [0.5, 300], [1.0, 800]]", ["field.steel_bh[0]", "[0, 0]"]),
        ("[[0, 0], [1.0, 800]]", ["field.steel_bh", "at least 3 pairs", "got 2"]),
        ("[[0, 0], [0.5, 300, 1], [1.0, 800]]", ["field.steel_bh[1]", "pair of finite"]),
        ("[0, 0.5, 1.0]", ["field.steel_bh[0]", "pair of finite"]),
        ('"1018"', ["field.steel_bh", "at least 3 pairs"]),
        ("[[0, 0], [0.5, inf], [1.0, 800]]", ["field.steel_bh[1]", "finite"]),
        ("[[0, 0], [1.0, 800], [5.5, 4e6]]", ["field.steel_bh[2]", "below 5"]),
        # last interval dH/dB = 1e3 A/(m T), far below 1/(3 mu0) = 2.65e5
        ("[[0, 0], [1.0, 800], [2.0, 1800]]", ["field.steel_bh[2]", "saturation line"]),
    ],
)
def test_bad_table_exit_2_names_the_key(tmp_path, capsys, table, fragments):
    code = main(["field", str(study_with(tmp_path, table)), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2, err
    for fragment in fragments:
        assert fragment in err
    assert "Traceback" not in err
    assert err.count("msens: error") == 1  # one error line (after the command's first line)
    assert not (tmp_path / "out").exists()


def test_table_parses_into_a_bh_curve(tmp_path):
    path = study_with(tmp_path, "[[0, 0], [0.5, 200.0], [1.2, 1000], [2.0, 3e5]]")
    curve = load_study(path).field.steel_bh
    assert curve.name == "user table"
    assert curve.source == str(path)
    np.testing.assert_array_equal(curve.b, [0.0, 0.5, 1.2, 2.0])
    np.testing.assert_array_equal(curve.h, [0.0, 200.0, 1000.0, 3e5])
    assert curve.b.dtype == float and curve.h.dtype == float
    assert not curve.b.flags.writeable  # frozen record: its table cannot change under a cache


def test_study_without_table_keeps_1018():
    study = load_study(default_study_path())
    assert study.field.steel_bh is None
    assert geometry_from_study(study).steel is STEEL_1018_BH


def transducer_key(g: SensorGeometry) -> str:
    # the key transducer_report uses: the law follows the geometry's table
    return cache_key(g, stress_force=g.beads.contact_load, law=law_for_steel(g.steel),
                     material=BEAD_STEEL, approach=True)


def test_cache_keys(tmp_path):
    default = geometry_from_study(load_study(default_study_path()))
    same = geometry_from_study(load_study(study_with(tmp_path, f"[{TABLE_1018}]")))
    soft = geometry_from_study(load_study(study_with(
        tmp_path, "[[0, 0], [0.5, 100.0], [1.2, 500], [2.0, 3e5]]")))
    assert same.steel.name == "user table" and soft.steel.name == "user table"
    # the committed default mesh and transducers keep their names
    assert geometry_key(SensorGeometry()) == "fd62a31efc65de6e"
    assert transducer_key(SensorGeometry()) == "86623a3fddc3684a"
    # the material is not geometry: every table shares the default mesh
    assert geometry_key(same) == geometry_key(soft) == geometry_key(default)
    # transducers depend on the curve's points, not on its name
    assert transducer_key(same) == transducer_key(default) == "86623a3fddc3684a"
    assert transducer_key(soft) != transducer_key(default)

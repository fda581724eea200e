"""Study.replace: dotted keys change a loaded study, validated exactly like the TOML file."""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest

import msens.api as ms
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, default_study_path, load_study, parse_study
from msens.errors import InputError

MSS = default_study_path()


def _without_source(study):
    return dataclasses.replace(study, source="")


def test_replace_equals_editing_the_file():
    study = load_study(MSS)
    text = MSS.read_text()
    assert text.count("turns = 1100") == 2 and "drop_height_m = 7.2e-3" in text
    edited = parse_study(text.replace("drop_height_m = 7.2e-3", "drop_height_m = 0.01")
                         .replace("turns = 1100", "turns = 900", 1))
    changed = study.replace({"striker.drop_height_m": 0.01, "sensor[1].coil.turns": 900})
    assert _without_source(changed) == _without_source(edited)
    assert ms.provenance(changed) == ms.provenance(edited)  # the same content hash
    assert [s.coil.turns for s in changed.setups[0].sensors] == [900, 1100]
    assert changed.striker.velocity_m_per_s == pytest.approx(np.sqrt(2 * 9.80665 * 0.01))
    assert "striker.drop_height_m=0.01" in changed.source
    # the original is untouched, and replacing nothing or the same value changes nothing
    assert study.striker.drop_height_m == 7.2e-3
    assert study.replace({}) is study
    assert ms.provenance(study.replace({"striker.drop_height_m": 7.2e-3})) == \
        ms.provenance(study)


def test_spellings_api_keywords_numpy_and_chained():
    study = load_study(MSS)
    a = study.replace({"electronics.cable_capacitance_F": 2e-10})
    b = study.replace(**{"electronics.cable_capacitance_F": np.float64(2e-10)})
    c = ms.replace(study, {"electronics.cable_capacitance_F": 2e-10})
    assert a == b == c
    d = a.replace({"sensor[2].coil.turns": np.int64(1200)})  # a replaced study replaces again
    assert d.electronics.cable_capacitance_f == 2e-10
    assert d.setups[0].sensors[1].coil.turns == 1200


def test_nested_setup_keys_and_new_tables():
    study = load_study(builtin_study_path(PAPER_TABLE2))
    changed = study.replace({"setup[3].precompression[1].force_N": 2.5,
                             "setup[1].sensor[2].particle": 17,
                             "electronics.johnson_noise": True})
    assert changed.setup("mss").precompression[0].force_n == 2.5
    assert changed.setup("bead").sensors[1].particle == 17
    assert changed.electronics.johnson_noise is True
    # a table the file leaves out is created
    coil = load_study(MSS).replace({"sensor[1].magnet.remanence_T": 0.4,
                                    "sensor[1].magnet.recoil_permeability": 1.1,
                                    "sensor[1].magnet.grade": None})
    assert coil.setups[0].sensors[0].magnet.remanence_t == 0.4


def test_none_removes_a_key():
    study = load_study(MSS)
    with pytest.raises(InputError, match=r"'striker.drop_height_m' or "
                                         r"'striker.velocity_m_per_s': give exactly one"):
        study.replace({"striker.velocity_m_per_s": 0.4})
    fast = study.replace({"striker.drop_height_m": None, "striker.velocity_m_per_s": 0.4})
    assert fast.striker.velocity_m_per_s == 0.4 and fast.striker.drop_height_m is None


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        # from the validation, exactly as for a file
        ({"striker.drop_heigth_m": 0.01}, r"with striker.drop_heigth_m=0.01: unknown key "
                                          r"'striker.drop_heigth_m'; allowed keys here"),
        ({"strikr.drop_height_m": 0.01}, r"unknown key 'strikr'"),
        ({"striker.drop_height_m": -0.01}, r"'striker.drop_height_m' must be >= 1e-06, got -0.01"),
        ({"sensor[1].coil.turns": 0}, r"'sensor\[1\].coil.turns' must be >= 1, got 0"),
        ({"sensor[1].coil.turns": 900.5}, r"'sensor\[1\].coil.turns' must be an integer"),
        ({"chain.beads": "many"}, r"'chain.beads' must be an integer"),
        ({"sensor[2].particle": 40}, r"'sensor\[2\].particle' must be a particle from 3 to 30"),
        # from the key itself
        ({"sensor[0].coil.turns": 900}, r"replace key 'sensor\[0\].coil.turns': the study has "
                                        r"2 \[\[sensor\]\] table\(s\), sensor\[1\] to "
                                        r"sensor\[2\], not sensor\[0\] \(indices count from 1"),
        ({"sensor[3].coil.turns": 900}, r"not sensor\[3\]"),
        ({"sensor.coil.turns": 900}, r"'sensor' is an array of 2 table\(s\): give an index"),
        ({"striker[1].drop_height_m": 1}, r"'striker' is not an array of tables"),
        ({"striker.drop_height_m.x": 1}, r"'striker.drop_height_m' is a value \(0.0072\), "
                                         r"not a table"),
        ({"chain..beads": 3}, r"replace key 'chain..beads': bad part ''"),
        ({"chain.colour": None}, r"nothing to remove, 'chain.colour' is not in the study"),
        ({"chain.beads": object()}, r"is not a TOML value"),
        ({"sensor[1]": 5}, r"a \[\[sensor\]\] table is replaced by a dict"),
    ],
)
def test_bad_changes_name_the_key(changes, message):
    with pytest.raises(InputError, match=message):
        load_study(MSS).replace(changes)


def test_only_studies_read_from_toml_can_be_replaced():
    study = dataclasses.replace(load_study(MSS), name="x")
    with pytest.raises(InputError, match=r"study 'x' was not read from a study file"):
        study.replace({"chain.beads": 20})


def test_a_pickled_study_keeps_its_document():
    study = pickle.loads(pickle.dumps(load_study(MSS)))
    assert study.replace({"chain.beads": 28}).chain.beads == 28


def test_relative_measurement_file_keeps_its_folder(tmp_path):
    (tmp_path / "data.csv").write_text("x")
    text = MSS.read_text() + '\n[measurement]\nfile = "data.csv"\n'
    (tmp_path / "s.toml").write_text(text)
    study = load_study(tmp_path / "s.toml").replace({"chain.beads": 29})
    assert study.measurement_file == tmp_path / "data.csv"

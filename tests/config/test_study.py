"""Study parsing: valid files load into typed values; every bad input names its key."""

from __future__ import annotations

import math

import pytest

from msens.chain.model import DampingLaw as Damping
from msens.config.schema import PAPER_TABLE2
from msens.config.study import (
    builtin_study_path,
    default_study_path,
    load_study,
    parse_study,
)
from msens.errors import InputError
from msens.readout.sensors import SensorKind

MINIMAL = """
schema = "msens.study/1"
name = "t"
[chain]
beads = 10
[striker]
drop_height_m = 0.0072
[[sensor]]
kind = "bead"
particle = 5
"""


def test_default_study_is_the_physics_mss():
    s = load_study(default_study_path())
    assert s.name == "paper-mss"
    assert [x.particle for x in s.setups[0].sensors] == [13, 18]


def test_table2_study_loads_three_setups():
    s = load_study(builtin_study_path(PAPER_TABLE2))
    assert [x.name for x in s.setups] == ["bead", "rod", "mss"]
    assert s.striker.velocity_m_per_s == pytest.approx(math.sqrt(2 * 9.80665 * 0.0072))
    assert s.chain.n_particles == 30
    assert s.dissipation_fit.ar_top == 0.55
    assert len(s.reference) == 6
    mss = s.setup("mss")
    assert [(p.first, p.last, p.force_n) for p in mss.precompression] == [(11, 14, 1.8),
                                                                         (16, 19, 1.8)]


@pytest.mark.parametrize("name", ["paper-table2", "paper-mss"])
def test_studies_folder_copy_matches_builtin(pytestconfig, name):
    root = pytestconfig.rootpath
    builtin = builtin_study_path(name)
    assert (root / "studies" / f"{name}.toml").read_text() == builtin.read_text()
    load_study(builtin)


def test_minimal_study_defaults():
    s = parse_study(MINIMAL)
    assert s.chain.damping is Damping.LINEAR
    assert s.setups[0].sensors[0].kind is SensorKind.BEAD
    assert s.setups[0].name == "t"


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        (("beads = 10", "beads = 10\nbead_mass_kg = -1.0"), "chain.bead_mass_kg"),
        (("particle = 5", "particle = 0"), "sensor[1].particle"),
        (("particle = 5", "particle = 12"), "sensor[1].particle"),
        (("beads = 10", "beads = 10\nbead_colour = 'red'"), "unknown key 'chain.bead_colour'"),
        (("beads = 10", "beads = 'ten'"), "chain.beads' must be an integer"),
        (("drop_height_m = 0.0072", "drop_height_m = 0.0072\nvelocity_m_per_s = 1.0"),
         "give exactly one"),
        (('kind = "bead"', 'kind = "laser"'), "sensor[1].kind"),
        (('schema = "msens.study/1"', 'schema = "msens.study/9"'), "schema"),
        (("particle = 5", "particle = 5\n[measurement]\nfile = 'nope.csv'"), "nope.csv"),
        (("beads = 10", "beads = 10\ndamping = 'viscous'"), "chain.damping"),
        (("particle = 5", "particle = 5\n[[precompression]]\ncontacts = [3, 1]\nforce_N = 1.0"),
         "precompression[1].contacts"),
    ],
)
def test_bad_input_names_the_key(edit, fragment):
    old, new = edit
    text = MINIMAL.replace(old, new, 1)
    assert text != MINIMAL
    with pytest.raises(InputError) as info:
        parse_study(text, source="s.toml")
    assert fragment in str(info.value)


def test_missing_file_named(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        load_study(tmp_path / "missing.toml")


def test_rod_sensor_requires_insert():
    text = MINIMAL.replace('kind = "bead"', 'kind = "rod"')
    with pytest.raises(InputError, match="needs an"):
        parse_study(text)


def test_bad_toml_reported():
    with pytest.raises(InputError, match="not valid TOML"):
        parse_study("schema = ", source="x.toml")

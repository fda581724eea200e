"""Sweep spec parsing and validation: every bad entry is named (InputError -> exit 2)."""

from __future__ import annotations

import pytest

from msens.cli import main
from msens.config.study import load_study
from msens.design.sweep import base_geometry, parse_sweep, validate_designs
from msens.errors import InputError

HEAD = 'schema = "msens.sweep/1"\nname = "t"\n'


def test_ranges_lists_scalars_and_design_order():
    spec = parse_sweep(HEAD + """
[coil]
turns = [600, 1100]
length_m = { start = 5e-3, stop = 7e-3, num = 3 }
wire = "awg36"
[magnet]
radial_gap_m = { start = 0.0, stop = 1e-3, step = 0.5e-3 }
""")
    assert spec.kind == "magnet"
    assert dict(spec.axes)["coil.length_m"] == (5e-3, 6e-3, 7e-3)
    assert dict(spec.axes)["coil.wire"] == ("AWG36",)
    assert dict(spec.axes)["magnet.radial_gap_m"] == (0.0, 0.5e-3, 1e-3)
    designs = spec.designs()
    assert len(designs) == 2 * 3 * 1 * 3
    assert designs[1].values == (("coil.turns", 600), ("coil.length_m", 5e-3),
                                 ("coil.wire", "AWG36"), ("magnet.radial_gap_m", 0.5e-3))
    assert [d.index for d in designs] == list(range(18))


def test_coil_only_is_a_coil_sweep():
    assert parse_sweep(HEAD + "[coil]\nturns = [1, 2]\n").kind == "coil"


def test_model_contact_map_overrides_the_study():
    """``[model] contact_map``: absent follows the study; a boolean overrides it; anything
    else is named."""
    body = "[magnet]\ngrade = ['N38']\n"
    assert parse_sweep(HEAD + body).contact_map is None
    assert parse_sweep(HEAD + body + "[model]\ncontact_map = false\n").contact_map is False
    assert parse_sweep(HEAD + body + "[model]\ncontact_map = true\n").contact_map is True
    with pytest.raises(InputError, match="contact_map"):
        parse_sweep(HEAD + body + "[model]\ncontact_map = 'no'\n")


def test_model_verify_needs_a_screening_magnet_sweep():
    """``[model] verify``: the number of best screened designs evaluated again with the
    contact maps; only in a magnet sweep that screens without them."""
    body = "[magnet]\ngrade = ['N38', 'ceramic8']\n[model]\n"
    assert parse_sweep(HEAD + body + "contact_map = false\n").verify == 0
    assert parse_sweep(HEAD + body + "contact_map = false\nverify = 2\n").verify == 2
    assert parse_sweep(HEAD + body + "contact_map = false\nverify = 9\n").verify == 9  # all
    assert parse_sweep(HEAD + body + 'contact_map = false\nverify = "auto"\n').verify == "auto"
    for extra, words in (("verify = 1\n", "contact_map = false"),
                         ("contact_map = true\nverify = 1\n", "contact_map = false"),
                         ("contact_map = false\nverify = -1\n", ">= 0"),
                         ("contact_map = false\nverify = 1.5\n", "integer"),
                         ('contact_map = false\nverify = "all"\n', "'auto'"),
                         ('verify = "auto"\n', "contact_map = false")):
        with pytest.raises(InputError, match=r"model\.verify") as info:
            parse_sweep(HEAD + body + extra)
        assert words in str(info.value)
    with pytest.raises(InputError, match="magnet sweeps"):
        parse_sweep(HEAD + "[coil]\nturns = [1, 2]\n[model]\ncontact_map = false\n"
                           "verify = 1\n")


@pytest.mark.parametrize("body, words", [
    ("[coil]\nturns = []\n", ["coil.turns", "empty range"]),
    ("[coil]\nturns = { start = 400, stop = 1200, step = 5e-324 }\n",
     ["coil.turns", "more than"]),
    ("[coil]\nlength_m = { start = 5e-3, stop = 4e-3, step = 1e-3 }\n",
     ["coil.length_m", "empty range"]),
    ("[coil]\nlength_m = { start = 5e-3, stop = 6e-3, num = 0 }\n", ["empty range"]),
    ("[coil]\ndiameter_m = [1e-3]\n", ["coil.diameter_m", "not a sweep parameter"]),
    ("[magnet]\ncolour = ['red']\n", ["magnet.colour", "not a sweep parameter"]),
    ("[coil]\nturns = [100, -5]\n", ["coil.turns[1]", "out of range"]),
    ("[coil]\ninner_radius_m = 2.0\n", ["coil.inner_radius_m", "out of range"]),
    ("[coil]\nwire = ['AWG99']\n", ["coil.wire", "AWG30"]),
    ("[magnet]\ngrade = ['N52x']\n", ["magnet.grade", "unknown magnet grade"]),
    ("[coil]\nturns = [1.5]\n", ["coil.turns", "integer"]),
    ("", ["varies nothing"]),
    ("[coil]\nturns = [1, 1]\n", ["twice"]),
])
def test_bad_specs_name_the_entry(body, words):
    with pytest.raises(InputError) as err:
        parse_sweep(HEAD + body)
    for w in words:
        assert w in str(err.value)


def test_overlapping_design_is_named():
    study = load_study("studies/paper-mss.toml")
    spec = parse_sweep(HEAD + "sensor = 13\n[coil]\nturns = [1100, 3000]\n")
    with pytest.raises(InputError) as err:
        validate_designs(base_geometry(study), 13, spec.designs(), "s.toml")
    msg = str(err.value)
    assert "design 1 (turns=3000)" in msg and "overlap" in msg and "coil_13" in msg


def test_cli_bad_sweep_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(HEAD + "[coil]\nturns = []\n")
    code = main(["design", "studies/paper-mss.toml", "--sweep", str(bad), "--out",
                 str(tmp_path / "o")])
    assert code == 2
    err = capsys.readouterr().err
    assert "coil.turns" in err and "empty range" in err
    bad.write_text(HEAD + "sensor = 14\n[coil]\nturns = [5]\n")
    assert main(["design", "studies/paper-mss.toml", "--sweep", str(bad), "--out",
                 str(tmp_path / "o")]) == 2
    assert "not an MsS sensor" in capsys.readouterr().err

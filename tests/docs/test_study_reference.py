"""The study-file reference of the docs is generated from the readers and the schema: every
key a study file can hold is in it, with a unit and a description (docs/_ext/studyref.py)."""

from __future__ import annotations

import importlib.util
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def studyref():
    spec = importlib.util.spec_from_file_location("studyref", ROOT / "docs" / "_ext" /
                                                  "studyref.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["studyref"] = module  # dataclasses resolve their module by name
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop("studyref", None)


@pytest.fixture(scope="module")
def keys(studyref):
    return studyref.reference(ROOT)


def test_every_key_has_a_unit_and_a_description(studyref, keys):
    """A key added to a reader without an ``Attributes`` entry (with its unit: an SI suffix
    in its name or a ``Unit: ...`` sentence) in the record it fills fails here."""
    assert len(keys) > 60
    assert studyref.missing(keys) == []


def test_the_check_catches_an_undocumented_key(studyref, keys):
    bare = studyref.Key(table="chain", name="bead_colour", kind="string")
    studyref._describe(bare)  # no Attributes entry names it
    assert studyref.missing([bare]) == ["chain.bead_colour (no unit) (no description)"]
    assert studyref.missing([k for k in keys if k.name == "turns"]) == []


def test_every_key_a_reader_asks_for_is_in_the_reference(studyref, keys):
    """The probe documents take every branch of the readers: each key name in their source is
    in the reference (a new branch the probes miss fails here)."""
    listed = {k.name for k in keys} | {k.name for k in studyref.tables(ROOT)}
    assert studyref.reader_keys() - listed == set()


def _toml_keys(doc: dict, table: str = "") -> set[str]:
    out = set()
    for name, value in doc.items():
        dotted = f"{table}.{name}" if table else name
        if isinstance(value, dict):
            out |= _toml_keys(value, dotted)
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                out |= _toml_keys(item, dotted + "[]")
        else:
            out.add(dotted)
    return out


@pytest.mark.parametrize("path", ["studies/paper-mss.toml", "studies/paper-table2.toml",
                                  "tests/data/tiny-mss.toml"])
def test_every_key_of_the_shipped_studies_is_documented(keys, path):
    dotted = {k.dotted for k in keys}
    used = _toml_keys(tomllib.loads((ROOT / path).read_text()))
    assert used - dotted == set()


def test_the_page_lists_every_key_with_its_unit(studyref, keys, tmp_path):
    page = studyref.write_rst(ROOT, tmp_path / "study-reference.rst").read_text()
    for key in keys:
        if not key.table.startswith("setup[]."):  # shown once, under the top-level tables
            assert f"``{key.name}``" in page, key.dotted
    assert "kg/(s m^0.5)" in page and "(undocumented)" not in page


def test_every_sweep_key_has_a_unit_and_a_description(studyref, tmp_path):
    """The sweep-file reference (msens.sweep/1): every parameter of COIL_PARAMETERS and
    MAGNET_PARAMETERS and every key the reader asks for is documented, with a unit."""
    import importlib

    sweep = importlib.import_module("msens.design.sweep")
    keys = studyref.sweep_reference()
    assert studyref.missing(keys) == []
    dotted = {k.dotted for k in keys}
    assert {f"coil.{n}" for n in sweep.COIL_PARAMETERS} <= dotted
    assert {f"magnet.{n}" for n in sweep.MAGNET_PARAMETERS} <= dotted
    assert {"model.verify", "recommend.min_bandwidth_Hz", "sensor"} <= dotted
    page = studyref.write_sweep_rst(tmp_path / "sweep-reference.rst").read_text()
    assert "``radial_gap_m``" in page and "(undocumented)" not in page


@pytest.mark.parametrize("path", ["studies/sweep-coil.toml", "studies/sweep-magnet.toml"])
def test_every_key_of_the_shipped_sweeps_is_documented(studyref, path):
    dotted = {k.dotted for k in studyref.sweep_reference()}
    doc = tomllib.loads((ROOT / path).read_text())
    used = {f"{t}.{k}" if isinstance(v, dict) and t in ("coil", "magnet", "model",
                                                          "recommend") else t
            for t, v in doc.items() for k in (v if isinstance(v, dict) else [None])}
    assert used - dotted == set()

"""Conventions shared by the msens sub-commands (issue 37, item 4).

``--set KEY=VALUE`` on every command that takes a study, validated like the file; a study
written back to TOML (``msens study``) that reads back equal; ``--overwrite`` for output
files; ``--out`` defaults; the same default study for ``run`` and ``diagnose``; help with a
description and an example for every sub-command; cheap checks before any work; a typo of
a required key named.
"""

from __future__ import annotations

import dataclasses
import time
import tomllib

import numpy as np
import pytest

from msens.cli import BUILTIN_STUDIES, _parser, main, parse_sets
from msens.config.dump import format_toml, study_toml
from msens.config.study import builtin_study_path, load_study, parse_study
from msens.errors import InputError

STUDY_COMMANDS = ("run", "study", "field", "synth", "compare", "diagnose", "design")


def _equal(a, b) -> bool:
    return dataclasses.replace(a, source="") == dataclasses.replace(b, source="")


def _no_simulation(monkeypatch):
    """Fail the test if anything is simulated or solved."""
    def boom(*args, **kwargs):
        raise AssertionError("work started before the cheap checks")

    from msens import pipeline

    for workflow in ("run", "synth", "compare"):  # each workflow's own reference
        monkeypatch.setattr(f"msens.workflows.{workflow}.run_study", boom)
    monkeypatch.setattr(pipeline, "simulate", boom)


# --- --set -------------------------------------------------------------------------------


def test_parse_sets_keys_and_values():
    got = parse_sets(["striker.drop_height_m=0.01", "sensor.1.coil.turns=900",
                      "setup[2].sensor.1.coil.wire=AWG34", "field.contact_map=false",
                      "name = my study", "x.y=[1, 2]", "t={ grade = \"N42\" }",
                      "s=\"quoted\""])
    assert got == {"striker.drop_height_m": 0.01, "sensor[1].coil.turns": 900,
                   "setup[2].sensor[1].coil.wire": "AWG34", "field.contact_map": False,
                   "name": "my study", "x.y": [1, 2], "t": {"grade": "N42"}, "s": "quoted"}


@pytest.mark.parametrize(("items", "fragment"), [
    (["striker.drop_height_m"], "--set 'striker.drop_height_m': expected KEY=VALUE"),
    (["=1"], "--set '=1': expected KEY=VALUE"),
    (["a.b=1", "a.b=2"], "--set a.b given twice"),
    (["sensor.1.coil.turns=1", "sensor[1].coil.turns=2"], "--set sensor[1].coil.turns given twice"),
])
def test_parse_sets_rejects(items, fragment):
    import re

    with pytest.raises(InputError, match="^" + re.escape(fragment)):
        parse_sets(items)


def test_every_study_command_takes_set():
    parser = _parser()
    needs = {"compare": ["s.toml", "d.csv"], "design": ["--sweep", "w.toml"]}
    for command in STUDY_COMMANDS:
        args = parser.parse_args([command, *needs.get(command, []), "--set", "a.b=1",
                                  "--set", "c=2"])
        assert args.sets == ["a.b=1", "c=2"], command


@pytest.mark.parametrize(("setting", "fragments"), [
    ("chain.colour=1", ["unknown key 'chain.colour'"]),
    ("striker.drop_heigth_m=0.01", ["unknown key 'striker.drop_heigth_m'"]),
    ("sensor.1.coil.turns=-9", ["'sensor[1].coil.turns' must be >= 1, got -9"]),
    ("sensor.3.coil.turns=9", ["sensor[1] to sensor[2], not sensor[3]"]),
    ("striker.drop_height_m=1cm", ["'striker.drop_height_m' must be a number", "'1cm'"]),
    ("nonsense", ["--set 'nonsense': expected KEY=VALUE"]),
])
@pytest.mark.parametrize("command", ["run", "synth", "study"])
def test_bad_set_exits_2_naming_the_key_before_any_work(monkeypatch, capsys, tmp_path,
                                                         command, setting, fragments):
    _no_simulation(monkeypatch)
    out = tmp_path / ("o.csv" if command == "synth" else "o")
    args = [command, "--set", setting] + ([] if command == "study" else ["--out", str(out)])
    assert main(args) == 2
    err = capsys.readouterr().err
    assert all(f in err for f in fragments), err
    assert "Traceback" not in err and err.count("msens: error") == 1


def test_set_changes_what_runs(monkeypatch, tmp_path):
    seen = {}

    def fake_run(study, **kwargs):
        seen["study"] = study
        raise InputError("stop here")

    from msens import api

    monkeypatch.setattr(api, "run", fake_run)
    assert main(["run", "paper-table2", "--set", "striker.drop_height_m=0.01", "--set",
                 "setup.3.sensor.1.coil.turns=900", "--out", str(tmp_path / "o")]) == 2
    study = seen["study"]
    assert study.striker.drop_height_m == 0.01
    assert study.setups[2].sensors[0].coil.turns == 900
    assert "with striker.drop_height_m=0.01" in study.source


# --- a study written back to TOML ---------------------------------------------------------


@pytest.mark.parametrize("name", BUILTIN_STUDIES)
def test_study_toml_round_trip(name):
    study = load_study(builtin_study_path(name))
    again = parse_study(study_toml(study), source="dumped")
    assert _equal(again, study)
    changed = study.replace({"striker.drop_height_m": 0.011})
    back = parse_study(study_toml(changed), source="dumped")
    assert _equal(back, changed) and not _equal(back, study)
    assert study_toml(back).split("\n", 1)[1] == study_toml(changed).split("\n", 1)[1]


def test_study_toml_header_stays_a_comment():
    """The header names the study and its source: one comment line whatever they hold (a
    name cannot hold a line break, a source can)."""
    text = builtin_study_path("paper-table2").read_text()
    study = parse_study(text, source="two\nlines\r") \
        .replace({"name": "rig #2 \u00e9t\u00e9 'x'"})
    dumped = study_toml(study)
    assert dumped.startswith("# msens study ") and "\r" not in dumped.split("\n", 1)[0]
    assert _equal(parse_study(dumped, source="dumped"), study)


def test_format_toml_round_trips_awkward_documents():
    doc = {"schema": "x/1", "plain": 1, "float": 1e-300, "big": 2.0**70, "neg": -0.0,
           "inf": float("inf"), "whole": 3.0, "text": "quote \" backslash \\ tab\t nl\n \x7f é",
           "a key": True, "list": [1.5, "two", [3]], "empty": [], "table": {},
           "nested": {"deep": {"x": 1}, "arr": [{"a": 1, "sub": {"b": 2}}, {"a": 2}]},
           "mixed": [{"a": 1}, 2]}
    assert tomllib.loads(format_toml(doc)) == doc


def test_cli_study_prints_saves_and_refuses_to_overwrite(tmp_path, capsys):
    assert main(["study", "paper-table2", "--set", "striker.drop_height_m=0.009"]) == 0
    text = capsys.readouterr().out
    assert "drop_height_m = 0.009" in text
    path = tmp_path / "s.toml"
    assert main(["study", "--set", "sensor.1.coil.turns=900", "--out", str(path)]) == 0
    capsys.readouterr()
    saved = load_study(path)
    assert saved.setups[0].sensors[0].coil.turns == 900
    expected = load_study(builtin_study_path("paper-mss")).replace(
        {"sensor[1].coil.turns": 900})
    assert _equal(saved, expected)
    before = path.read_text()
    assert main(["study", "--out", str(path)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert path.read_text() == before
    assert main(["study", "--out", str(path), "--overwrite"]) == 0
    assert load_study(path).setups[0].sensors[0].coil.turns == 1100
    assert main(["study", "--out", str(tmp_path / "s.json")]) == 2
    assert "unknown file type '.json'" in capsys.readouterr().err


# --- --overwrite, early refusals ------------------------------------------------------------


def _waveform_file(path):
    from msens.io.read import write_waveform
    from msens.io.waveform import Channel, Waveform

    write_waveform(Waveform(np.arange(50) * 1e-7, np.zeros((50, 1)), (Channel("bead", 13),),
                            {}), path)
    return path


def test_convert_overwrite(tmp_path, capsys):
    src = _waveform_file(tmp_path / "a.csv")
    target = tmp_path / "b.npz"
    target.write_bytes(b"mine")
    assert main(["convert", str(src), str(target)]) == 2
    err = capsys.readouterr().err
    assert "file exists" in err and "--overwrite" in err and "overwrite=True" not in err
    assert target.read_bytes() == b"mine"
    assert main(["convert", str(src), str(target), "--overwrite"]) == 0
    assert main(["check-waveform", str(target)]) == 0


def test_convert_refuses_a_bad_target_before_reading(tmp_path, capsys, monkeypatch):
    import msens.io.read as read

    monkeypatch.setattr(read, "read_waveform", lambda *a, **k: pytest.fail("read first"))
    assert main(["convert", str(tmp_path / "missing.csv"), str(tmp_path / "b.xlsx")]) == 2
    assert "unknown file type '.xlsx'" in capsys.readouterr().err


@pytest.mark.parametrize(("out", "fragment"), [
    ("x.xlsx", "unknown file type '.xlsx'"),
    ("exists.csv", "--overwrite"),
    ("nofolder/x.csv", ""),
])
def test_synth_refuses_bad_output_at_once(tmp_path, capsys, monkeypatch, out, fragment):
    _no_simulation(monkeypatch)
    (tmp_path / "exists.csv").write_text("mine")
    (tmp_path / "nofolder").write_text("a file where a folder should be")
    start = time.perf_counter()
    assert main(["synth", "paper-table2", "--out", str(tmp_path / out)]) == 2
    assert time.perf_counter() - start < 30  # no simulation (a study load at most)
    err = capsys.readouterr().err
    assert fragment in err and err.count("msens: error") == 1
    assert (tmp_path / "exists.csv").read_text() == "mine"


def test_synth_overwrite_replaces_its_file(tmp_path, monkeypatch, capsys):
    from types import SimpleNamespace

    from msens import api

    calls = []

    def fake_synth(study, out, **kw):  # the command prints what its result's table says
        calls.append((out, kw))
        return SimpleNamespace(table=lambda: f"wrote {out}")

    monkeypatch.setattr(api, "synth", fake_synth)
    target = tmp_path / "w.csv"
    target.write_text("old")
    assert main(["synth", "paper-table2", "--out", str(target), "--overwrite"]) == 0
    assert calls[0][0] == target and calls[0][1]["overwrite"] is True
    assert capsys.readouterr().out == f"wrote {target}\n"


# --- defaults -------------------------------------------------------------------------------


@pytest.mark.parametrize(("command", "extra", "expected"), [
    ("field", [], "out/paper-mss-field"),
    ("compare", ["data.csv"], "out/paper-table2-compare"),
    ("diagnose", ["--reference", "bead"], "out/paper-table2-diagnose"),
    ("design", ["--sweep", "w.toml"], "out/paper-mss-design"),
])
def test_out_defaults_follow_the_study_and_command(monkeypatch, tmp_path, command, extra,
                                                   expected):
    from pathlib import Path

    from msens import api

    seen = {}

    def capture(study, *args, **kwargs):
        seen["args"] = args
        raise InputError("stop here")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(api, command, capture)
    monkeypatch.setattr("msens.cli._data", lambda path, columns: Path(path))
    study = "paper-mss" if command in ("field", "design") else "paper-table2"
    argv = {"compare": ["compare", study, *extra],
            "diagnose": ["diagnose", "--study", study, *extra]}.get(command,
                                                                  [command, study, *extra])
    assert main(argv) == 2
    assert Path(expected) in seen["args"]


def test_diagnose_defaults_to_the_run_study(monkeypatch, tmp_path):
    from msens import api

    seen = {}

    def capture(study, data, out, **kwargs):
        seen["study"], seen["out"] = study.name, out
        raise InputError("stop here")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(api, "diagnose", capture)
    assert main(["diagnose", "--reference", "paper-mss"]) == 2
    assert seen["study"] == load_study(builtin_study_path("paper-mss")).name == "paper-mss"
    assert str(seen["out"]) == "out/paper-mss-diagnose"


# --- help -----------------------------------------------------------------------------------


def test_every_subcommand_has_a_description_and_an_example():
    import argparse

    parser = _parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, command in sub.choices.items():
        text = command.format_help()
        assert command.description and len(command.description) > 80, name
        assert "examples:" in text and f"  msens {name}" in text, name
        assert "  " + name in parser.format_help()  # listed with its one-line help


# --- a typo of a required key ---------------------------------------------------------------


def test_a_typo_of_a_required_key_is_named(tmp_path, capsys):
    text = builtin_study_path("paper-table2").read_text()
    path = tmp_path / "s.toml"
    path.write_text(text.replace("drop_height_m", "drop_heigth_m", 1))
    assert main(["study", str(path)]) == 2
    err = capsys.readouterr().err
    assert "unknown key 'striker.drop_heigth_m'" in err
    assert "'striker.drop_height_m' or 'striker.velocity_m_per_s'" in err
    path.write_text(text.replace("name = ", "nmae = ", 1))
    assert main(["study", str(path)]) == 2
    err = capsys.readouterr().err
    assert "'name' is missing (unknown key 'nmae' given)" in err

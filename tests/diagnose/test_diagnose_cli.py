"""``msens diagnose``: a run end to end, the feature-only mode, and bad input (exit 2)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from msens.cli import main
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, load_study
from msens.diagnose.effects import Context
from msens.diagnose.hidden import hidden_case
from msens.diagnose.predict import Predictor, baseline_state
from msens.io.read import write_waveform
from msens.io.waveform import Waveform
from msens.pipeline import output_times


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """A bead-setup measurement whose wall is aluminium-like (70 GPa)."""
    study = load_study(builtin_study_path(PAPER_TABLE2))
    ctx = Context(study, study.setup("bead"))
    from msens.pipeline import calibrate_dissipation

    fit = calibrate_dissipation(study, output_times(study))
    base = baseline_state(ctx, fit.gamma_c, fit.gamma_w)
    wf, _ = hidden_case(ctx, base, Predictor(output_times(study)),
                        {"wall_stiffness": {"wall_youngs_modulus_pa": 70e9}}, seed=21)
    d = tmp_path_factory.mktemp("data")
    path = d / "shot.csv"
    write_waveform(wf, path)
    dead = np.array(wf.data)
    dead[:, :] = np.random.default_rng(1).normal(0.0, 1e-4, dead.shape)
    write_waveform(Waveform(time=wf.time, data=dead, channels=wf.channels), d / "dead.csv")
    # two shots, the second without its bead@18 channel
    two = Waveform(time=wf.time, data=np.column_stack([wf.data, wf.data[:, 0]]),
                   channels=(*wf.channels, type(wf.channels[0])("bead", 13, 2)))
    write_waveform(two, d / "lacking.csv")
    # two shots, the second shorter (its cells empty at the end)
    text = (d / "shot.csv").read_text().splitlines()
    head = next(i for i, line in enumerate(text) if line.startswith("time_s"))
    rows = [text[head] + ",bead@13#2,bead@18#2"]
    for k, line in enumerate(text[head + 1:]):
        cells = line.split(",")
        rows.append(line + ("," + ",".join(cells[1:]) if k < 5000 else ",,"))
    (d / "ragged.csv").write_text("\n".join(text[:head] + rows) + "\n")
    return d


def test_diagnose_names_the_soft_wall(data, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["diagnose", str(data / "shot.csv"), "--study", "paper-table2", "--out",
                 str(out)]) == 0
    report = json.loads((out / "diagnosis.json").read_text())
    assert report["effect"] == "wall_stiffness"
    assert report["parameters"]["wall_youngs_modulus_pa"] == pytest.approx(70e9, rel=0.15)
    assert report["misfit_after"] < report["misfit_before"]
    assert report["candidates"][0]["effect"] == "wall_stiffness"
    assert report["explained"] is True
    assert (out / "diagnosis.png").exists()
    assert "wall_stiffness" in capsys.readouterr().out


def test_feature_only_mode_on_table2(tmp_path):
    out = tmp_path / "t2"
    assert main(["diagnose", "--study", "paper-table2", "--reference", "bead", "--out",
                 str(out)]) == 0
    report = json.loads((out / "diagnosis.json").read_text())
    assert report["mode"] == "features" and report["n_observations"] == 4
    assert report["misfit_after"] <= report["misfit_before"]
    assert {c["effect"] for c in report["candidates"]} >= {"striker_velocity", "wall_stiffness"}


@pytest.mark.parametrize("args", [
    ["diagnose", "{data}/dead.csv"],  # no usable channel
    ["diagnose", "{data}/shot.csv", "--study", "{data}/rods.toml"],  # sensors do not match
    ["diagnose", "{data}/shot.csv", "--reference", "bead"],  # both modes
    ["diagnose"],  # neither
    ["diagnose", "--reference", "nosuch"],
    ["diagnose", "{data}/missing.csv"],
    ["diagnose", "{data}/lacking.csv"],  # a channel missing in one shot
    ["diagnose", "{data}/ragged.csv"],  # shots of different lengths
])
def test_bad_input_exits_2(data, tmp_path, args, capsys):
    text = builtin_study_path(PAPER_TABLE2).read_text()
    # a study whose only setup has rods at 13 and 18: bead data do not match it
    parts = text.split("[[setup]]")  # header, bead, rod, mss (+ calibration, reference)
    (data / "rods.toml").write_text(parts[0] + "[[setup]]" + parts[2])
    argv = [a.format(data=data) for a in args] + ["--out", str(tmp_path / "o")]
    if "--study" not in argv:  # the bead setups (the default study is the MsS one)
        argv += ["--study", "paper-table2"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "msens: error:" in err and "Traceback" not in err
    if "lacking" in args[-1]:
        assert "shot #2" in err and "bead@18" in err
    if "ragged" in args[-1]:
        assert "bead@13#2" in err

"""Every workflow's typed result: ``to_json()`` is the JSON file the workflow wrote,
``table()`` the text the command printed, ``figures`` the figures written.

Each command runs once with its API function wrapped, so the result it printed is the one
checked (tiny study; the feature-only diagnosis of the paper's Table 2)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from tests.design.test_design_cli import TINY_COIL
from tests.uq.test_propagate import CHAIN_INPUTS

import msens
from msens import api
from msens.cli import main
from msens.io.read import read_waveform

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "tests" / "data" / "tiny-mss.toml"


def _spy(monkeypatch, name: str) -> list:
    """Wrap ``msens.api.<name>``: the results the command got, in order."""
    real, seen = getattr(api, name), []

    def wrapped(*args, **kwargs):
        seen.append(real(*args, **kwargs))
        return seen[-1]

    monkeypatch.setattr(api, name, wrapped)
    return seen


def _json(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def data(tmp_path_factory) -> msens.SynthResult:
    """Two synthetic shots of the tiny study (the API's synth)."""
    out = tmp_path_factory.mktemp("synth") / "data.csv"
    return api.synth(api.load(TINY), out, shots=2, seed=3)


def test_run_result_is_summary_json_and_the_printed_table(tmp_path, monkeypatch, capsys):
    seen = _spy(monkeypatch, "run")
    out = tmp_path / "run"
    assert main(["run", str(TINY), "--out", str(out), "--no-figures"]) == 0
    result = seen[0]
    assert isinstance(result, msens.StudyResult)
    assert result.to_json() == _json(out / "summary.json")
    assert capsys.readouterr().out == (f"{result.table()}\n\nwrote 1 files to {out}/: "
                                       "summary.json\n")
    assert result.table() == api.format_summary(result)


def test_synth_result_is_the_file(data):
    assert isinstance(data, msens.SynthResult)
    assert os.fspath(data) == str(data) == str(data.path) and data.path.is_file()
    assert data.table() == f"wrote {data.path}" and data.figures == ()
    waveform = read_waveform(data)  # path-like: it passes wherever the file does
    js = data.to_json()
    assert js["file"] == str(data.path) and js["shots"] == 2 and js["seed"] == 3
    assert js["samples"] == waveform.time.size
    assert tuple(js["channels"]) == tuple(c.name for c in waveform.channels)
    assert js["provenance"] == msens.summary(msens.run(api.load(TINY)))["provenance"]
    json.dumps(js)  # plain JSON values
    # code written when synth returned the path: its Path methods still work
    assert data.read_bytes() == data.path.read_bytes() and data.suffix == ".csv"


def test_synth_prints_its_table(tmp_path, monkeypatch, capsys):
    seen = _spy(monkeypatch, "synth")
    out = tmp_path / "w.csv"
    assert main(["synth", str(TINY), "--out", str(out)]) == 0
    assert capsys.readouterr().out == seen[0].table() + "\n" == f"wrote {out}\n"


def test_compare_result_is_compare_json_and_the_printed_table(data, tmp_path, monkeypatch,
                                                              capsys):
    seen = _spy(monkeypatch, "compare")
    out = tmp_path / "compare"
    assert main(["compare", str(TINY), str(data), "--out", str(out)]) == 0
    result = seen[0]
    assert isinstance(result, msens.CompareResult)
    assert result.to_json() == _json(out / "compare.json")
    assert capsys.readouterr().out == result.table() + "\n"
    assert result.table().startswith(api.format_comparison(result.to_json()) + "\n\nwrote ")
    assert result.figures == (out / "overlay.png",) and result.figures[0].is_file()
    assert result.files == (out / "compare.json", out / "overlay.png")
    result.to_json()["setup"] = "changed"  # a copy: the result stays as written
    assert result.to_json() == _json(out / "compare.json")


def test_field_result_is_field_json_and_the_printed_table(tmp_path, monkeypatch, capsys):
    seen = _spy(monkeypatch, "field")
    out = tmp_path / "field"
    assert main(["field", str(TINY), "--out", str(out)]) == 0
    result = seen[0]
    assert isinstance(result, msens.FieldResult)
    assert result.to_json() == _json(out / "field.json")
    assert capsys.readouterr().out == result.table() + "\n"
    assert result.table() == api.format_field(result.model, result.written,
                                              timings_s=result.timings_s)
    assert out / "field.json" in result.files and out / "field.vtu" in result.files
    assert out / "field_B.png" in result.figures
    assert all(p.is_file() for p in result.files)


def test_design_result_is_recommendation_json_and_the_printed_table(tmp_path, monkeypatch,
                                                                    capsys):
    (tmp_path / "sweep.toml").write_text(TINY_COIL)
    seen = _spy(monkeypatch, "design")
    out = tmp_path / "design"
    assert main(["design", str(TINY), "--sweep", str(tmp_path / "sweep.toml"), "--out",
                 str(out), "--workers", "1"]) == 0
    result = seen[0]
    assert isinstance(result, msens.DesignResult)
    assert result.to_json() == _json(out / "recommendation.json")
    assert capsys.readouterr().out == result.table() + "\n"
    assert result.table() == api.format_design(result)
    assert result.figures == (out / "pareto.png",)


def test_diagnose_result_is_diagnosis_json_and_the_printed_table(tmp_path, monkeypatch,
                                                                 capsys):
    seen = _spy(monkeypatch, "diagnose")
    out = tmp_path / "diagnose"
    assert main(["diagnose", "--study", "paper-table2", "--reference", "bead", "--out",
                 str(out)]) == 0
    result = seen[0]
    assert isinstance(result, msens.DiagnoseResult)
    assert result.to_json() == _json(out / "diagnosis.json")
    assert capsys.readouterr().out == result.table() + "\n"
    assert result.table().startswith(api.format_diagnosis(result.to_json()) + "\n\nwrote ")
    assert result.figures == (out / "diagnosis.png",)
    assert len(result.passes) == 1 and result.passes[0].effect == result.to_json()["effect"]


def test_uq_result_is_uq_json_and_the_printed_table(tmp_path, monkeypatch, capsys):
    import msens.uq

    seen = []
    real = msens.uq.run_uq
    monkeypatch.setattr(msens.uq, "run_uq", lambda *a, **k: seen.append(real(*a, **k))
                        or seen[-1])
    (tmp_path / "u.toml").write_text(CHAIN_INPUTS)
    out = tmp_path / "uq"
    assert main(["uq", "--inputs", str(tmp_path / "u.toml"), "--out", str(out), "--samples",
                 "4", "--workers", "1", "-q"]) == 0
    result = seen[0]
    assert result.to_json() == _json(out / "uq.json")
    assert capsys.readouterr().out == result.table() + "\n"
    assert {p.name for p in result.figures} == {"uq_waveforms.png", "uq_sobol.png"}


def test_calibrate_result_is_calibration_json_and_the_printed_table(tmp_path, monkeypatch,
                                                                    capsys):
    from benchmarks.calibrate_coverage import INPUTS, STUDY

    import msens.uq.calibration

    seen = []
    real = msens.uq.calibration.run_calibrate
    monkeypatch.setattr(msens.uq.calibration, "run_calibrate",
                        lambda *a, **k: seen.append(real(*a, **k)) or seen[-1])
    (tmp_path / "s.toml").write_text(STUDY)
    (tmp_path / "u.toml").write_text(INPUTS)
    data = api.synth(api.load(tmp_path / "s.toml"), tmp_path / "w.csv", seed=4)
    out = tmp_path / "cal"
    assert main(["calibrate", str(data), "--study", str(tmp_path / "s.toml"), "--inputs",
                 str(tmp_path / "u.toml"), "--param", "striker.drop_height_m", "--walkers",
                 "8", "--steps", "20", "--out", str(out), "-q"]) == 0
    result = seen[0]
    assert result.to_json() == _json(out / "calibration.json")
    assert capsys.readouterr().out == result.table() + "\n"
    assert result.figures and all(p.suffix == ".png" for p in result.figures)

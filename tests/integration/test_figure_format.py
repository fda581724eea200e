"""``--format png|pdf|svg``: one figure format for `msens run`, `field`, `compare`, `diagnose`
and `design`, at one resolution (:data:`msens.io.output.DPI`); ``summary.json`` is unaffected."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from msens import api, plots
from msens.cli import _parser, main
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path, default_study_path
from msens.design.report import pareto_plot
from msens.design.sweep import Design

MAGIC = {"png": b"\x89PNG", "pdf": b"%PDF", "svg": b"<?xml"}
TABLE2 = str(builtin_study_path(PAPER_TABLE2))


def _is(path, fmt: str) -> bool:
    return path.suffix == f".{fmt}" and path.read_bytes()[:5].startswith(MAGIC[fmt])


@pytest.mark.parametrize("command", [
    ["run"], ["field", "s.toml", "--out", "o"], ["compare", "s.toml", "d.csv", "--out", "o"],
    ["diagnose", "--reference", "bead", "--out", "o"],
    ["design", "s.toml", "--sweep", "w.toml", "--out", "o"]])
def test_every_figure_command_takes_the_formats(command):
    parser = _parser()
    assert parser.parse_args(command).fig_format == "png"
    for fmt in plots.FORMATS:
        assert parser.parse_args([*command, "--format", fmt]).fig_format == fmt


def test_unknown_format_exit_2(tmp_path, capsys):
    assert main(["run", "--format", "bmp", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--format" in err and "invalid choice" in err
    assert not (tmp_path / "o").exists()


def test_api_checks_the_format(tmp_path):
    from msens.errors import InputError

    with pytest.raises(InputError, match="--format must be one of png, pdf, svg"):
        api.prepare_outputs(tmp_path / "o", fig_format="jpg")


def test_run_figures_in_each_format_summary_unchanged(tmp_path):
    result = api.run(api.load(default_study_path()))
    written = {fmt: api.write_outputs(result, tmp_path / fmt, fig_format=fmt)
               for fmt in ("png", "svg")}
    names = {fmt: sorted(p.name for p in paths) for fmt, paths in written.items()}
    assert names["svg"] == sorted(n.replace(".png", ".svg") for n in names["png"])
    assert "magnetic_precompression.svg" in names["svg"] and "field_B.svg" in names["svg"]
    for fmt, paths in written.items():
        assert all(_is(p, fmt) for p in paths if p.name != "summary.json")
    assert (tmp_path / "png" / "summary.json").read_bytes() == \
        (tmp_path / "svg" / "summary.json").read_bytes()


def test_cli_diagnose_and_compare_write_the_chosen_format(tmp_path):
    out = tmp_path / "diag"
    assert main(["diagnose", "--study", "paper-table2", "--reference", "bead", "--out", str(out),
                 "--format", "pdf"]) == 0
    assert _is(out / "diagnosis.pdf", "pdf") and not (out / "diagnosis.png").exists()
    json.loads((out / "diagnosis.json").read_text())
    data = tmp_path / "shots.npz"
    assert main(["synth", TABLE2, "--out", str(data), "--setup", "rod"]) == 0
    out = tmp_path / "cmp"
    assert main(["compare", TABLE2, str(data), "--out", str(out), "--format", "svg"]) == 0
    assert _is(out / "overlay.svg", "svg")


def test_design_writes_the_chosen_format(tmp_path):
    from msens.design import files

    assert files("svg") == ("designs.csv", "pareto.svg", "recommendation.json")
    study = tmp_path / "study.toml"
    study.write_text((Path(__file__).parents[1] / "data" / "tiny-mss.toml").read_text())
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('schema = "msens.sweep/1"\nname = "t"\n[coil]\nturns = [600, 1100]\n')
    out = tmp_path / "o"
    assert main(["design", str(study), "--sweep", str(sweep), "--out", str(out),
                 "--format", "svg", "-q"]) == 0
    assert _is(out / "pareto.svg", "svg") and not (out / "pareto.png").exists()


@pytest.mark.parametrize("fmt", plots.FORMATS)
def test_pareto_plot_writes_its_suffix_format_reproducibly(tmp_path, fmt):
    rng = np.random.default_rng(0)
    designs = [Design(i, (("coil.turns", 600 + 100 * i),)) for i in range(6)]
    rows = [{"status": "ok", "snr": float(s), "precompression_N": 1.0,
             "bandwidth_Hz": float(b), "resonance_Hz": float(b) * 3}
            for s, b in zip(rng.uniform(1, 9, 6), rng.uniform(1e4, 9e4, 6), strict=True)]
    paths = [tmp_path / f"a.{fmt}", tmp_path / f"b.{fmt}"]
    for p in paths:
        pareto_plot(designs, rows, p, best=2)
    assert _is(paths[0], fmt)
    assert paths[0].read_bytes() == paths[1].read_bytes()

"""Feedback and install weight (issue 22, items 3 and 4).

- The library logs its stages (loggers ``msens.*``) and never prints; the command shows them
  on stderr as ``msens: ...`` lines and ``-q``/``--quiet`` silences them and the bars.
- pyvista (``msens[viz]``) and dask (``msens[cluster]``) are optional: without them the
  3-D field figure is skipped with a hint and ``--scheduler`` is one clear InputError.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from msens.cli import _parser, main
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path
from msens.errors import InputError

# the paper's three bead/rod/mss setups without the Eq. 10 fit, over a short window: ~1 s
FAST = builtin_study_path(PAPER_TABLE2).read_text().split("[calibration.dissipation]")[0] \
    .replace("t_end_s = 1.0e-3", "t_end_s = 5.0e-4")  # holds every reflection (issue 38)


def _fast_study(tmp_path):
    path = tmp_path / "fast.toml"
    path.write_text(FAST)
    return path


def test_run_logs_its_stages_on_stderr(tmp_path, capsys):
    assert main(["run", str(_fast_study(tmp_path)), "--out", str(tmp_path / "out"),
                 "--no-figures"]) == 0
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    for setup in ("bead", "rod", "mss"):
        assert any(line.startswith(f"msens: setup {setup}: simulating the chain")
                   for line in lines), captured.err
        assert any(line.startswith(f"msens: setup {setup}: simulated in") for line in lines)
    assert all(line.startswith("msens: ") for line in lines)  # nothing else on stderr
    assert "msens:" not in captured.out  # the results stay on stdout, the feedback off it


@pytest.mark.parametrize("where", ["before", "after"])
def test_quiet_silences_stderr(tmp_path, capsys, where):
    args = ["run", str(_fast_study(tmp_path)), "--out", str(tmp_path / "out"), "--no-figures"]
    args = ["--quiet", *args] if where == "before" else [*args, "-q"]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert captured.err == ""
    assert "setup" in captured.out  # the result table is still printed


def test_quiet_flag_before_or_after_the_command():
    parse = _parser().parse_args
    assert parse(["run"]).quiet is False
    assert parse(["-q", "run"]).quiet is True
    assert parse(["run", "--quiet"]).quiet is True
    assert parse(["--quiet", "verify"]).quiet is True


def test_main_leaves_the_logging_setup_as_it_found_it(tmp_path, capsys):
    log = logging.getLogger("msens")
    before = (list(log.handlers), log.level)
    main(["run", str(tmp_path / "missing.toml")])  # an input error: exit 2
    main(["-q", "check-waveform", str(tmp_path / "missing.csv")])
    capsys.readouterr()
    assert (list(log.handlers), log.level) == before


def test_library_code_does_not_print(tmp_path, capsys, caplog):
    """Without the command's handler the stages reach logging only (here: caplog)."""
    from msens import api

    with caplog.at_level(logging.INFO, logger="msens"):
        api.run(api.load(_fast_study(tmp_path)))
    assert capsys.readouterr().err == ""
    assert any("simulating the chain" in r.getMessage() for r in caplog.records)
    assert {r.name for r in caplog.records} >= {"msens.pipeline"}


def test_calibration_logs_and_counts_chains(monkeypatch, caplog):
    """The Eq. 10 stage logs its start and result; the bar counts the chains built."""
    from msens import pipeline
    from msens.config.study import load_study

    study = load_study(builtin_study_path(PAPER_TABLE2))
    built = []

    def fake_fit(make_chain, **kw):  # two chains instead of ~130 chain runs
        built.extend(make_chain(g, 0.0) for g in (1.0, 2.0))
        return SimpleNamespace(gamma_c=1.5, gamma_w=0.0, n_simulations=2)

    monkeypatch.setattr(pipeline, "fit_dissipation", fake_fit)
    with caplog.at_level(logging.INFO, logger="msens"):
        fit = pipeline.calibrate_dissipation(study, pipeline.output_times(study))
    assert fit.gamma_c == 1.5 and len(built) == 2
    messages = [r.getMessage() for r in caplog.records]
    assert any(m.startswith("calibrating the dissipation (paper Eq. 10)") for m in messages)
    assert any(m.startswith("calibrated gamma_c = 1.5 kg/s") for m in messages)


def test_diagnosis_logs_candidates_and_decision(monkeypatch, caplog):
    from msens.diagnose import candidates

    effects = [SimpleNamespace(name="wall_dissipation"), SimpleNamespace(name="gap")]
    monkeypatch.setattr(candidates, "fit_effect", lambda e, *a: e.name)
    with caplog.at_level(logging.INFO, logger="msens"):
        fits = candidates.fit_candidates(effects, None, None, None, None, None)
        candidates.log_decision([SimpleNamespace(effect="gap", score=3.0)], None, 10.0)
    assert fits == ["wall_dissipation", "gap"]
    messages = [r.getMessage() for r in caplog.records]
    assert "fitting 2 candidate effects: wall_dissipation, gap" in messages
    assert "decision: none (best gap scores 3.0 <= threshold 10)" in messages


# ----------------------------------------------------------------------------- base install

def test_field_3d_without_pyvista_is_skipped_with_a_hint(tmp_path, monkeypatch, caplog):
    from msens import field_outputs as report

    monkeypatch.setitem(sys.modules, "pyvista", None)  # what the base install looks like
    with pytest.raises(ImportError, match=r'pip install "msens\[viz\]"'):
        report.plot_field_3d(None, tmp_path / "field_3d.png")
    # the other outputs are written; the figure is reported as skipped, with the hint
    for name in ("write_json", "write_vtu", "plot_field_map"):
        monkeypatch.setattr(report, name, lambda rep, path, **kw: path)
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="msens"):
        written = report.write_field_outputs(None, tmp_path)
    assert written["field_3d.png"].startswith("skipped")
    assert 'msens[viz]' in written["field_3d.png"]
    hints = [r.getMessage() for r in caplog.records if "msens[viz]" in r.getMessage()]
    assert len(hints) == 1 and hints[0].startswith("field_3d.png skipped")


def test_scheduler_without_dask_is_an_input_error(monkeypatch):
    from msens.parallel import run_tasks

    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(InputError, match=r'pip install "msens\[cluster\]"'):
        list(run_tasks(abs, [1, -2], scheduler="tcp://127.0.0.1:1"))
    assert sorted(run_tasks(abs, [1, -2], workers=1)) == [(0, 1), (1, 2)]  # local: no dask


def test_design_scheduler_without_dask_exits_2(tmp_path, monkeypatch, capsys):
    study, sweep = tmp_path / "study.toml", tmp_path / "sweep.toml"
    study.write_text((Path(__file__).parents[1] / "data" / "tiny-mss.toml").read_text())
    sweep.write_text("""
schema = "msens.sweep/1"
name = "tiny-magnet"
[magnet]
grade = ["ceramic8", "N38"]
[model]
bead_padding = 2
""")
    monkeypatch.setitem(sys.modules, "distributed", None)
    code = main(["design", str(study), "--sweep", str(sweep), "--out", str(tmp_path / "d"),
                 "--scheduler", "tcp://127.0.0.1:1", "-q"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("msens: error: --scheduler needs dask.distributed")
    assert 'pip install "msens[cluster]"' in err

"""The msens command: bad input gives one message and exit status 2, never a traceback."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from msens.cli import main
from msens.config.schema import PAPER_TABLE2
from msens.config.study import builtin_study_path

GOOD = builtin_study_path(PAPER_TABLE2).read_text()


def _study(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        ("bead_mass_kg = 0.45e-3", "bead_mass_kg = -0.45e-3", "chain.bead_mass_kg"),
        ("particle = 13\n  [[setup.sensor]]\n  kind = \"bead\"",
         "particle = 0\n  [[setup.sensor]]\n  kind = \"bead\"", "particle"),
        ("  particle = 18\n\n[[setup]]\nname = \"rod\"",
         "  particle = 31\n\n[[setup]]\nname = \"rod\"", "from 2 to 30"),
        ("gravity = 9.80665", "gravity = 9.80665\ncolour = 1", "unknown key 'chain.colour'"),
        ("beads = 29", "beads = \"many\"", "must be an integer"),
    ],
)
def test_bad_study_exit_2(tmp_path, capsys, old, new, fragment):
    assert old in GOOD
    path = _study(tmp_path, GOOD.replace(old, new, 1))
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "--no-figures"])
    err = capsys.readouterr().err
    assert code == 2
    assert fragment in err
    assert "Traceback" not in err
    assert err.count("msens: error") == 1  # one error line (after the command's first line)


def test_missing_file_exit_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.toml")]) == 2
    assert "nope.toml" in capsys.readouterr().err


def test_unknown_command_exit_2(capsys):
    assert main(["fly"]) == 2
    assert "invalid choice" in capsys.readouterr().err


def test_console_script_no_traceback(tmp_path):
    """The installed entry point, as a user runs it."""
    proc = subprocess.run([sys.executable, "-m", "msens.cli", "run", str(tmp_path / "x.toml")],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "x.toml" in proc.stderr


def test_refuses_to_overwrite_user_file(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("mine")
    code = main(["run", str(_study(tmp_path, GOOD)), "--out", str(out), "--no-figures"])
    assert code == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert (out / "summary.json").read_text() == "mine"


def test_run_writes_summary_and_reruns(tmp_path):
    fast = GOOD.split("[calibration.dissipation]")[0].replace("t_end_s = 1.0e-3",
                                                              "t_end_s = 4.0e-4")
    path = _study(tmp_path, fast)
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--no-figures"]) == 0
    first = json.loads((out / "summary.json").read_text())
    assert main(["run", str(path), "--out", str(out), "--no-figures"]) == 0  # own files: ok
    second = json.loads((out / "summary.json").read_text())
    assert first == second  # reproducible
    assert {r["setup"] for r in first["rows"]} == {"bead", "rod", "mss"}


def test_compare_mss_data_against_bead_study_exit_2(tmp_path, capsys):
    from msens.io.read import write_waveform
    from msens.io.waveform import Channel, Waveform

    bead_only = GOOD.split('[[setup]]\nname = "rod"')[0].replace("t_end_s = 1.0e-3",
                                                                   "t_end_s = 2.0e-4")
    data = tmp_path / "mss.csv"
    write_waveform(Waveform(time=np.arange(200) * 1e-7, data=np.zeros((200, 2)),
                            channels=(Channel("mss", 13), Channel("mss", 18)),
                            metadata={"units": "V"}), data)
    code = main(["compare", str(_study(tmp_path, bead_only)), str(data), "--out",
                 str(tmp_path / "cmp")])
    err = capsys.readouterr().err
    assert code == 2
    assert "mss@13, mss@18 of the data have no sensor" in err
    assert "bead (bead@13, bead@18)" in err
    assert "Traceback" not in err and err.count("msens: error") == 1


def _flat_waveform(path, kind, units="V"):
    """A silent two-channel record at particles 13 and 18 (the channels are what matters)."""
    from msens.io.read import write_waveform
    from msens.io.waveform import Channel, Waveform

    write_waveform(Waveform(time=np.arange(200) * 1e-7, data=np.zeros((200, 2)),
                            channels=(Channel(kind, 13), Channel(kind, 18)),
                            metadata={"units": units}), path)
    return path


@pytest.mark.parametrize(
    ("study", "kind", "units", "fragment"),
    [
        # the physics study's run: ~1 s with the transducer cache in meshes/, 10-40 s cold
        ("paper-mss", "bead", "V", "bead@13, bead@18 of the data have no sensor in study "
                                   "'paper-mss'; data has bead@13, bead@18; study setups: "
                                   "paper-mss (mss@13, mss@18)"),
        ("bead-only", "mss", "V", "mss@13, mss@18 of the data have no sensor in study "
                                  "'paper-table2'"),
        ("paper-mss", "mss", "mV", "the data's metadata say units: mV"),
    ],
)
def test_compare_bad_data_fails_before_the_run(tmp_path, capsys, monkeypatch, study, kind,
                                               units, fragment):
    """Data that cannot match the study are rejected from the study file, before anything
    is simulated: exit 2 and one line, in well under the run's time."""
    import time

    from msens.config.study import default_study_path

    def no_run(*args, **kwargs):  # a warm cache makes the run fast: timing alone can't tell
        raise AssertionError("compare ran the study before checking the data")

    monkeypatch.setattr("msens.workflows.compare.run_study", no_run)

    path = (default_study_path() if study == "paper-mss"
            else _study(tmp_path, GOOD.split('[[setup]]\nname = "rod"')[0]))
    data = _flat_waveform(tmp_path / "data.csv", kind, units)
    start = time.perf_counter()
    code = main(["compare", str(path), str(data), "--out", str(tmp_path / "cmp")])
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code == 2
    assert fragment in err
    assert "Traceback" not in err and err.count("msens: error") == 1
    assert elapsed < 5.0, f"compare took {elapsed:.1f} s to reject the data"
    assert not (tmp_path / "cmp" / "compare.json").exists()


def test_bare_msens_prints_help_and_version_is_known(capsys):
    from msens.cli import main, version

    assert main([]) == 0
    out = capsys.readouterr().out
    assert "usage: msens" in out and "check-waveform" in out
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"msens {version()}"


def test_usage_errors_have_one_prefix(capsys):
    from msens.cli import main

    assert main(["-q", "synth", "--shots", "many"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("msens: error: synth: ") and err.count("msens") == 1


def test_check_waveform_and_convert(tmp_path, capsys):
    from msens.cli import main

    src = tmp_path / "a.csv"
    src.write_text("# msens-waveform: 1\ntime_s,bead@13\n0.0,0.0\n1e-6,1.0\n2e-6,0.5\n")
    assert main(["check-waveform", str(src)]) == 0
    assert "ok, 3 samples" in capsys.readouterr().out
    target = tmp_path / "a.npz"
    assert main(["convert", str(src), str(target)]) == 0
    assert main(["check-waveform", str(target)]) == 0
    # never overwritten
    assert main(["convert", str(src), str(target)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["check-waveform", str(tmp_path / "missing.csv")]) == 2
    assert capsys.readouterr().err.splitlines()[-1].startswith("msens: error: ")


def test_result_files_record_the_version_and_the_study_hash(tmp_path):
    from msens import api
    from msens.version import version

    root = Path(__file__).resolve().parents[1]
    study = api.load(root / "studies" / "paper-mss.toml")
    p = api.provenance(study)
    assert p["msens_version"] == version() and len(p["study_sha256"]) == 64
    # the hash is the study's content, not its file's name
    copy = tmp_path / "copy.toml"
    copy.write_text((root / "studies" / "paper-mss.toml").read_text())
    assert api.provenance(api.load(copy)) == p
    changed = tmp_path / "changed.toml"
    changed.write_text(copy.read_text().replace("drop_height_m = 7.2e-3",
                                                "drop_height_m = 7.3e-3"))
    assert api.provenance(api.load(changed))["study_sha256"] != p["study_sha256"]
    assert api.summary(api.run(study))["provenance"] == p

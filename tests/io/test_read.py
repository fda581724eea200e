"""Format dispatch, cross-format exact round trips, safe writes, the check entry point."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from msens.errors import InputError
from msens.io import Channel, Waveform, check_waveform_file, read_waveform, write_waveform
from msens.io.read import main_check


def make_waveform() -> Waveform:
    rng = np.random.default_rng(11)
    nt = 2000
    time = -2e-5 + 1e-7 * np.arange(nt)  # 10 MHz, as in the paper's measurements
    channels = (Channel("bead", 13), Channel("bead", 18), Channel("mss", 13, 2))
    data = rng.normal(scale=10.0 ** rng.integers(-6, 2, size=3), size=(nt, 3))
    return Waveform(time, data, channels, {"drop_height_m": "0.0072", "rig": "tube A"})


def test_csv_npz_tdms_chain_is_exact(tmp_path: Path) -> None:
    w = make_waveform()
    current = w
    for step, suffix in enumerate([".csv", ".npz", ".tdms", ".csv", ".tdms", ".npz"]):
        path = tmp_path / f"s{step}{suffix}"
        write_waveform(current, path)
        current = read_waveform(path)
        assert current == w, suffix
        np.testing.assert_array_equal(current.data, w.data)  # bit-exact, not approx


def test_suffix_is_case_insensitive(tmp_path: Path) -> None:
    w = make_waveform()
    write_waveform(w, tmp_path / "W.CSV")
    assert read_waveform(tmp_path / "W.CSV") == w


def test_unknown_suffix_and_missing_file(tmp_path: Path) -> None:
    with pytest.raises(
        InputError,
        match=r"unknown waveform file type '\.txt'; allowed suffixes are .csv, .npz, .tdms",
    ):
        read_waveform(tmp_path / "a.txt")
    with pytest.raises(InputError, match=r"unknown waveform file type"):
        write_waveform(make_waveform(), tmp_path / "a.mat")
    with pytest.raises(InputError, match=r"nope\.csv: file not found"):
        read_waveform(tmp_path / "nope.csv")
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(InputError, match=r"d\.csv: not a regular file"):
        read_waveform(tmp_path / "d.csv")
    with pytest.raises(InputError, match=r"does not exist"):
        write_waveform(make_waveform(), tmp_path / "no" / "a.csv")


@pytest.mark.parametrize("suffix", [".csv", ".npz", ".tdms"])
def test_never_overwrites_unless_asked(tmp_path: Path, suffix: str) -> None:
    w = make_waveform()
    path = tmp_path / f"w{suffix}"
    path.write_bytes(b"precious")
    with pytest.raises(InputError, match=r"file exists; pass overwrite=True"):
        write_waveform(w, path)
    assert path.read_bytes() == b"precious"
    write_waveform(w, path, overwrite=True)
    assert read_waveform(path) == w
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no temp files left


def test_check_entry_point(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    good = write_waveform(make_waveform(), tmp_path / "good.npz")
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,bead@13\n0,1\n1,oops\n")
    assert check_waveform_file(good) == make_waveform()
    assert main_check([str(good)]) == 0
    assert "good.npz: ok, 2000 samples, dt = 1e-07 s" in capsys.readouterr().out
    assert main_check([str(good), str(bad)]) == 2
    captured = capsys.readouterr()
    assert "bad.csv:3: column 'bead@13': non-numeric cell 'oops'" in captured.err
    assert "Traceback" not in captured.err
    assert main_check([]) == 2
    assert "usage" in capsys.readouterr().err

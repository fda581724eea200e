"""Waveform TDMS files: LabVIEW-style input, rejections, exact round trip."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from msens.errors import InputError
from msens.io.tdms import read_tdms, write_tdms
from msens.io.waveform import Channel, Waveform


def _write(path: Path, channels: list[ChannelObject], root: dict | None = None) -> Path:
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([RootObject(root or {}), GroupObject("g"), *channels])
    return path


def test_round_trip_exact(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    w = Waveform(
        -2e-5 + 1e-7 * np.arange(500),
        rng.normal(size=(500, 3)),
        (Channel("bead", 13), Channel("rod", 18), Channel("mss", 13, 4)),
        {"drop_height_m": "0.0072", "operator": "x y"},
    )
    write_tdms(w, tmp_path / "w.tdms")
    assert read_tdms(tmp_path / "w.tdms") == w


def test_labview_style_channels(tmp_path: Path) -> None:
    """Free channel names, particle as a double, time from wf_* properties, odd root keys."""
    props = {"kind": "bead", "particle": 13.0, "wf_start_offset": -1e-5, "wf_increment": 1e-7}
    props2 = dict(props, kind="mss", particle="18", repeat=np.int32(2))
    data = np.arange(6, dtype=np.float32)
    path = _write(
        tmp_path / "lv.tdms",
        [ChannelObject("g", "Dev1/ai0", data, props), ChannelObject("g", "Dev1/ai1", data, props2)],
        root={"Author Name": "skipped", "description": "two\nlines"},
    )
    w = read_tdms(path)
    assert w.names == ("bead@13", "mss@18#2")
    np.testing.assert_allclose(w.time, -1e-5 + 1e-7 * np.arange(6), rtol=0, atol=1e-20)
    assert dict(w.metadata) == {"description": "two lines"}


TIME = ChannelObject("g", "time_s", np.arange(4.0))


@pytest.mark.parametrize(
    ("channels", "message"),
    [
        ([TIME, ChannelObject("g", "a", np.ones(4), {"particle": 3})], r"'g'/'a' has no 'kind'"),
        ([TIME, ChannelObject("g", "a", np.ones(4), {"kind": "rod"})], r"'a' has no 'particle'"),
        (
            [TIME, ChannelObject("g", "a", np.ones(4), {"kind": "coil", "particle": 3})],
            r"property kind 'coil' is not one of bead, rod, mss",
        ),
        (
            [TIME, ChannelObject("g", "a", np.ones(4), {"kind": "rod", "particle": 2.5})],
            r"property particle 2.5 is not a positive integer",
        ),
        (
            [TIME, ChannelObject("g", "a", np.ones(3), {"kind": "rod", "particle": 2})],
            r"channel rod@2 has 3 samples but time_s has 4",
        ),
        (
            [
                TIME,
                ChannelObject("g", "a", np.ones(4), {"kind": "rod", "particle": 2}),
                ChannelObject("g", "b", np.ones(4), {"kind": "rod", "particle": 2}),
            ],
            r"duplicate channel rod@2",
        ),
        ([ChannelObject("g", "a", np.ones(4), {"kind": "rod", "particle": 2})], r"no time column"),
        ([TIME], r"no data channels"),
        (
            [
                TIME,
                ChannelObject(
                    "g", "a", np.array([1, np.inf, 1, 1]), {"kind": "rod", "particle": 2}
                ),
            ],
            r"rod@2\[1\]: channel rod@2 value inf is not finite",
        ),
        (
            [TIME, ChannelObject("g", "a", np.array(["x"] * 4), {"kind": "rod", "particle": 2})],
            r"must hold real numbers",
        ),
    ],
)
def test_rejections(tmp_path: Path, channels: list, message: str) -> None:
    path = _write(tmp_path / "bad.tdms", channels)
    with pytest.raises(InputError, match=r"bad\.tdms: .*" + message):
        read_tdms(path)


def test_not_tdms(tmp_path: Path) -> None:
    path = tmp_path / "x.tdms"
    path.write_bytes(b"hello")
    with pytest.raises(InputError, match=r"x\.tdms: not a TDMS file"):
        read_tdms(path)
    good = tmp_path / "good.tdms"
    write_tdms(Waveform(np.arange(100.0), np.ones((100, 1)), (Channel("rod", 2),)), good)
    path.write_bytes(good.read_bytes()[:60])
    with pytest.raises(InputError, match=r"x\.tdms"):
        read_tdms(path)

"""Waveform NPZ archives: rejections naming file and array, exact round trip."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest

from msens.errors import InputError
from msens.io.npz import read_npz, write_npz
from msens.io.waveform import Channel, Waveform


def _save(path: Path, **arrays: object) -> Path:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    path.write_bytes(buffer.getvalue())
    return path


def test_round_trip_exact(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    w = Waveform(
        1e-7 * np.arange(300) - 3e-6,
        rng.normal(size=(300, 2)),
        (Channel("mss", 13), Channel("mss", 13, 2)),
        {"note": "two shots"},
    )
    write_npz(w, tmp_path / "w.npz")
    assert read_npz(tmp_path / "w.npz") == w


def test_plain_archive_without_metadata_and_int_data(tmp_path: Path) -> None:
    path = _save(tmp_path / "p.npz", time_s=np.arange(4.0), **{"rod@18": np.arange(4)})
    w = read_npz(path)
    assert w.names == ("rod@18",) and dict(w.metadata) == {}
    np.testing.assert_array_equal(w.channel("rod@18"), [0.0, 1.0, 2.0, 3.0])


T = np.arange(4.0)


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        ({"bead@1": T}, r"no time column"),
        ({"time_s": T}, r"no channel arrays"),
        ({"time_s": T, "coil@1": T}, r"unknown array 'coil@1': allowed are 'time_s'"),
        ({"time_s": T, "bead@1": T[:3]}, r"channel bead@1 has 3 samples but time_s has 4"),
        ({"time_s": T, "bead@1": T, "bead@1#1": T}, r"duplicate channel bead@1"),
        ({"time_s": T, "bead@1": np.array([0, 1, np.nan, 3])}, r"bead@1\[2\]: .*not finite"),
        ({"time_s": T[::-1], "bead@1": T}, r"time_s\[1\]: time_s must increase"),
        ({"time_s": T, "bead@1": T.astype(complex)}, r"array 'bead@1' must be real"),
        ({"time_s": T, "bead@1": T.reshape(2, 2)}, r"must be 1-D"),
        ({"time_s": T, "bead@1": T, "__metadata__": np.array("{")}, r"not valid JSON"),
        ({"time_s": T, "bead@1": T, "__metadata__": np.array("[1]")}, r"JSON object"),
        (
            {"time_s": T, "bead@1": T, "__metadata__": np.array(json.dumps({"k": 1}))},
            r"metadata 'k' must be a string",
        ),
    ],
)
def test_rejections(tmp_path: Path, arrays: dict, message: str) -> None:
    path = _save(tmp_path / "bad.npz", **arrays)
    with pytest.raises(InputError, match=r"bad\.npz.*" + message):
        read_npz(path)


def test_object_arrays_are_refused_without_unpickling(tmp_path: Path) -> None:
    path = _save(tmp_path / "o.npz", time_s=T, **{"bead@1": np.array([1, "a", None, 2], object)})
    with pytest.raises(InputError, match=r"o\.npz: not a readable NPZ archive.*pickle"):
        read_npz(path)


def test_npy_and_garbage_and_empty(tmp_path: Path) -> None:
    npy = tmp_path / "a.npz"
    np.save(npy.with_suffix(".npy"), T)
    npy.write_bytes(npy.with_suffix(".npy").read_bytes())
    with pytest.raises(InputError, match=r"a\.npz: a single \.npy array"):
        read_npz(npy)
    junk = tmp_path / "j.npz"
    junk.write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(InputError, match=r"j\.npz: not a readable NPZ archive"):
        read_npz(junk)
    empty = tmp_path / "e.npz"
    empty.write_bytes(b"")
    with pytest.raises(InputError, match=r"e\.npz: empty file"):
        read_npz(empty)

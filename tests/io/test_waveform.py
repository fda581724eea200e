"""Channel names and the Waveform container's invariants."""

from __future__ import annotations

import numpy as np
import pytest

from msens.errors import InputError
from msens.io.waveform import TIME_RTOL, Channel, Waveform


def make_waveform(nt: int = 50, names: tuple[str, ...] = ("bead@13", "mss@18#2")) -> Waveform:
    rng = np.random.default_rng(1)
    time = -1e-5 + 1e-7 * np.arange(nt)
    channels = tuple(Channel.parse(n) for n in names)
    return Waveform(time, rng.normal(size=(nt, len(names))), channels, {"drop_height_m": "0.0072"})


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("bead@13", Channel("bead", 13, 1)),
        ("rod@2", Channel("rod", 2, 1)),
        ("mss@18#2", Channel("mss", 18, 2)),
        (" mss@18#1 ", Channel("mss", 18, 1)),
    ],
)
def test_channel_parse(name: str, expected: Channel) -> None:
    assert Channel.parse(name) == expected


def test_channel_name_is_canonical() -> None:
    assert Channel("bead", 13).name == "bead@13"
    assert Channel("bead", 13, 2).name == "bead@13#2"
    assert Channel.parse("bead@13#1").name == "bead@13"


@pytest.mark.parametrize(
    "name", ["Bead@13", "bead13", "bead@0", "bead@-1", "piezo@3", "bead@13#0", "bead@1.5", ""]
)
def test_channel_parse_rejects(name: str) -> None:
    with pytest.raises(InputError, match="bead, rod, mss"):
        Channel.parse(name)


@pytest.mark.parametrize(
    ("kind", "particle", "repeat"),
    [("coil", 1, 1), ("bead", 0, 1), ("bead", 1, 0), ("bead", True, 1)],
)
def test_channel_rejects_bad_fields(kind: str, particle: int, repeat: int) -> None:
    with pytest.raises(InputError):
        Channel(kind, particle, repeat)  # type: ignore[arg-type]


def test_waveform_accessors() -> None:
    w = make_waveform()
    assert w.dt == pytest.approx(1e-7, rel=1e-12)
    assert w.names == ("bead@13", "mss@18#2")
    np.testing.assert_array_equal(w.channel("mss@18#2"), w.data[:, 1])
    np.testing.assert_array_equal(w.channel(Channel("bead", 13)), w.data[:, 0])
    assert w.select(kind="mss").names == ("mss@18#2",)
    assert w.select(particle=13).names == ("bead@13",)
    assert w.metadata["drop_height_m"] == "0.0072"


def test_waveform_is_read_only_and_compares_exactly() -> None:
    w = make_waveform()
    with pytest.raises(ValueError, match="read-only"):
        w.data[0, 0] = 1.0
    with pytest.raises(TypeError):
        w.metadata["x"] = "y"  # type: ignore[index]
    assert w == make_waveform()
    other = Waveform(w.time, np.nextafter(w.data, np.inf), w.channels, w.metadata)
    assert other != w


def test_missing_channel_lists_present() -> None:
    w = make_waveform()
    with pytest.raises(InputError, match=r"rod@13 not in waveform; present: bead@13, mss@18#2"):
        w.channel("rod@13")
    with pytest.raises(InputError, match="no channel"):
        w.select(kind="rod")
    with pytest.raises(InputError, match="not one of"):
        w.select(kind="coil")


def _build(time: np.ndarray, data: np.ndarray, names: tuple[str, ...], meta=None) -> Waveform:
    return Waveform(time, data, tuple(Channel.parse(n) for n in names), meta or {})


@pytest.mark.parametrize(
    ("time", "data", "names", "meta", "message"),
    [
        (np.arange(5.0), np.zeros((4, 1)), ("bead@1",), None, "shape"),
        (np.arange(1.0), np.zeros((1, 1)), ("bead@1",), None, "at least 2 samples"),
        (np.array([0.0, 2.0, 1.0]), np.zeros((3, 1)), ("bead@1",), None, "increase strictly"),
        (np.array([0.0, 1.0, 3.0]), np.zeros((3, 1)), ("bead@1",), None, "not uniformly"),
        (np.array([0.0, np.nan, 2.0]), np.zeros((3, 1)), ("bead@1",), None, "not finite"),
        (np.arange(3.0), np.array([[0.0], [np.inf], [0.0]]), ("bead@1",), None, "bead@1"),
        (np.arange(3.0), np.zeros((3, 2)), ("bead@1", "bead@1#1"), None, "duplicate"),
        (np.arange(3.0), np.zeros((3, 0)), (), None, "at least one channel"),
        (np.arange(3.0), np.zeros((3, 1)), ("bead@1",), {"a b": "x"}, "bad metadata key"),
        (np.arange(3.0), np.zeros((3, 1)), ("bead@1",), {"a": "x\ny"}, "one line"),
        (np.arange(3.0), np.zeros((3, 1)), ("bead@1",), {"msens-waveform": "1"}, "reserved"),
        (np.arange(3.0), np.zeros((3, 1), complex), ("bead@1",), None, "real numeric"),
    ],
)
def test_waveform_rejects(time, data, names, meta, message: str) -> None:
    with pytest.raises(InputError, match=message):
        _build(time, data, names, meta)


def test_time_tolerance_boundary() -> None:
    time = np.arange(100.0)
    ok = time.copy()
    ok[50] += 0.5 * TIME_RTOL
    _build(ok, np.zeros((100, 1)), ("rod@3",))
    bad = time.copy()
    bad[50] += 2 * TIME_RTOL
    with pytest.raises(InputError, match="sample 50"):
        _build(bad, np.zeros((100, 1)), ("rod@3",))

"""Waveform CSV: parsing, every rejection with file:line, exact round trip."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from msens.errors import InputError
from msens.io.csv import format_csv, parse_csv, read_csv, write_csv
from msens.io.waveform import Channel, Waveform

GOOD = """# msens-waveform: 1
# drop_height_m: 0.0072
#
# operator: A. N. Other
time_s, bead@13 ,bead@18#2
-1.0e-05,0.0012,-0.0003
-0.9e-05,0.0013,-0.0004

-0.8e-05,0.0014,-0.0005
"""


def test_parse_good_file() -> None:
    w = parse_csv(GOOD, "good.csv")
    assert w.names == ("bead@13", "bead@18#2")
    assert dict(w.metadata) == {"drop_height_m": "0.0072", "operator": "A. N. Other"}
    np.testing.assert_array_equal(w.time, [-1.0e-05, -0.9e-05, -0.8e-05])
    np.testing.assert_array_equal(w.channel("bead@18#2"), [-0.0003, -0.0004, -0.0005])


def test_crlf_and_bom_are_accepted(tmp_path: Path) -> None:
    path = tmp_path / "w.csv"
    path.write_bytes(b"\xef\xbb\xbf" + GOOD.replace("\n", "\r\n").encode())
    assert read_csv(path) == parse_csv(GOOD, "x")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", r"f\.csv: empty file"),
        ("# a: 1\n\n", r"f\.csv: empty file"),
        ("time_s,bead@1\n", r"f\.csv: empty file: the header is followed by no data"),
        ("t,bead@1\n0,1\n1,1\n", r"f\.csv:1: no time column"),
        ("bead@1,time_s\n0,1\n1,1\n", r"f\.csv:1: no time column"),
        ("time_s\n0\n1\n", r"f\.csv:1: the header names no channel"),
        ("time_s,bead@1,coil@2\n0,1,1\n", r"f\.csv:1: column 3: unknown channel name 'coil@2'"),
        ("time_s,bead@1,bead@1#1\n0,1,1\n", r"f\.csv:1: duplicate channel bead@1"),
        ("time_s,bead@1\n0,1\n1,x\n", r"f\.csv:3: column 'bead@1': non-numeric cell 'x'"),
        ("time_s,bead@1\n0,1\n1,\n", r"f\.csv:3: column 'bead@1': non-numeric cell ''"),
        ("time_s,bead@1\n0,1\n1,1_0\n", r"f\.csv:3: column 'bead@1': non-numeric"),
        ("time_s,bead@1\n0,1\n1,1,2\n", r"f\.csv:3: 3 cells, but the header has 2 columns"),
        ("time_s,bead@1\n0,1\n1\n", r"f\.csv:3: 1 cells, but the header has 2"),
        ("time_s,bead@1\n0,1\n1,nan\n", r"f\.csv:3: channel bead@1 value nan is not finite"),
        ("time_s,bead@1\n0,1\n1,-inf\n", r"f\.csv:3: channel bead@1 value -inf is not finite"),
        ("time_s,bead@1\n0,1\ninf,1\n", r"f\.csv:3: time_s is not finite"),
        ("time_s,bead@1\n0,1\n2,1\n1,1\n", r"f\.csv:4: time_s must increase strictly"),
        ("time_s,bead@1\n0,1\n0,1\n", r"f\.csv:3: time_s must increase strictly"),
        ("time_s,bead@1\n0,1\n1,1\n3,1\n4,1\n", r"f\.csv:(3|4): time_s is not uniformly"),
        ("time_s,bead@1\n0,1\n", r"f\.csv: need at least 2 samples"),
        ("# no colon here\ntime_s,bead@1\n0,1\n1,1\n", r"f\.csv:1: bad metadata line"),
        ("# : value\ntime_s,bead@1\n0,1\n1,1\n", r"f\.csv:1: bad metadata line"),
        ("# a b: 1\ntime_s,bead@1\n0,1\n1,1\n", r"f\.csv:1: bad metadata key 'a b'"),
        ("# a: 1\n# a: 2\ntime_s,bead@1\n0,1\n1,1\n", r"f\.csv:2: metadata key 'a' given twice"),
        ("# msens-waveform: 2\ntime_s,bead@1\n0,1\n1,1\n", r"f\.csv:1: unsupported"),
        ("time_s,bead@1\n0,1\n# a: 1\n1,1\n", r"f\.csv:3: metadata line after the header"),
    ],
)
def test_rejections_name_file_and_line(text: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        parse_csv(text, "f.csv")


def test_non_utf8_is_rejected(tmp_path: Path) -> None:
    path = tmp_path / "w.csv"
    path.write_bytes(b"time_s,bead@1\n0,\xff\n")
    with pytest.raises(InputError, match=r"w\.csv: not UTF-8 text \(byte 16\)"):
        read_csv(path)


def test_round_trip_is_exact_for_awkward_floats(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    nt = 400
    time = 0.1 * (np.arange(nt) - 17) / 3.0  # inexact binary fractions
    data = np.column_stack(
        [
            rng.normal(size=nt) * 10.0 ** rng.integers(-300, 300, size=nt),
            np.nextafter(rng.uniform(-1, 1, size=nt), 2.0),
            np.where(np.arange(nt) % 2 == 0, -0.0, 5e-324),  # signed zero, subnormal
        ]
    )
    channels = (Channel("bead", 13), Channel("rod", 18, 3), Channel("mss", 13))
    w = Waveform(time, data, channels, {"drop_height_m": "0.0072", "empty": ""})
    path = tmp_path / "w.csv"
    write_csv(w, path)
    back = read_csv(path)
    assert back == w
    assert np.array_equal(np.signbit(back.data), np.signbit(w.data))
    assert format_csv(back) == path.read_text()


def _scope_text(times: np.ndarray, fmt: str = "{:.5e}") -> str:
    """An oscilloscope-style export: times printed with 6 significant digits."""
    rows = [f"{fmt.format(float(t))},{np.sin(1e4 * t):.6f}" for t in times]
    return "time_s,mss@13\n" + "\n".join(rows) + "\n"


def test_scope_times_with_six_digits_are_regularised() -> None:
    """A 10 MHz record from -0.1 ms printed as %.5e deviates from its grid by up to 5e-3 dt
    (over TIME_RTOL): accepted, and the least-squares grid recovers the true times to
    < 1e-4 dt (the rounding errors average out)."""
    dt = 1e-7
    exact = -1e-4 + dt * np.arange(20000)
    w = parse_csv(_scope_text(exact), "scope.csv")
    assert np.max(np.abs(w.time - exact)) < 1e-4 * dt
    assert np.diff(w.time).std() < 1e-9 * dt


def test_scope_times_still_catch_a_missing_sample() -> None:
    dt = 1e-7
    times = np.delete(-1e-4 + dt * np.arange(2000), 700)
    with pytest.raises(InputError, match=r"scope\.csv:\d+: time_s is not uniformly sampled"):
        parse_csv(_scope_text(times), "scope.csv")


def test_full_precision_jitter_is_still_rejected() -> None:
    """With repr-printed times there is no rounding to allow for: 1 % jitter is rejected."""
    dt = 1e-7
    times = -1e-4 + dt * np.arange(2000)
    times[1000] += 0.01 * dt
    with pytest.raises(InputError, match="not uniformly sampled"):
        parse_csv(_scope_text(times, "{!r}"), "jitter.csv")

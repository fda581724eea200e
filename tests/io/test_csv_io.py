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


# --- the fast reader (a compiled parser for the data lines) and its line-by-line fallback


def _line_by_line(monkeypatch) -> None:
    """Make the readers skip the fast path (the reference behaviour)."""
    import msens.io.csv as csv_mod

    monkeypatch.setattr(csv_mod, "read_numeric_block", lambda *a, **k: None)
    monkeypatch.setattr("msens.io.text_table.read_numeric_block", lambda *a, **k: None)


def _big_text(nt: int, fmt: str, *, blanks: bool = False, crlf: bool = False) -> str:
    rng = np.random.default_rng(nt)
    t = -1e-4 + 1e-7 * np.arange(nt)
    v = rng.normal(size=(nt, 2)) * 1e-3
    cell = repr if fmt == "repr" else (lambda x: fmt % x)
    rows = [f"{cell(float(a))},{cell(float(b))},{cell(float(c))}"
            for a, (b, c) in zip(t, v, strict=True)]
    if blanks:
        rows = [r if i % 97 else r + "\n" for i, r in enumerate(rows)]
    text = "# msens-waveform: 1\n# units: V\ntime_s,mss@13,mss@18\n" + "\n".join(rows) + "\n"
    return text.replace("\n", "\r\n") if crlf else text


@pytest.mark.parametrize(
    ("fmt", "blanks", "crlf"),
    [("repr", False, False), ("%.5e", False, False), ("%.5e", True, True),
     ("%.7f", True, False), ("%.16e", False, True)],
)
def test_fast_reader_equals_line_by_line(monkeypatch, fmt, blanks, crlf) -> None:
    import msens.io.csv as csv_mod

    text = _big_text(3000, fmt, blanks=blanks, crlf=crlf)
    used = []
    original = csv_mod.read_numeric_block
    monkeypatch.setattr(csv_mod, "read_numeric_block",
                        lambda *a, **k: used.append(original(*a, **k)) or used[-1])
    fast = parse_csv(text, "f.csv")
    assert used and used[0] is not None  # the fast reader read it
    _line_by_line(monkeypatch)
    slow = parse_csv(text, "f.csv")
    assert fast == slow
    assert np.array_equal(fast.time, slow.time)  # also the regularised time axis


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ("x", r"f\.csv:(?P<line>\d+): column 'mss@18': non-numeric cell 'x'"),
        ("nan", r"f\.csv:(?P<line>\d+): channel mss@18 value nan is not finite"),
        ("1_0", r"f\.csv:(?P<line>\d+): column 'mss@18': non-numeric cell '1_0'"),
        ("1,2", r"f\.csv:(?P<line>\d+): 4 cells, but the header has 3 columns"),
        ("\"1\"", r"f\.csv:(?P<line>\d+): column 'mss@18': non-numeric cell '\"1\"'"),
        ("1\r2", r"f\.csv:(?P<line>\d+): column 'mss@18': non-numeric cell"),
    ],
)
def test_large_file_errors_name_the_line(bad, message) -> None:
    """A bad cell deep in a large file with blank lines: the message names its line as an
    editor shows it."""
    text = _big_text(5000, "repr", blanks=True)
    lines = text.split("\n")
    target = 4000
    head, _, _ = lines[target - 1].rpartition(",")
    lines[target - 1] = f"{head},{bad}"
    with pytest.raises(InputError, match=message) as info:
        parse_csv("\n".join(lines), "f.csv")
    assert f"f.csv:{target}:" in str(info.value)


def test_fast_reader_keeps_exact_floats(tmp_path: Path) -> None:
    """Awkward floats (17 digits, subnormals, huge exponents) read back bit for bit."""
    rng = np.random.default_rng(11)
    nt = 5000
    data = np.column_stack([rng.normal(size=nt) * 10.0 ** rng.integers(-300, 300, size=nt),
                            np.nextafter(rng.uniform(-1, 1, size=nt), 2.0)])
    w = Waveform(1e-7 * np.arange(nt), data, (Channel("bead", 13), Channel("bead", 18)), {})
    write_csv(w, tmp_path / "w.csv")
    assert read_csv(tmp_path / "w.csv") == w


def test_vectorised_resolution_equals_printed_resolution() -> None:
    from msens.io.csv import _column_resolution, printed_resolution

    rng = np.random.default_rng(5)
    formats = ["%.5e", "%.3E", "%.6f", "%g", "repr", "%+.2e", "%.10f", "%.0f", "%.15e"]
    for _ in range(1500):
        n = int(rng.integers(1, 8))
        fmt = formats[rng.integers(len(formats))]
        values = rng.normal(size=n) * 10.0 ** rng.integers(-8, 8, size=n)
        values[rng.random(n) < 0.2] = 0.0
        cells = [repr(float(v)) if fmt == "repr" else fmt % v for v in values]
        if rng.random() < 0.3:
            cells = [f" {c}  " for c in cells]
        if rng.random() < 0.3:
            cells = ["00" + c.strip().lstrip("+-") for c in cells]
        raw = ",".join(cells).encode()
        starts = np.cumsum([0] + [len(c) + 1 for c in cells[:-1]]).astype(np.int32)
        ends = (starts + np.array([len(c) for c in cells])).astype(np.int32)
        got = _column_resolution(np.frombuffer(raw, np.uint8), starts, ends,
                                 np.array([float(c) for c in cells]))
        assert got == printed_resolution(cells), cells


@pytest.mark.parametrize("delimiter", [",", ";", "\t"])
def test_scope_export_fast_equals_line_by_line(monkeypatch, tmp_path, delimiter) -> None:
    from msens.io.mapped import read_mapped

    rng = np.random.default_rng(2)
    t = -1e-4 + 1e-7 * np.arange(4000)
    rows = [delimiter.join((f"{a:.5e}", f"{b:.4e}", "x", f"{c:.4e}"))
            for a, (b, c) in zip(t * 1e3, rng.normal(size=(t.size, 2)), strict=True)]
    text = (f"Model{delimiter}DSO\n\nTime{delimiter}CH1{delimiter}Note{delimiter}CH2\n"
            f"ms{delimiter}mV{delimiter}{delimiter}µV\n" + "\n".join(rows) + "\n")
    path = tmp_path / "scope.csv"
    path.write_bytes(text.encode("latin-1"))
    columns = "time=Time:ms,mss@13=CH1:mV,mss@18=CH2:uV"
    fast = read_mapped(path, columns)
    _line_by_line(monkeypatch)
    slow = read_mapped(path, columns)
    assert fast == slow
    assert np.array_equal(fast.time, slow.time)

"""Fuzzing the waveform readers: malformed files raise InputError and nothing else.

Budget: derandomized, at most 200 examples per test, no deadline; the whole module runs in
a few seconds. Raise ``max_examples`` locally for a deeper search.
"""

from __future__ import annotations

import io
import os
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from msens.errors import InputError
from msens.io import Channel, Waveform, read_waveform
from msens.io.csv import format_csv
from msens.io.npz import format_npz
from msens.io.read import check_waveform_file, main_check
from msens.io.tdms import format_tdms

#: Raise with MSENS_FUZZ_EXAMPLES=5000 for a deeper local search.
FUZZ = settings(
    max_examples=int(os.environ.get("MSENS_FUZZ_EXAMPLES", "200")),
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)


def _valid() -> Waveform:
    rng = np.random.default_rng(0)
    nt = 12
    return Waveform(
        -1e-6 + 1e-7 * np.arange(nt),
        rng.normal(size=(nt, 2)),
        (Channel("bead", 13), Channel("mss", 18, 2)),
        {"drop_height_m": "0.0072"},
    )


VALID = _valid()
CSV_TEXT = format_csv(VALID)
BYTES = {".csv": CSV_TEXT.encode(), ".npz": format_npz(VALID), ".tdms": format_tdms(VALID)}


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def _read_only_input_errors(path: Path, content: bytes) -> None:
    """Reading ``content`` either succeeds with a valid Waveform or raises InputError."""
    path.write_bytes(content)
    try:
        w = read_waveform(path)
    except InputError as exc:
        assert str(exc), "an InputError must carry a message"
        assert path.name in str(exc), f"message does not name the file: {exc}"
        event("rejected with InputError")
    else:
        assert isinstance(w, Waveform)
        assert np.all(np.isfinite(w.data))
        event("read as a valid waveform")


suffixes = st.sampled_from(sorted(BYTES))


@FUZZ
@given(suffix=suffixes, content=st.binary(max_size=2000))
def test_random_bytes(workdir: Path, suffix: str, content: bytes) -> None:
    _read_only_input_errors(workdir / f"random{suffix}", content)


@FUZZ
@given(suffix=suffixes, data=st.data())
def test_truncated_and_corrupted_valid_files(
    workdir: Path, suffix: str, data: st.DataObject
) -> None:
    content = bytearray(BYTES[suffix])
    cut = data.draw(st.integers(0, len(content)), label="cut")
    content = content[:cut]
    flips = data.draw(st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), max_size=4))
    for position, value in flips:
        if content:
            content[position % len(content)] = value
    _read_only_input_errors(workdir / f"cut{suffix}", bytes(content))


cells = st.one_of(
    st.text(max_size=12),
    st.sampled_from(["nan", "inf", "-inf", "1e400", "", " ", "1_0", "0x10", "1,2", "#", "１"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)
lines = st.one_of(
    st.text(max_size=40),
    st.builds(lambda k, v: f"# {k}: {v}", st.text(max_size=10), st.text(max_size=10)),
    st.builds(lambda cs: ",".join(cs), st.lists(cells, max_size=5)),
    st.builds(
        lambda cs: ",".join(["time_s", *cs]),
        st.lists(
            st.one_of(
                st.from_regex(r"(bead|rod|mss|x)@-?[0-9]{1,2}(#[0-9])?", fullmatch=True), cells
            ),
            max_size=4,
        ),
    ),
)


@FUZZ
@given(data=st.data())
def test_csv_mutations(workdir: Path, data: st.DataObject) -> None:
    text_lines = CSV_TEXT.split("\n")
    for _ in range(data.draw(st.integers(1, 3), label="n_mutations")):
        action = data.draw(st.sampled_from(["replace_cell", "insert", "replace", "delete"]))
        i = data.draw(st.integers(0, len(text_lines) - 1), label="line")
        if action == "replace_cell":
            parts = text_lines[i].split(",")
            j = data.draw(st.integers(0, len(parts) - 1), label="cell")
            parts[j] = data.draw(cells, label="new cell")
            text_lines[i] = ",".join(parts)
        elif action == "insert":
            text_lines.insert(i, data.draw(lines, label="new line"))
        elif action == "replace":
            text_lines[i] = data.draw(lines, label="new line")
        elif len(text_lines) > 1:
            del text_lines[i]
    content = "\n".join(text_lines).encode("utf-8", errors="surrogatepass")
    _read_only_input_errors(workdir / "mutated.csv", content)


names = st.one_of(
    st.sampled_from(["time_s", "bead@13", "rod@2#2", "mss@0", "__metadata__", "bead@13#1"]),
    st.text(alphabet=st.characters(codec="ascii", exclude_characters="/\\\x00"), max_size=8)
    .filter(lambda n: n not in ("file", "allow_pickle")),  # numpy.savez's own arguments
)
arrays = st.one_of(
    st.lists(st.floats(allow_nan=True), max_size=6).map(np.array),
    st.lists(st.integers(-5, 5), max_size=6).map(np.array),
    st.text(max_size=8).map(np.array),
    st.lists(st.booleans(), max_size=6).map(np.array),
    st.just(np.arange(12.0).reshape(3, 4)),
    st.just(-1e-6 + 1e-7 * np.arange(12)),
    st.just(np.zeros(12, complex)),
)


@FUZZ
@given(content=st.dictionaries(names, arrays, max_size=5))
def test_npz_random_arrays(workdir: Path, content: dict[str, np.ndarray]) -> None:
    buffer = io.BytesIO()
    np.savez(buffer, **content)
    _read_only_input_errors(workdir / "arrays.npz", buffer.getvalue())


@FUZZ
@given(suffix=suffixes, content=st.binary(max_size=300), valid=st.booleans())
def test_check_entry_never_raises(workdir: Path, suffix: str, content: bytes, valid: bool) -> None:
    path = workdir / f"check{suffix}"
    path.write_bytes(BYTES[suffix] if valid else content)
    out_buffer, err_buffer = io.StringIO(), io.StringIO()
    with redirect_stdout(out_buffer), redirect_stderr(err_buffer):
        status = main_check([str(path)])
    out, err = out_buffer.getvalue(), err_buffer.getvalue()
    try:
        check_waveform_file(path)
    except InputError as exc:
        assert status == 2 and str(exc) in err and "Traceback" not in err
    else:
        assert status == 0 and "ok" in out

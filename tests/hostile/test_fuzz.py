"""Fuzzing the commands with hostile study keys, waveform files and sweep specs: the
outcome is a result (exit 0) or one input error (exit 2), never a traceback, an internal
error or a run beyond its time bound.

Budget: derandomized and bounded for the default suite (about 20 s); the ``slow`` variants
search more (``MSENS_FUZZ_EXAMPLES`` raises both).
"""

from __future__ import annotations

import copy
import os
import time
import tomllib
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tests.hostile.conftest import TWENTY
from tests.hostile.tomltext import dumps

from msens import budget
from msens.cli import main
from msens.config.study import parse_study
from msens.design.sweep import parse_sweep
from msens.errors import InputError

ROOT = Path(__file__).parents[2]
SHIPPED = {p.stem: tomllib.loads(p.read_text()) for p in sorted((ROOT / "studies").glob("*.toml"))
           if "sweep" not in p.stem}
SHIPPED["paper-table2"] = tomllib.loads((ROOT / "src" / "msens" / "data" /
                                         "paper-table2.toml").read_text())
SWEEPS = [tomllib.loads(p.read_text()) for p in sorted((ROOT / "studies").glob("sweep-*.toml"))]
TWENTY_DOC = tomllib.loads(TWENTY)

_N = int(os.environ.get("MSENS_FUZZ_EXAMPLES", "0"))


#: Examples per test in the default suite and in the slow group.
FAST = {"parse": 120, "run": 10, "wave": 40, "sweep": 80, "args": 150}
SLOW = {"parse": 2000, "run": 150, "wave": 600, "sweep": 1000, "args": 3000}
_LONG = {"on": False}


def _settings(kind: str) -> settings:
    n = _N or (SLOW if _LONG["on"] else FAST)[kind]
    return settings(max_examples=n, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))

#: Values no key should take without a clear refusal.
HOSTILE = st.one_of(
    st.sampled_from([0, -1, 1, 0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e300, 1e308, -1e308,
                     float("nan"), float("inf"), float("-inf"), 2**63, -2**63, 10**30, True,
                     "", "NaN", "x" * 300, [], [1, 2], {}, {"a": 1}]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-2**65, max_value=2**65),
    st.text(max_size=12),
    st.lists(st.one_of(st.integers(-5, 40), st.floats(-1e3, 1e3)), max_size=4),
)


def _leaves(doc: Any, path: tuple = ()) -> list[tuple]:
    """Paths (keys and list indices) of every value that is not a table."""
    if isinstance(doc, dict):
        return [p for k, v in doc.items() for p in _leaves(v, (*path, k))]
    if isinstance(doc, list) and doc and all(isinstance(x, dict) for x in doc):
        return [p for i, v in enumerate(doc) for p in _leaves(v, (*path, i))]
    return [path]


def _tables(doc: Any, path: tuple = ()) -> list[tuple]:
    if isinstance(doc, dict):
        return [path] + [p for k, v in doc.items() for p in _tables(v, (*path, k))]
    if isinstance(doc, list) and doc and all(isinstance(x, dict) for x in doc):
        return [p for i, v in enumerate(doc) for p in _tables(v, (*path, i))]
    return []


def _node(doc: Any, path: tuple) -> Any:
    for p in path:
        doc = doc[p]
    return doc


@st.composite
def mutated(draw, base: dict) -> dict:
    """``base`` with one to three hostile edits: a value replaced or scaled, a key removed,
    an unknown key added."""
    doc = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        leaves = _leaves(doc)
        if not leaves:
            break
        kind = draw(st.sampled_from(["value", "scale", "remove", "unknown"]))
        path = draw(st.sampled_from(leaves))
        parent, key = _node(doc, path[:-1]), path[-1]
        old = parent[key]
        if kind == "scale" and isinstance(old, int | float) and not isinstance(old, bool):
            factor = 10.0 ** draw(st.integers(-40, 40)) * draw(st.sampled_from([1, -1]))
            parent[key] = old * factor if isinstance(old, float) else int(old * factor) \
                if abs(old * factor) < 2**62 else old * factor
        elif kind == "remove":
            del parent[key]
        elif kind == "unknown":
            table = _node(doc, draw(st.sampled_from(_tables(doc))))
            table[draw(st.sampled_from(["colour", "t_end", "Beads", "gamma"]))] = 1
        else:
            # a copy: sampled_from hands out the same {} / [] object every time, and an
            # "unknown" edit into it would nest it into itself over the examples
            parent[key] = copy.deepcopy(draw(HOSTILE))
    return doc


def _parse_outcome(doc: dict, source: str) -> None:
    """Parse and budget-check: a Study or an InputError, within a second."""
    start = time.perf_counter()
    try:
        text = dumps(doc)
    except (TypeError, ValueError):  # a value TOML cannot hold: nothing to test
        return
    try:
        study = parse_study(text, source=source)
        budget.check(study)
    except InputError as exc:
        assert str(exc).strip() and "\n" not in str(exc)
    assert time.perf_counter() - start < 2.0


def _check_cli(argv: list[str], capsys, seconds: float) -> int:
    start = time.perf_counter()
    code = main(argv)
    err = capsys.readouterr().err
    assert time.perf_counter() - start < seconds, argv
    assert code in (0, 2), err
    assert "Traceback" not in err and "internal error" not in err, err
    if code == 2:
        assert len([x for x in err.splitlines() if x.startswith("msens: error:")]) == 1, err
    return code


# --------------------------------------------------------------------------- study keys

@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_fuzz_shipped_study_keys(name):
    @_settings("parse")
    @given(mutated(SHIPPED[name]))
    def check(doc):
        _parse_outcome(doc, f"{name}.toml")
    check()


def test_fuzz_study_keys_through_run(tmp_path, capsys):
    """Mutated small studies run end to end through ``msens run``."""
    counter = iter(range(10**6))

    @_settings("run")
    @given(mutated(TWENTY_DOC))
    def check(doc):
        try:
            text = dumps(doc)
        except (TypeError, ValueError):
            return
        i = next(counter)
        path = tmp_path / f"s{i}.toml"
        path.write_text(text)
        _check_cli(["run", str(path), "--out", str(tmp_path / f"o{i}"), "--no-figures"],
                   capsys, seconds=60)
    check()


# --------------------------------------------------------------------------- waveforms

@pytest.fixture(scope="module")
def record(tmp_path_factory) -> tuple[Path, bytes]:
    from msens import api

    d = tmp_path_factory.mktemp("fuzzrec")
    study = d / "s.toml"
    study.write_text(TWENTY)
    path = api.synth(api.load(study), d / "w.csv", noise=0.01, seed=2)
    return study, path.read_bytes()


@st.composite
def damaged(draw, data: bytes) -> bytes:
    """A waveform file's bytes with lines or bytes changed, cut or repeated."""
    text = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["byte", "cut", "line", "number", "header"]))
        if not text:
            break
        at = draw(st.integers(0, len(text) - 1))
        if kind == "byte":
            text[at] = draw(st.integers(0, 255))
        elif kind == "cut":
            del text[at:]
        elif kind == "line":
            lines = bytes(text).split(b"\n")
            i = draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i]) if draw(st.booleans()) else lines.pop(i)
            text = bytearray(b"\n".join(lines))
        elif kind == "number":
            lines = bytes(text).split(b"\n")
            i = draw(st.integers(0, len(lines) - 1))
            cells = lines[i].split(b",")
            j = draw(st.integers(0, len(cells) - 1))
            cells[j] = draw(st.sampled_from([b"nan", b"-inf", b"1e308", b"0", b"-1e-300", b"",
                                             b"1,2", b"x", b"1e999"]))
            lines[i] = b",".join(cells)
            text = bytearray(b"\n".join(lines))
        else:
            text = bytearray(bytes(text).replace(
                b"time_s,", draw(st.sampled_from([b"time_s,bead@10#2,", b"t,", b"time_s,,",
                                                  b"time_s,bead@15,", b"time_s,mss@0,"])), 1))
    return bytes(text)


def test_fuzz_waveform_files(record, tmp_path, capsys):
    study, raw = record
    counter = iter(range(10**6))

    @_settings("wave")
    @given(damaged(raw), st.sampled_from(["check-waveform", "compare"]))
    def check(data, command):
        i = next(counter)
        path = tmp_path / f"w{i}.csv"
        path.write_bytes(data)
        argv = (["check-waveform", str(path)] if command == "check-waveform" else
                ["compare", str(study), str(path), "--out", str(tmp_path / f"o{i}")])
        code = main(argv)
        err = capsys.readouterr().err
        assert code in (0, 2) and "Traceback" not in err and "internal error" not in err, err
    check()


@pytest.mark.parametrize("suffix", [".npz", ".tdms"])
def test_fuzz_binary_waveform_files(record, tmp_path, capsys, suffix):
    from msens.io import read_waveform, write_waveform

    _, raw = record
    csv = tmp_path / "w.csv"
    csv.write_bytes(raw)
    good = tmp_path / f"w{suffix}"
    write_waveform(read_waveform(csv), good)
    data = good.read_bytes()
    counter = iter(range(10**6))

    @_settings("wave")
    @given(st.lists(st.tuples(st.integers(0, len(data) - 1), st.integers(0, 255)),
                    min_size=1, max_size=6), st.integers(0, len(data)))
    def check(edits, cut):
        b = bytearray(data[:max(cut, 1)])
        for at, byte in edits:
            if at < len(b):
                b[at] = byte
        path = tmp_path / f"x{next(counter)}{suffix}"
        path.write_bytes(bytes(b))
        code = main(["check-waveform", str(path)])
        err = capsys.readouterr().err
        assert code in (0, 2) and "Traceback" not in err and "internal error" not in err, err
        assert len(err) < 2000  # no raw bytes dumped
    check()


# --------------------------------------------------------------------------- sweeps

@pytest.mark.parametrize("index", range(len(SWEEPS)))
def test_fuzz_sweep_specs(index):
    from msens.config.study import load_study
    from msens.design.sweep import base_geometry, sweep_sensor, validate_designs

    study = load_study(ROOT / "studies" / "paper-mss.toml")
    base = base_geometry(study)  # outside the timed part: its first call imports the field code

    @_settings("sweep")
    @given(mutated(SWEEPS[index]))
    def check(doc):
        try:
            text = dumps(doc)
        except (TypeError, ValueError):
            return
        start = time.perf_counter()
        try:
            spec = parse_sweep(text, source="sweep.toml")
            sensor = sweep_sensor(study, spec)
            designs = spec.designs()
            if len(designs) <= 50:  # the geometry check of each design (ms apiece)
                validate_designs(base, sensor.particle, designs, spec.source)
        except InputError as exc:
            assert str(exc).strip()
        assert time.perf_counter() - start < 5.0
    check()


# --------------------------------------------------------------------------- arguments

#: Arguments of every kind a script or a shell may pass (issue 38: ``shots=2.5``,
#: ``scheduler=""``, ``workers=0``, a 300-character ``--out``).
ARGUMENTS = st.one_of(
    HOSTILE, st.none(), st.text(max_size=40), st.binary(max_size=8),
    st.sampled_from(["tcp://", "inproc://x", "tls://h:1", "h:", ":1", "[::1]", "tcp://h:0",
                     "/dev/zero", "/proc/self/x.csv", "y" * 300, "a\0b", ".", "/", "x.csv"]),
    st.builds(Path, st.text(max_size=20)))


def test_fuzz_command_arguments():
    """Every checked argument gives its value back (typed) or one InputError, at once."""
    from msens import preflight
    from msens.parallel import check_scheduler
    from msens.preflight import check_workers, count, number, output_dir, output_file

    checks = [lambda v: check_scheduler(v, connect=False), check_workers,
              lambda v: count(v, "--shots", 1, 10000),
              lambda v: number(v, "--noise", 0.0, 1.0), output_file, output_dir,
              preflight.study]

    @_settings("args")
    @given(st.sampled_from(range(len(checks))), ARGUMENTS)
    def check(which, value):
        start = time.perf_counter()
        try:
            checks[which](value)
        except InputError as exc:
            text = str(exc)
            assert text and "\n" not in text and len(text) <= 1100
        assert time.perf_counter() - start < 1.0
    check()


def test_fuzz_path_arguments_of_readers(tmp_path):
    """Readers and loaders given anything: a result or one InputError naming it."""
    from msens.config.study import load_study
    from msens.design.sweep import load_sweep
    from msens.io.read import read_waveform

    @_settings("args")
    @given(st.sampled_from([load_study, load_sweep, read_waveform]), ARGUMENTS)
    def check(reader, value):
        try:
            reader(value)
        except InputError as exc:
            assert str(exc) and "\n" not in str(exc)
    check()


@pytest.mark.slow
def test_fuzz_long(record, tmp_path, capsys, monkeypatch):
    """Every fuzz test above with the slow group's example counts."""
    monkeypatch.setitem(_LONG, "on", True)
    for sub in ("run", "wave", "npz", "tdms"):
        (tmp_path / sub).mkdir()
    for name in sorted(SHIPPED):
        test_fuzz_shipped_study_keys(name)
    test_fuzz_study_keys_through_run(tmp_path / "run", capsys)
    test_fuzz_waveform_files(record, tmp_path / "wave", capsys)
    for suffix in (".npz", ".tdms"):
        test_fuzz_binary_waveform_files(record, tmp_path / suffix[1:], capsys, suffix)
    for index in range(len(SWEEPS)):
        test_fuzz_sweep_specs(index)
    test_fuzz_command_arguments()
    test_fuzz_path_arguments_of_readers(tmp_path)


def test_fuzz_helpers_find_every_leaf():
    leaves = _leaves(SHIPPED["paper-mss"])
    assert ("chain", "beads") in leaves
    assert ("sensor", 1, "coil", "turns") in leaves
    assert tomllib.loads(dumps(SHIPPED["paper-mss"])) == SHIPPED["paper-mss"]

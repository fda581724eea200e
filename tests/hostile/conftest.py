"""Helpers of the hostile-input tests: a tiny study and a checked command run."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from msens.cli import main

#: Ten beads, a four-contact MsS at particle 6 and a bead sensor at 4: a run takes ~0.1 s.
TINY = """schema = "msens.study/1"
name = "tiny"
[chain]
beads = 10
damping = "linear-loading"
gamma_contact_kg_per_s = 4.7
[striker]
drop_height_m = 7.2e-3
[simulation]
t_end_s = 3.0e-4
sample_rate_hz = 5e6
[[sensor]]
kind = "bead"
particle = 4
[[sensor]]
kind = "bead"
particle = 8
"""


#: Twenty beads, bead sensors at 10 and 15, 0.8 ms: long enough that synthetic records of it
#: (with their trigger delay) hold both pulses after the trigger, so compare and diagnose
#: accept them.
TWENTY = (TINY.replace("beads = 10", "beads = 20").replace("particle = 4", "particle = 10")
          .replace("particle = 8", "particle = 15").replace("t_end_s = 3.0e-4", "t_end_s = 8.0e-4"))


def run_cli(argv: list[str], capsys: pytest.CaptureFixture, *, seconds: float = 20.0
            ) -> tuple[int, str]:
    """Run the command in-process; returns (exit status, stderr), checking the time bound."""
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert elapsed < seconds, f"{argv} took {elapsed:.1f} s"
    return code, err


def assert_input_error(code: int, err: str, *fragments: str) -> None:
    """Exit 2 with one 'msens: error:' line naming every fragment, no traceback."""
    lines = [line for line in err.splitlines() if line.startswith("msens: error:")]
    assert code == 2, err
    assert "Traceback" not in err and "internal error" not in err, err
    assert len(lines) == 1, err
    for f in fragments:
        assert f in lines[0], (f, lines[0])


@pytest.fixture
def tiny(tmp_path: Path):
    """A function writing the tiny study with text replacements (old -> new) applied."""
    def make(*changes: tuple[str, str], extra: str = "", name: str = "s.toml") -> Path:
        text = TINY
        for old, new in changes:
            assert old in text, old
            text = text.replace(old, new, 1)
        path = tmp_path / name
        path.write_text(text + extra)
        return path
    return make

"""The scripts in examples/ run as a newcomer runs them: each in its own process."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

pytest.importorskip("pandas")  # replace_parameter.py shows the DataFrames

# script -> text its output must contain; each takes 4-10 s once the chain kernel is compiled
CASES = {
    "run_default.py": "top            13    287.2",
    "replace_parameter.py": "unknown key 'striker.drop_heigth_m'",
    "synth_compare.py": "mss@18",
    "scope_export.py": "scope-mss.csv: 2435 samples",
}


def test_every_example_is_tested():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(CASES)


@pytest.mark.parametrize("script", sorted(CASES))
def test_example_runs(script, tmp_path):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, str(EXAMPLES / script), str(tmp_path / "out")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert CASES[script] in proc.stdout, proc.stdout[-3000:]
    assert "Traceback" not in proc.stderr

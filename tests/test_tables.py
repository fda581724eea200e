"""The text tables (``msens.tables``): plain formatting, no numerical library."""

from __future__ import annotations

import subprocess
import sys
from types import SimpleNamespace

from msens.tables import files_line, format_design


def test_tables_load_no_numerical_library():
    code = ("import sys, msens.tables; "
            "print(','.join(m for m in ('numpy', 'scipy', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60)
    assert out.stdout.strip() == ""


def test_design_table_without_a_recommendation():
    result = SimpleNamespace(kind="magnet", designs=3, failed=3, computed=1,
                             recommendation={"design": None, "reasons": ["all failed"]},
                             files=("a/designs.csv", "a/pareto.png"))
    assert format_design(result).splitlines() == [
        "magnet sweep: 3 designs (3 failed, 1 computed, 2 from cache)",
        "no recommended design: all failed", "wrote a/designs.csv, a/pareto.png"]
    assert files_line([]) == "wrote "

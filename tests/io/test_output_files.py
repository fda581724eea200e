"""Result files: strict JSON by value, normal permissions, never over a user's file."""

from __future__ import annotations

import json
import math
import os
import stat

import numpy as np
import pytest

from msens.errors import InputError
from msens.io.output import OutputDir, to_json


def test_json_is_strict_and_non_finite_numbers_become_null_by_value():
    data = {"study": "NaNotech", "folder": "NaNdir/Infinity", "a": math.nan,
            "b": [1.0, -math.inf, np.float64(np.inf)], "c": np.array([np.nan, 2.0]),
            "n": np.int64(3)}
    text = to_json(data)
    back = json.loads(text)  # strict: json.loads rejects NaN/Infinity only with a hook
    assert back == {"study": "NaNotech", "folder": "NaNdir/Infinity", "a": None,
                    "b": [1.0, None, None], "c": [None, 2.0], "n": 3}
    assert "NaN," not in text and "Infinity," not in text
    json.loads(text, parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))


def test_result_files_get_the_usual_permissions_and_user_files_are_kept(tmp_path):
    old = os.umask(0o022)
    try:
        d = OutputDir(tmp_path / "out")
        path = d.write_json("summary.json", {"x": 1})
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644
    (tmp_path / "out" / "mine.json").write_text("{}")
    with pytest.raises(InputError, match="refusing to overwrite"):
        d.write_json("mine.json", {"x": 2})
    assert (tmp_path / "out" / "mine.json").read_text() == "{}"

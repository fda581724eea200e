"""Plain-text maths in docstrings is escaped for reST, markup is left alone
(docs/_ext/plaintext.py: the docs build treats warnings as errors)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def plaintext():
    spec = importlib.util.spec_from_file_location("plaintext", ROOT / "docs" / "_ext" /
                                                  "plaintext.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize(("text", "expected"), [
    ("H = H(|B|) B/|B|", "H = H(\\|B\\|) B/\\|B\\|"),
    ("x**2 + a*b", "x\\*\\*2 + a\\*b"),
    ("shape (*broadcast(r, z).shape, 4)", "shape (\\*broadcast(r, z).shape, 4)"),
    ("these are *not* equal, **never**.", "these are *not* equal, **never**."),
    ("``|B|`` and :math:`|x|^2` and `a|b`_", "``|B|`` and :math:`|x|^2` and `a|b`_"),
    ("   | a | b |", "   | a | b |"),
    (">>> x**2", ">>> x**2"),
])
def test_escape(plaintext, text, expected):
    assert plaintext.escape(text) == expected


def test_literal_blocks_are_left_alone(plaintext):
    lines = ["Example::", "", "    y = x**2 | z", "", "after |B|"]
    plaintext.process_docstring(None, "function", "f", None, {}, lines)
    assert lines == ["Example::", "", "    y = x**2 | z", "", "after \\|B\\|"]

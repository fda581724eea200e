"""The README, LICENSE, CITATION.cff and CHANGELOG.md a new user reads first."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOI = "10.3390/s130101231"


def test_readme_is_short_cites_the_paper_and_keeps_the_two_commands():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 150
    assert DOI in text and "1231–1246" in text
    assert "pip install . && msens run" in text
    assert 'pip install ".[test]" && pytest -n auto --dist loadfile' in text


def test_readme_links_point_at_files_in_the_repository():
    text = (ROOT / "README.md").read_text()
    links = [t for t in re.findall(r"\]\(([^)\s]+)\)", text) if "://" not in t]
    assert links, "the README links into docs/"
    for target in links:
        assert (ROOT / target.split("#")[0]).exists(), target


def test_license_and_citation():
    assert "MIT License" in (ROOT / "LICENSE").read_text()
    assert "Copyright (c) 2026 The msens developers" in (ROOT / "LICENSE").read_text()
    cff = (ROOT / "CITATION.cff").read_text()
    assert re.search(r"^cff-version: 1\.2\.0$", cff, re.M)
    assert re.search(r"^message: ", cff, re.M) and re.search(r"^title: ", cff, re.M)
    assert re.search(r"^references:$", cff, re.M) and f"doi: {DOI}" in cff


def test_changelog_follows_keep_a_changelog():
    text = (ROOT / "CHANGELOG.md").read_text()
    assert text.startswith("# Changelog") and "## [Unreleased]" in text


def test_readme_python_example_runs(capsys):
    """The README's Python block runs as written (the built-in study, committed caches)."""
    text = (ROOT / "README.md").read_text()
    code = re.search(r"## Python\n\n```python\n(.*?)```", text, re.S).group(1)
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    coil = namespace["coil"]
    assert 0.1 < coil["peak_voltage_V"] < 2.0  # volts at the DAQ of coil 13
    record = namespace["record"]
    assert record.voltage.shape == record.t_daq.shape

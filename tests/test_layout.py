"""The tests mirror the source: ``tests/<package>/`` for each subpackage of msens,
``tests/test_<module>*.py`` for its top-level modules, and the folders that cut across them
(verification against exact and published results, hostile input, cross-command
integration, the documentation, test data)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "msens"

#: Test folders that are no package of msens, with what they hold.
ACROSS = {
    "verification": "exact solutions and published results",
    "hostile": "hostile input at the command line and the Python API",
    "integration": "workflows across commands",
    "docs": "the documentation and the README",
    "data": "study and waveform files the tests read",
}
#: Top-level test files of the package as a whole.
WHOLE = {"test_face.py", "test_import_order.py", "test_layout.py"}


def test_every_test_folder_is_a_package_or_says_what_it_holds():
    packages = {p.parent.name for p in SRC.glob("*/__init__.py")}
    folders = {p.name for p in (ROOT / "tests").iterdir()
               if p.is_dir() and not p.name.startswith((".", "_"))}
    stray = sorted(folders - packages - set(ACROSS))
    assert not stray, f"test folders that mirror no package of src/msens: {stray}"


def test_every_top_level_test_names_its_module():
    modules = {p.stem for p in SRC.glob("*.py") if not p.stem.startswith("_")}
    stray = sorted(p.name for p in (ROOT / "tests").glob("test_*.py")
                   if p.name not in WHOLE
                   and not any(p.stem == f"test_{m}" or p.stem.startswith(f"test_{m}_")
                               for m in modules))
    assert not stray, (f"top-level tests that name no top-level module of src/msens "
                       f"(move them into tests/<package>/ or tests/integration/): {stray}")

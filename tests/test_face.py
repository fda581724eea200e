"""The package's face (``msens/__init__.py``): its names, its cost, its workflow functions."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest

import msens

ROOT = Path(__file__).resolve().parents[1]


def test_every_face_name_resolves():
    missing = [n for n in msens.__all__ if not hasattr(msens, n)]
    assert not missing
    assert len(msens.__all__) == len(set(msens.__all__))
    assert set(msens.__all__) <= set(dir(msens))


def test_the_face_names_come_from_their_homes():
    from msens import api
    from msens.config.study import Study
    from msens.errors import InputError, InternalError
    from msens.results import StudyResult

    assert msens.run is api.run and msens.load_default is api.load_default
    assert msens.Study is Study and msens.StudyResult is StudyResult
    assert msens.InputError is InputError and msens.InternalError is InternalError


def test_version_is_the_installed_one():
    assert msens.__version__ == version("msens")


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        msens.no_such_name  # noqa: B018


def test_import_msens_is_cheap():
    """A bare ``import msens`` loads neither the compiled chain kernel nor the finite-element
    code nor the plotting library (the names load on first use)."""
    heavy = ("numba", "skfem", "gmsh", "meshio", "matplotlib", "scipy", "numpy")
    code = ("import sys, msens; "
            f"print(','.join(m for m in {heavy!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60)
    assert out.stdout.strip() == ""


def test_workflow_functions_survive_their_submodules_import():
    """``msens.field`` etc. stay the workflow functions after the subpackages of the same
    names are imported; the subpackages are still importable by name."""
    for name in ("compare", "design", "diagnose", "field", "synth"):
        module = importlib.import_module(f"msens.{name}")
        assert callable(getattr(msens, name)) and getattr(msens, name) is not module
        assert getattr(msens, name) is getattr(importlib.import_module("msens.api"), name)
    from msens.field import solve

    assert solve.__name__ == "msens.field.solve"


def _shadowing_imports(path: Path) -> list[str]:
    """``import msens.<workflow>...`` statements in a file: through the face they bind the
    workflow function, not the module (use ``from msens.<workflow> import ...``)."""
    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "msens" and len(parts) > 1 and parts[1] in msens._SHADOWED:
                    bad.append(f"{path.relative_to(ROOT)}:{node.lineno}: import {alias.name}")
    return bad


def test_nobody_imports_a_shadowed_module_by_attribute():
    files = [p for d in ("src", "tests", "benchmarks", "examples")
             for p in (ROOT / d).rglob("*.py")]
    bad = [b for p in files for b in _shadowing_imports(p)]
    assert not bad, "use 'from msens.X import Y' instead:\n" + "\n".join(bad)


@pytest.mark.slow
def test_run_the_default_study_from_the_face():
    """``msens.run(msens.load_default())``: the main study from the committed caches."""
    result = msens.run(msens.load_default())
    assert isinstance(result, msens.StudyResult)
    assert result.study.name == msens.load_default().name
    rows = result.rows()
    assert rows and all(r["tof_us"] > 0 for r in rows)


def _packages() -> list[str]:
    """Every public (sub)package of msens, by dotted name."""
    src = ROOT / "src"
    return sorted(".".join(p.parent.relative_to(src).parts)
                  for p in (src / "msens").rglob("__init__.py")
                  if not any(part.startswith("_") for part in p.parent.relative_to(src).parts))


def test_the_package_list_is_complete():
    assert {"msens.chain", "msens.config", "msens.design", "msens.diagnose", "msens.field",
            "msens.io", "msens.magnetics", "msens.mechanics", "msens.params", "msens.readout",
            "msens.signals"} <= set(_packages())


@pytest.mark.parametrize("package", _packages())
def test_every_public_package_lists_its_api(package):
    """``__all__`` exists, every name in it resolves, and none is also the name of a
    submodule (importing that submodule would replace the name on the package)."""
    module = importlib.import_module(package)
    assert isinstance(getattr(module, "__all__", None), list | tuple), f"{package}: no __all__"
    assert len(module.__all__) == len(set(module.__all__))
    missing = [n for n in module.__all__ if not hasattr(module, n)]
    assert not missing, f"{package}.__all__ names what it does not define: {missing}"
    folder = Path(module.__file__).parent
    submodules = {p.stem for p in folder.glob("*.py")} | {p.parent.name
                                                           for p in folder.glob("*/__init__.py")}
    shadowed = msens._SHADOWED if package == "msens" else frozenset()  # the face's own rule
    clash = sorted(n for n in set(module.__all__) & submodules - shadowed
                   if getattr(module, n) is not importlib.import_module(f"{package}.{n}"))
    assert not clash, f"{package}.__all__ names that are also submodules: {clash}"
    namespace: dict = {}
    exec(f"from {package} import *", namespace)  # the star import a user may write
    assert set(module.__all__) <= set(namespace)


def test_a_light_module_does_not_load_its_heavy_siblings():
    """``msens.mechanics.hertz`` (needed by the chain) without scikit-fem."""
    code = "import sys, msens.mechanics.hertz; print('skfem' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60)
    assert out.stdout.strip() == "False"


def test_python_dash_m_msens_is_the_command():
    """``python -m msens`` runs the ``msens`` command: its help, its version, its exit codes."""
    def run(*args):
        return subprocess.run([sys.executable, "-m", "msens", *args], capture_output=True,
                              text=True, timeout=120)

    out = run("--help")
    assert out.returncode == 0 and out.stdout.startswith("usage: msens")
    assert "compare" in out.stdout and "diagnose" in out.stdout
    out = run("--version")
    assert out.returncode == 0 and version("msens") in out.stdout
    out = run("run", "no-such-study.toml")
    assert out.returncode == 2 and "no-such-study.toml" in out.stderr
    assert "Traceback" not in out.stderr

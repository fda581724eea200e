"""The import graph follows the data flow: no module imports a higher stage, no cycles.

Every top-level unit of ``src/msens`` (a module, or a subpackage as a whole) has a stage,
from the foundations (errors, parameters, file formats) through mechanics, read-out and
signals, the chain and the field model, the transducer core, the study configuration (which
maps a study onto those models, so no model knows the study schema) and the results to the
workflows and the command line. A unit may import its own stage or lower ones; imports
inside functions count too, as do relative imports and ``importlib.import_module`` with a
literal name. A unit missing from ``STAGES`` fails the test: give it its place.

Two graphs are checked for cycles: the modules', and the units' (a subpackage as one node),
so two units of one stage may not import each other even through different modules. An
exception is an explicit, commented entry of ``ALLOWED``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "msens"

#: Stage of every top-level unit, lowest first.
STAGES = {
    0: ("errors", "version", "parallel", "meshing", "vocabulary", "_lazy", "progress",
        "numba_cache"),
    1: ("params", "io", "store", "numba_cache_file"),
    2: ("mechanics", "readout", "signals"),
    3: ("chain", "field"),
    4: ("calibrate",),
    5: ("magnetics",),
    6: ("config",),
    7: ("results", "tables"),
    8: ("budget", "preflight", "pipeline", "synth", "compare", "field_outputs"),
    9: ("plots", "plots_mss"),
    10: ("design", "diagnose", "workflows", "uq"),
    11: ("api",),
    12: ("cli",),
    13: ("__main__",),
}
STAGE = {unit: k for k, units in STAGES.items() for unit in units}

#: Imports that break the order on purpose, as ("importing module", "imported module") with
#: the reason; none today. An entry that no longer matches an import fails the test.
ALLOWED: dict[tuple[str, str], str] = {}


def _modules() -> dict[str, Path]:
    out = {}
    for path in SRC.rglob("*.py"):
        parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _package(module: str, path: Path) -> str:
    """The package a module's relative imports start from."""
    return module if path.name == "__init__.py" else module.rpartition(".")[0]


def _imports(module: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """msens modules imported anywhere in a file, at module level or inside functions
    (``from pkg import sub`` names ``pkg.sub``; ``from . import x`` is resolved)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = _package(module, path).split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "msens":
                continue
            subs = [f"{target}.{a.name}" for a in node.names]
            found.update(s for s in subs if s in modules)
            if any(s not in modules for s in subs):
                found.add(target)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name in modules)
        elif isinstance(node, ast.Call) and node.args \
                and isinstance(node.args[0], ast.Constant) \
                and isinstance(node.args[0].value, str) and node.args[0].value in modules \
                and getattr(node.func, "attr", getattr(node.func, "id", "")) == "import_module":
            found.add(node.args[0].value)
    return found


def _unit(module: str) -> str:
    return module.split(".")[1] if module.count(".") else ""


MODULES = _modules()
GRAPH = {m: _imports(m, p, MODULES) - {m} for m, p in MODULES.items()}


def _checked(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """``graph`` without the allowed edges."""
    return {a: {b for b in targets if (a, b) not in ALLOWED} for a, targets in graph.items()}


def _unit_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The graph of top-level units: an edge where any module of one imports any of another
    (the face, ``msens/__init__.py``, is the top and is left out)."""
    units: dict[str, set[str]] = {}
    for a, targets in graph.items():
        if _unit(a):
            units.setdefault(_unit(a), set()).update(
                _unit(b) for b in targets if _unit(b) and _unit(b) != _unit(a))
    return units


def _upward(graph: dict[str, set[str]]) -> list[str]:
    return sorted(f"{a} -> {b}" for a, targets in graph.items() for b in targets
                  if _unit(a) in STAGE and _unit(b) in STAGE
                  and STAGE[_unit(b)] > STAGE[_unit(a)])


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one node (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, children = work[-1]
            w = next(children, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_every_unit_has_a_stage():
    units = {_unit(m) for m in MODULES} - {""}
    missing = sorted(units - set(STAGE))
    assert not missing, f"give these a stage in tests/test_import_order.py: {missing}"


def test_the_graph_sees_every_kind_of_import(tmp_path):
    """Module-level, function-level, relative and ``import_module`` imports are all edges."""
    pkg = tmp_path / "msens" / "field"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    probe = pkg / "probe.py"
    probe.write_text("import msens.errors\n"
                     "def f():\n    from msens.chain import model\n"
                     "    from .. import config\n    from . import solve\n"
                     "    import importlib\n    importlib.import_module('msens.results')\n")
    modules = {m: Path() for m in ("msens.errors", "msens.chain", "msens.chain.model",
                                   "msens.config", "msens.field.solve", "msens.results")}
    assert _imports("msens.field.probe", probe, modules) == {
        "msens.errors", "msens.chain.model", "msens.config", "msens.field.solve",
        "msens.results"}


def test_the_checks_find_upward_imports_and_cycles():
    graph = {"msens.chain.a": {"msens.field.b"}, "msens.field.b": {"msens.chain.c"},
             "msens.chain.c": set(), "msens.api": {"msens.cli"}}
    assert _upward(graph) == ["msens.api -> msens.cli"]
    assert _cycles(_unit_graph(graph)) == [["chain", "field"]]  # no module cycle, a unit one
    assert not _cycles(graph)
    assert _cycles({"a": {"b"}, "b": {"a"}, "c": {"a"}}) == [["a", "b"]]


def test_the_allowed_exceptions_still_exist():
    stale = [edge for edge in ALLOWED if edge[1] not in GRAPH.get(edge[0], set())]
    assert not stale, f"remove these from ALLOWED: {stale}"


def test_no_module_imports_a_higher_stage():
    upward = _upward(_checked(GRAPH))
    assert not upward, "upward imports:\n" + "\n".join(upward)


def test_no_import_cycles_between_modules():
    cycles = _cycles(_checked(GRAPH))
    assert not cycles, f"import cycles: {cycles}"


def test_no_import_cycles_between_units():
    cycles = _cycles(_unit_graph(_checked(GRAPH)))
    assert not cycles, f"import cycles between top-level units: {cycles}"


@pytest.mark.parametrize("low,high", [("chain", "field"), ("field", "chain")])
def test_the_chain_and_the_field_model_do_not_know_each_other(low, high):
    crossing = [f"{a} -> {b}" for a, targets in GRAPH.items() for b in targets
                if _unit(a) == low and _unit(b) == high]
    assert not crossing, crossing

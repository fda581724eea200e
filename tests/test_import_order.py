"""The import graph follows the data flow: no module imports a higher stage, no cycles.

Every top-level unit of ``src/msens`` (a module, or a subpackage as a whole) has a stage,
from the foundations (errors, parameters, file formats) through mechanics, read-out and
signals, the chain and the field model, the transducer core, the study configuration (which
maps a study onto those models, so no model knows the study schema) and the results to the
workflows and the command line. A unit may import its own stage or lower ones; imports
inside functions count too. A unit missing from ``STAGES`` fails the test: give it its place.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "msens"

#: Stage of every top-level unit, lowest first.
STAGES = {
    0: ("errors", "version", "parallel", "meshing", "vocabulary", "_lazy"),
    1: ("params", "io", "store"),
    2: ("mechanics", "readout", "signals"),
    3: ("chain", "field"),
    4: ("calibrate",),
    5: ("magnetics",),
    6: ("config",),
    7: ("results",),
    8: ("budget", "preflight", "pipeline", "synth", "compare", "field_outputs"),
    9: ("plots", "plots_mss"),
    10: ("design", "diagnose"),
    11: ("api",),
    12: ("cli",),
}
STAGE = {unit: k for k, units in STAGES.items() for unit in units}


def _modules() -> dict[str, Path]:
    out = {}
    for path in SRC.rglob("*.py"):
        parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _imports(path: Path, modules: dict[str, Path]) -> set[str]:
    """msens modules imported anywhere in a file (``from pkg import sub`` names ``pkg.sub``)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0 \
                and node.module.split(".")[0] == "msens":
            subs = [f"{node.module}.{a.name}" for a in node.names]
            found.update(s for s in subs if s in modules)
            if any(s not in modules for s in subs):
                found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name in modules)
    return found


def _unit(module: str) -> str:
    return module.split(".")[1] if module.count(".") else ""


MODULES = _modules()
GRAPH = {m: _imports(p, MODULES) - {m} for m, p in MODULES.items()}


def test_every_unit_has_a_stage():
    units = {_unit(m) for m in MODULES} - {"", "__main__"}
    missing = sorted(units - set(STAGE))
    assert not missing, f"give these a stage in tests/test_import_order.py: {missing}"


def test_no_module_imports_a_higher_stage():
    upward = [f"{a} -> {b}" for a, targets in GRAPH.items() for b in targets
              if _unit(a) in STAGE and _unit(b) in STAGE and STAGE[_unit(b)] > STAGE[_unit(a)]]
    assert not upward, "upward imports:\n" + "\n".join(sorted(upward))


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
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


def test_no_import_cycles():
    assert _cycles({"a": {"b"}, "b": {"a"}, "c": {"a"}}) == [["a", "b"]]  # the check works
    cycles = _cycles(GRAPH)
    assert not cycles, f"import cycles: {cycles}"


@pytest.mark.parametrize("low,high", [("chain", "field"), ("field", "chain")])
def test_the_chain_and_the_field_model_do_not_know_each_other(low, high):
    crossing = [f"{a} -> {b}" for a, targets in GRAPH.items() for b in targets
                if _unit(a) == low and _unit(b) == high]
    assert not crossing, crossing

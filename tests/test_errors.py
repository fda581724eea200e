"""The error boundary: bad input is :class:`InputError` (exit 2), a broken invariant of msens
is :class:`InternalError` (exit 1, "a bug in msens"), and the source keeps the two apart."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from msens.cli import main
from msens.errors import InputError, InternalError, internal, require

SRC = Path(__file__).resolve().parents[1] / "src" / "msens"


def test_the_two_roles_are_distinct_types():
    assert not issubclass(InternalError, InputError)
    assert not issubclass(InputError, InternalError)
    with pytest.raises(InternalError, match="broken"):
        internal(False, "internal: broken")
    with pytest.raises(InputError, match="bad"):
        require(False, "bad")
    internal(True, "never raised")
    require(True, "never raised")


def test_an_internal_error_exits_1_and_says_it_is_a_bug(monkeypatch, capsys):
    """An :class:`InternalError` from inside a workflow: one line, exit 1, "bug in msens",
    never the exit 2 of bad input; the traceback only with ``--debug``."""
    import msens.cli as cli

    def broken(args):
        internal(False, "internal: contact 12-13 flat not found")

    monkeypatch.setitem(cli._COMMANDS, "verify", broken)
    monkeypatch.delenv(cli.DEBUG_ENV, raising=False)
    assert main(["verify"]) == 1
    err = capsys.readouterr().err
    # one line about the error (after the command's first line, "msens: verify: ...")
    lines = [line for line in err.strip().splitlines() if not line.startswith("msens: verify:")]
    assert len(lines) == 1, err
    assert lines[0].startswith("msens: internal error (InternalError: internal: contact 12-13")
    assert "bug in msens" in lines[0] and "report" in lines[0]
    assert "msens: error:" not in err and "Traceback" not in err
    assert main(["--debug", "verify"]) == 1
    assert "Traceback" in capsys.readouterr().err


def _misfiled_invariants(path: Path, root: Path = SRC) -> list[str]:
    """Checks of msens's own invariants ("internal: ..." messages) raised as anything but an
    internal error: ``require(..., "internal: ...")`` (an InputError, exit 2) or
    ``raise ValueError/RuntimeError("internal: ...")``."""
    def says_internal(node: ast.AST | None) -> bool:
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            return node.value.lstrip().startswith("internal")
        if isinstance(node, ast.JoinedStr) and node.values:
            return says_internal(node.values[0])
        return False

    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            name = node.func.id
            if name == "require" and len(node.args) > 1 and says_internal(node.args[1]):
                bad.append(f"{path.relative_to(root)}:{node.lineno}: require(..., 'internal')")
            elif name != "InternalError" and name.endswith("Error") and node.args \
                    and says_internal(node.args[0]):
                bad.append(f"{path.relative_to(root)}:{node.lineno}: {name}('internal ...')")
    return bad


def test_the_check_finds_misfiled_invariants(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text('require(x, "internal: a")\nraise RuntimeError(f"internal: {x}")\n'
                     'internal(x, "internal: fine")\nraise InternalError("internal: fine")\n'
                     'require(x, "user input")\n')
    assert len(_misfiled_invariants(probe, tmp_path)) == 2


def test_no_invariant_check_reports_a_bug_as_bad_input():
    bad = [b for p in sorted(SRC.rglob("*.py")) for b in _misfiled_invariants(p)]
    assert not bad, "use msens.errors.internal / InternalError:\n" + "\n".join(bad)

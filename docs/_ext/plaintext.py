"""Plain-text mathematics in docstrings, made safe for reST.

msens docstrings write formulas as plain text: absolute values ``|B|``, powers ``x**2``,
products ``a*b``, unpacking ``(*shape, 4)``. reST reads ``|...|`` as a substitution and ``*`` as
emphasis, and the docs build (warnings as errors) would fail on them. :func:`escape` escapes
those characters outside inline literals, roles and interpreted text, and leaves table rows,
line blocks and directives alone; the ``autodoc-process-docstring`` hook of ``msens_docs``
applies it to every docstring, :mod:`apiref` to its summary lines.
"""

from __future__ import annotations

import re

#: Inline literals, roles with their content, and interpreted text: left as they are.
_PROTECTED = re.compile(r"(``.+?``|:[\w:.+-]+:`[^`]*`|`[^`]*`_{0,2})")
#: ``*`` used as an operator or for unpacking: between word characters or brackets
#: (``x**2``, ``a*b``, ``(*shape``), not the ``*emphasis*`` that follows a space.
_STAR = re.compile(r"(?<=[\w)\]([{,])(\*+)(?=[\w(\[])")


def escape(line: str) -> str:
    """``line`` with its plain-text ``|`` and operator ``*`` escaped for reST."""
    stripped = line.lstrip()
    if stripped.startswith(("|", "+-", "+=", "..", ">>>", "...")):
        return line  # table rows, line blocks, directives, doctest lines
    parts = _PROTECTED.split(line)
    for i in range(0, len(parts), 2):  # the even parts are outside the protected spans
        text = parts[i].replace("|", "\\|")
        parts[i] = _STAR.sub(lambda m: "\\*" * len(m.group(1)), text)
    return "".join(parts)


def process_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    """``autodoc-process-docstring`` hook: escape every line (see :func:`escape`)."""
    in_literal_block = False
    block_indent = 0
    for i, line in enumerate(lines):
        indent = len(line) - len(line.lstrip())
        if in_literal_block:
            if line.strip() and indent <= block_indent:
                in_literal_block = False
            else:
                continue
        lines[i] = escape(line)
        if line.rstrip().endswith("::") or line.lstrip().startswith(".. code"):
            in_literal_block, block_indent = True, indent

"""Sphinx extension of the msens docs: writes the generated pages before the sources are read.

- ``_generated/study-reference.rst`` and ``_generated/sweep-reference.rst`` from the
  study and sweep readers and their records (:mod:`studyref`);
- ``_generated/api-*.rst`` from ``msens.__all__`` and the subpackages' ``__all__``
  (:mod:`apiref`);

runs ``msens verify`` for the validation page (``_generated/verify.txt``),
and makes the plain-text mathematics of docstrings (``|B|``, ``x**2``) safe for reST
(:mod:`plaintext`).
"""

from __future__ import annotations

from pathlib import Path

import apiref
import plaintext
import studyref


def _verify_table(target: Path) -> None:
    """``msens verify``'s table, computed now: the validation page includes it."""
    from msens.field.verify import format_table, run_all

    text = format_table(run_all()) + "\n"
    if not target.exists() or target.read_text() != text:
        target.write_text(text)


def _generate(app) -> None:
    docs = Path(app.srcdir)
    (docs / "_generated").mkdir(exist_ok=True)
    _verify_table(docs / "_generated" / "verify.txt")
    studyref.write_rst(docs.parent, docs / "_generated" / "study-reference.rst")
    studyref.write_sweep_rst(docs / "_generated" / "sweep-reference.rst")
    apiref.write_api(docs / "_generated")


def setup(app):
    app.connect("builder-inited", _generate)
    # numpydoc registers its own handler at priority 500: escape before it parses
    app.connect("autodoc-process-docstring", plaintext.process_docstring, priority=400)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

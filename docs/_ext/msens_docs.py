"""Sphinx extension of the msens docs: writes the generated pages before the sources are read.

- ``_generated/study-reference.rst`` from the study readers and the schema
  (:mod:`studyref`);
- ``_generated/api-*.rst`` from ``msens.__all__`` and the subpackages' ``__all__``
  (:mod:`apiref`).
"""

from __future__ import annotations

from pathlib import Path

import apiref
import studyref


def _generate(app) -> None:
    docs = Path(app.srcdir)
    studyref.write_rst(docs.parent, docs / "_generated" / "study-reference.rst")
    apiref.write_api(docs / "_generated")


def setup(app):
    app.connect("builder-inited", _generate)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

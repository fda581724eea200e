"""Write a study back to TOML: what ``msens study`` prints and saves.

A study keeps the TOML document it was validated from (:func:`msens.config.study.parse_study`,
including the keys :meth:`~msens.config.study.Study.replace` changed); :func:`study_toml`
writes that document, so reading the text again gives an equal study
(:func:`msens.config.study.parse_study`). A relative ``[measurement] file`` is written as
an absolute path, so the saved file works from any folder.

:func:`format_toml` writes any document of TOML values (tables, arrays of tables, arrays,
strings, numbers, booleans) that :mod:`tomllib` reads back equal.
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Mapping
from typing import Any

from msens.config.study import Study
from msens.errors import InputError, InternalError

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def study_toml(study: Study) -> str:
    """The TOML text of ``study`` (schema ``msens.study/1``).

    Parameters
    ----------
    study : Study
        A study read from a file or text (also after :meth:`Study.replace`).

    Returns
    -------
    str
        A TOML document whose :func:`~msens.config.study.parse_study` equals ``study``
        (all fields but ``source``).

    Raises
    ------
    InputError
        If the study was built in memory rather than read (it has no document).
    """
    state = getattr(study, "_document", None)
    if state is None:
        raise InputError(f"study {study.name!r} was not read from a study file, so it has no "
                         "TOML document to write")
    document, _ = state
    document = copy.deepcopy(dict(document))
    measurement = document.get("measurement")
    if isinstance(measurement, dict) and study.measurement_file is not None:
        measurement["file"] = str(study.measurement_file.resolve())
    origin = "".join(c if c.isprintable() else " " for c in f"{study.name!r}, written from "
                     f"{study.source}")  # one comment line, whatever the names hold
    header = f"# msens study {origin}\n"
    return header + format_toml(document)


def format_toml(document: Mapping[str, Any]) -> str:
    """TOML text of ``document`` (plain values first, then tables and arrays of tables).

    Raises
    ------
    InternalError
        For a value TOML cannot hold (None, or an object that is not a TOML value).
    """
    lines: list[str] = []
    _table(document, (), lines)
    return "\n".join(lines).lstrip("\n") + "\n"


def _is_table_array(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, Mapping)
                                                            for v in value)


def _table(table: Mapping[str, Any], path: tuple[str, ...], lines: list[str]) -> None:
    plain = [(k, v) for k, v in table.items()
             if not isinstance(v, Mapping) and not _is_table_array(v)]
    for key, value in plain:
        lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in table.items():
        if isinstance(value, Mapping):
            sub = (*path, key)
            has_plain = any(not isinstance(v, Mapping) and not _is_table_array(v)
                            for v in value.values())
            if has_plain or not value:  # a header only where it holds keys (or is empty)
                lines += ["", f"[{'.'.join(map(_key, sub))}]"]
            _table(value, sub, lines)
        elif _is_table_array(value):
            sub = (*path, key)
            for item in value:
                lines += ["", f"[[{'.'.join(map(_key, sub))}]]"]
                _table(item, sub, lines)


def _key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _string(key)


def _string(text: str) -> str:
    out = ['"']
    for ch in text:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        text = repr(value)
        return text if any(c in text for c in ".eEn") else text + ".0"
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, Mapping):  # a table inside an array of mixed values
        return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise InternalError(f"cannot write {type(value).__name__} {value!r} as a TOML value")

"""The study-file reference, generated from the readers and the schema.

Every key of a study file is read through :class:`msens.io.tomlreader.Table`. This module
runs the study readers (:mod:`msens.config.study` and its ``read_*`` modules) on a few probe
documents that together take every branch (each damping law, a drop height and a velocity,
a magnet by grade and by remanence, ``[[setup]]`` tables, every optional table), with a
:class:`Table` that records each call: the key, its table, its type, default, allowed range
and choices, exactly as the reader passes them. The description and unit of each key come
from the ``Attributes`` section of the record it fills (:mod:`msens.config.schema`, the
:class:`~msens.config.study.Study` and :class:`~msens.readout.electronics.ElectronicsSpec`
docstrings); a key's unit is read from its name's SI suffix (``_m``, ``_kg_per_s``, ``_F``)
or, for keys without one, from a ``Unit: ...`` sentence of its description.

:func:`reference` returns the keys; :func:`write_rst` writes the docs page (called from
``docs/conf.py`` at every build); ``tests/docs/test_study_reference.py`` fails when a key
lacks a unit or a description.
"""

from __future__ import annotations

import copy
import inspect
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from msens.config import schema, study
from msens.io.tomlreader import Table
from msens.readout.electronics import ElectronicsSpec


@dataclass
class Key:
    """One study key as the readers read it.

    Attributes
    ----------
    table : str
        Its table, arrays of tables written ``[[...]]``-style as ``sensor[]``.
    name : str
        The key as written in the file.
    kind : str
        ``number``, ``integer``, ``string``, ``boolean``, ``table``, ``array of tables`` or
        ``value`` (checked by the reader itself).
    default : Any
        What an absent key means (``None``: nothing, or required when ``required``).
    required : bool
    low, high : float or None
        The allowed range the reader checks, ``low_open`` for an open lower bound.
    choices : tuple of str or None
    unit, description : str
        From the schema's docstrings ('' when missing: the test fails on it).
    record : str
        The documented record that carries the key's value.
    """

    table: str
    name: str
    kind: str
    default: Any = None
    required: bool = False
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    choices: tuple[str, ...] | None = None
    unit: str = ""
    description: str = ""
    record: str = ""
    order: int = 1_000  # position of its entry in the record's Attributes (page order)

    @property
    def dotted(self) -> str:
        return f"{self.table}.{self.name}" if self.table else self.name


# --------------------------------------------------------------------------- recording


class _Recorder:
    def __init__(self) -> None:
        self.keys: dict[tuple[str, str], Key] = {}

    def add(self, path: str, name: str, kind: str, **info: Any) -> None:
        table = re.sub(r"\[\d+\]", "[]", path)
        key = (table, name)
        entry = self.keys.get(key)
        if entry is None:
            self.keys[key] = Key(table=table, name=name, kind=kind, **info)
            return
        # the same key read again (another branch, or raw first and then typed): keep the
        # most specific kind and every piece of information given
        if entry.kind == "value" and kind != "value":
            entry.kind = kind
        for attr, value in info.items():
            old = getattr(entry, attr)
            if (old is None or old is False) and not (value is None or value is False):
                setattr(entry, attr, value)


class _RecordingTable(Table):
    """A :class:`Table` that tells a :class:`_Recorder` every key it is asked for."""

    def __init__(self, data, path, source, recorder: _Recorder):
        super().__init__(data, path, source)
        self._rec = recorder

    def number(self, name, default=None, *, required=False, low=None, high=None,
               low_open=False, allow_none=False):
        self._rec.add(self._path, name, "number", default=default, required=required,
                      low=low, high=high, low_open=low_open)
        return super().number(name, default, required=required, low=low, high=high,
                              low_open=low_open, allow_none=allow_none)

    def integer(self, name, default=None, *, required=False, low=None, high=None):
        self._rec.add(self._path, name, "integer", default=default, required=required,
                      low=low, high=high)
        return super().integer(name, default, required=required, low=low, high=high)

    def string(self, name, default=None, *, required=False, choices=None):
        self._rec.add(self._path, name, "string", default=default, required=required,
                      choices=None if choices is None else tuple(choices))
        return super().string(name, default, required=required, choices=choices)

    def boolean(self, name, default=None, *, required=False):
        self._rec.add(self._path, name, "boolean", default=default, required=required)
        return super().boolean(name, default, required=required)

    def raw(self, name, default=None):
        self._rec.add(self._path, name, "value", default=default)
        return super().raw(name, default)

    def table(self, name, *, required=False):
        self._rec.add(self._path, name, "table", required=required)
        value = super().table(name, required=required)
        if value is None:
            return None
        return _RecordingTable(value.data, value._path, self._source, self._rec)

    def tables(self, name):
        self._rec.add(self._path, name, "array of tables")
        return [_RecordingTable(t.data, t._path, self._source, self._rec)
                for t in super().tables(name)]


def _probes(root: Path) -> list[tuple[str, dict, Path]]:
    """Documents that take every branch of the readers."""
    import tomllib

    mss = tomllib.loads((root / "studies" / "paper-mss.toml").read_text())
    table2 = tomllib.loads((root / "studies" / "paper-table2.toml").read_text())
    probes = [("paper-mss", mss, root), ("paper-table2", table2, root)]

    hkk = copy.deepcopy(mss)
    hkk["chain"]["damping"] = "hertz-kuwabara-kono"
    for k in ("gamma_contact_kg_per_s", "gamma_wall_kg_per_s"):
        hkk["chain"].pop(k)
    hkk["striker"] = {"velocity_m_per_s": 0.3}
    hkk["sensor"][0]["magnet"] = {"remanence_T": 0.4, "recoil_permeability": 1.1,
                                  "inner_radius_m": 6e-3}
    hkk["sensor"][0]["coil"]["packing_factor"] = 0.6
    hkk["sensor"][0]["coil"]["axial_offset_m"] = 0.0
    hkk["field"] = {"beads": [2, 30], "contact_load_N": 2.0, "eddy_currents": True,
                    "skin_size_m": 4e-5, "small_signal_permeability": "reversible",
                    "reversibility": 0.1, "steel_bh": [[0, 0], [1.0, 800.0], [2.0, 4e5]]}
    hkk["electronics"].update({"adc_bits": 12, "adc_range_V": 1.0})
    hkk["chain"]["insert"] = [{"particle": 5, "kind": "rod"}]
    hkk["precompression"] = [{"contacts": [11, 14], "force_N": 1.8}]
    hkk["measurement"] = {"file": "examples/data/scope-mss.csv"}
    probes.append(("branches", hkk, root))
    return probes


def _record(root: Path) -> _Recorder:
    rec = _Recorder()
    for name, doc, base in _probes(root):
        table = _RecordingTable(doc, "", name, rec)
        table.string("schema", required=True)
        study._study(table, name, base)
    return rec


# --------------------------------------------------------------------------- descriptions

#: The record whose docstring documents the keys of each table (arrays as ``name[]``).
RECORDS: dict[str, type] = {
    "": study.Study,
    "chain": schema.ChainSpec,
    "chain.wall": schema.WallSpec,
    "chain.insert[]": schema.InsertSpec,
    "striker": schema.StrikerSpec,
    "sensor[]": schema.SensorSpec,
    "sensor[].coil": schema.CoilSpec,
    "sensor[].magnet": schema.MagnetSpec,
    "precompression[]": schema.PrecompressionSpec,
    "setup[]": schema.SetupSpec,
    "setup[].insert[]": schema.InsertSpec,
    "setup[].sensor[]": schema.SensorSpec,
    "setup[].sensor[].coil": schema.CoilSpec,
    "setup[].sensor[].magnet": schema.MagnetSpec,
    "setup[].precompression[]": schema.PrecompressionSpec,
    "simulation": schema.SimulationSpec,
    "electronics": ElectronicsSpec,
    "field": schema.FieldSpec,
    "calibration": study.Study,
    "calibration.dissipation": schema.DissipationFitSpec,
    "reference": study.Study,
    "reference.row[]": schema.ReferenceRow,
    "measurement": study.Study,
}

#: SI suffixes of key names and the unit each stands for (longest first when matched).
SUFFIXES: dict[str, str] = {
    "kg_per_s_sqrt_m": "kg/(s m^0.5)",
    "v_per_rthz": "V/√Hz",
    "s_per_m": "S/m",
    "kg_per_s": "kg/s",
    "m_per_s2": "m/s²",
    "m_per_s": "m/s",
    "kg_per_m3": "kg/m³",
    "pa": "Pa",
    "kg": "kg",
    "ohm": "Ω",
    "hz": "Hz",
    "us": "µs",
    "m": "m",
    "s": "s",
    "n": "N",
    "t": "T",
    "f": "F",
    "k": "K",
    "v": "V",
}


def _attributes(cls: type) -> list[tuple[list[str], str, str]]:
    """``(names, type, description)`` of the numpydoc ``Attributes`` section of ``cls``."""
    doc = inspect.getdoc(cls) or ""
    lines = doc.splitlines()
    try:
        start = next(i for i, line in enumerate(lines[:-1])
                     if line.strip() == "Attributes" and set(lines[i + 1].strip()) == {"-"})
    except StopIteration:
        return []
    out: list[tuple[list[str], str, list[str]]] = []
    for line in lines[start + 2:]:
        if line and not line.startswith(" "):
            if set(line.strip()) == {"-"}:  # the next section's underline
                out.pop() if out and not out[-1][2] else None
                break
            names, _, typ = line.partition(" : ")
            out.append(([n.strip() for n in names.split(",")], typ.strip(), []))
        elif out:
            out[-1][2].append(line.strip())
    return [(names, typ, " ".join(d).strip()) for names, typ, d in out]


def _suffix_unit(name: str) -> str:
    low = name.lower()
    for suffix in SUFFIXES:
        if low.endswith("_" + suffix):
            return SUFFIXES[suffix]
    return ""


_UNIT_SENTENCE = re.compile(r"\s*Unit:\s*([^.]*[^.\s])\.?\s*$")


def _describe(key: Key, records: dict[str, tuple[type, ...]] | None = None) -> None:
    classes = (records or {}).get(key.table) or (
        (RECORDS[key.table],) if key.table in RECORDS else ())
    if not classes:
        return
    cls = classes[0]
    key.record = f"{cls.__module__}.{cls.__qualname__}"
    entries = [e for c in classes for e in _attributes(c)]
    lname = key.name.lower()
    match = None
    for rule in (
        lambda names, text: lname in (n.lower() for n in names),
        lambda names, text: f"``{key.name}``" in text,  # the docs name the TOML key
        lambda names, text: any(lname.startswith(n.lower() + "_") for n in names),
        lambda names, text: any(n.lower().startswith(lname + "_") for n in names),
    ):
        match = next(((n, names, typ, text) for n, (names, typ, text) in enumerate(entries)
                      if rule(names, text)), None)
        if match is not None:
            break
    if match is None:
        return
    key.order, names, _typ, text = match
    unit = _suffix_unit(key.name)
    found = _UNIT_SENTENCE.search(text)
    if found:
        text = text[:found.start()].rstrip()
        unit = unit or found.group(1)
    if not unit:
        for n in names:
            if n.lower().startswith(lname) or lname.startswith(n.lower()):
                unit = _suffix_unit(n)
                if unit:
                    break
    if not unit and key.kind in ("string", "boolean", "table", "array of tables"):
        unit = "—"
    key.unit = unit
    key.description = text


def reference(root: str | Path) -> list[Key]:
    """Every study key with its table, type, default, range, unit and description.

    Parameters
    ----------
    root : str or Path
        The repository (its ``studies/`` and ``examples/data/`` feed the probe documents).
    """
    rec = _record(Path(root))
    keys = [k for k in rec.keys.values() if k.kind not in ("table", "array of tables")]
    for key in keys:
        _describe(key)
    return keys


def missing(keys: list[Key]) -> list[str]:
    """The dotted names of ``keys`` that lack a unit or a description."""
    return [k.dotted + (" (no unit)" if not k.unit else "")
            + (" (no description)" if not k.description else "")
            for k in keys if not k.unit or not k.description]


def reader_keys() -> set[str]:
    """Every key name the readers ask a :class:`Table` for, found in their source: the
    string literals passed to ``number``, ``integer``, ``string``, ``boolean``, ``raw``,
    ``has``, ``table`` and ``tables`` (and the keys of a loop over a literal tuple of names)."""
    import ast

    from msens.config import read_chain, read_options, read_setups

    names: set[str] = set()
    methods = {"number", "integer", "string", "boolean", "raw", "table", "tables"}
    for module in (read_chain, read_options, read_setups, study):
        tree = ast.parse(inspect.getsource(module))
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr in methods and node.args
                    and isinstance(node.args[0], ast.Constant)
                    and isinstance(node.args[0].value, str)):
                names.add(node.args[0].value)
            if (isinstance(node, ast.For) and isinstance(node.iter, ast.Tuple)
                    and all(isinstance(e, ast.Constant) and isinstance(e.value, str)
                            for e in node.iter.elts)):
                names.update(e.value for e in node.iter.elts)
    return names


def sweep_reference() -> list[Key]:
    """Every key of a sweep file (schema ``msens.sweep/1``, :mod:`msens.design.sweep`).

    ``[coil]`` and ``[magnet]`` take the parameters of ``COIL_PARAMETERS`` and
    ``MAGNET_PARAMETERS`` (each a value, a list, or a range table ``{start, stop, num}`` or
    ``{start, stop, step}``), described by the study's coil and magnet records; the other
    tables are recorded from the reader (:func:`msens.design.sweep.parse_sweep`) on a probe.
    """
    from msens.design import sweep as sw

    rec = _Recorder()
    probe = {"schema": sw.SCHEMA, "name": "probe", "sensor": 13,
             "coil": {"turns": [600, 1100]},
             "magnet": {"grade": ["ceramic8"]},
             "model": {"bead_padding": 4, "contact_map": False, "verify": 2},
             "recommend": {"objective": "snr", "min_bandwidth_Hz": 5e4,
                           "max_precompression_N": 5.0, "min_snr": 1.0,
                           "min_resonance_Hz": 1e4}}

    def recording(text, *, source, schema):
        table = _RecordingTable(probe, "", source, rec)
        table.string("schema", required=True)
        return table

    original = sw.read_document
    sw.read_document = recording
    try:
        sw.parse_sweep("", source="probe")
    finally:
        sw.read_document = original
    keys = [k for k in rec.keys.values()
            if k.kind not in ("table", "array of tables") and k.table not in ("coil", "magnet")]
    for section, params in (("coil", sw.COIL_PARAMETERS), ("magnet", sw.MAGNET_PARAMETERS)):
        for name, (kind, low, high) in params.items():
            key = Key(table=section, name=name, kind={"int": "integer", "float": "number"}
                      .get(kind, "string"))
            if kind in ("int", "float"):
                key.low, key.high = low, high
            elif kind == "wire":
                key.choices = tuple(f"AWG{g}" for g in range(int(low), int(high) + 1))
            elif kind == "grade":
                from msens.params.materials import MAGNET_GRADES

                key.choices = tuple(sorted(MAGNET_GRADES))
            keys.append(key)
    records = {"": (sw.SweepSpec,), "model": (sw.SweepSpec,), "recommend": (sw.Recommend,),
               "coil": (schema.CoilSpec,), "magnet": (schema.MagnetSpec, sw.SweepSpec)}
    for key in keys:
        _describe(key, records)
    return keys


def tables(root: str | Path) -> list[Key]:
    """The tables and arrays of tables a study file may contain."""
    rec = _record(Path(root))
    return [k for k in rec.keys.values() if k.kind in ("table", "array of tables")]


# --------------------------------------------------------------------------- page


def _fmt(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "``true``" if value else "``false``"
    if isinstance(value, float):
        return f"``{value:.6g}``"
    if isinstance(value, str):
        return f'``"{value}"``'
    return f"``{value!r}``"


def _range(key: Key) -> str:
    if key.choices:
        return ", ".join(f'``"{c}"``' for c in key.choices)
    if key.low is None and key.high is None:
        return ""
    lo = "−∞" if key.low is None else f"{key.low:g}"
    infinite = key.high is None or math.isinf(key.high)
    hi = "∞)" if infinite else f"{key.high:g}]"
    return f"{'(' if key.low_open or key.low is None else '['}{lo}, {hi}"


def _toml_table(table: str) -> str:
    if not table:
        return "top level"
    parts = table.split(".")
    if parts[-1].endswith("[]"):
        return "[[" + table.replace("[]", "") + "]]"
    return "[" + table.replace("[]", "") + "]"


def _tables_rst(keys: list[Key], *, skip_prefix: str = "\0") -> list[str]:
    """The key tables of a reference page, one section per TOML table."""
    by_table: dict[str, list[Key]] = {}
    for key in keys:  # tables in the order the readers read them
        by_table.setdefault(key.table, []).append(key)
    for items in by_table.values():  # keys in their record's order (stable)
        items.sort(key=lambda k: k.order)
    out: list[str] = []
    for table, items in by_table.items():
        if table.startswith(skip_prefix):
            continue
        title = f"``{_toml_table(table)}``"
        out += [title, "-" * len(title), ""]
        record = items[0].record
        if record:
            out += [f"Read into :class:`{record}`.", ""]
        out += [
            ".. list-table::",
            "   :header-rows: 1",
            "   :widths: 18 9 12 14 47",
            "",
            "   * - key",
            "     - unit",
            "     - default",
            "     - allowed",
            "     - description",
        ]
        for key in items:
            default = "required" if key.required else (_fmt(key.default) or "—")
            out += [
                f"   * - ``{key.name}``",
                f"     - {key.unit}",
                f"     - {default}",
                f"     - {_range(key) or '—'}",
                f"     - {key.description or '(undocumented)'}",
            ]
        out.append("")
    return out


def _write(target: str | Path, lines: list[str]) -> Path:
    text = "\n".join(lines) + "\n"
    target = Path(target)
    if not target.exists() or target.read_text() != text:  # unchanged: no rebuild
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text)
    return target


def write_rst(root: str | Path, target: str | Path) -> Path:
    """Write the study-file reference page to ``target`` (only when it changed)."""
    head = [
        ".. This page is generated by docs/_ext/studyref.py at every build: do not edit.",
        "",
        ".. _study-reference:",
        "",
        "Study-file reference",
        "====================",
        "",
        "Every key of a study file (schema ``msens.study/1``), as the readers in",
        ":mod:`msens.config` read it: its unit, what an absent key means (*default*), the",
        "range or choices the reader accepts, and what it is. The page is generated at every",
        "docs build by running the readers on probe documents and reading the descriptions",
        "from the docstrings of the records they fill, so it cannot drift from the code.",
        "Units are SI and appear in the key names; a key outside its range, an unknown key",
        "or a missing required key stops msens with one message naming the key (exit 2).",
        "Further cross-checks (a bead density from mass and diameter, a dashpot time, a",
        "particle inside the chain, a static load below yield) are stated in the",
        "descriptions; the physical limits and their reasons are in",
        ":mod:`msens.config.plausible`.",
        "",
        "A plain study has ``[[sensor]]``, ``[[chain.insert]]`` and ``[[precompression]]`` at",
        "top level (one setup named after the study); a comparison study such as",
        "``studies/paper-table2.toml`` lists ``[[setup]]`` tables instead, each with its own",
        "``[[setup.sensor]]``, ``[[setup.insert]]`` and ``[[setup.precompression]]``, whose",
        "keys are those of the top-level tables below. Design sweeps have their own file:",
        ":ref:`sweep-reference`.",
        "",
    ]
    return _write(target, head + _tables_rst(reference(root), skip_prefix="setup[]."))


def write_sweep_rst(target: str | Path) -> Path:
    """Write the sweep-file reference page to ``target`` (only when it changed)."""
    head = [
        ".. This page is generated by docs/_ext/studyref.py at every build: do not edit.",
        "",
        ".. _sweep-reference:",
        "",
        "Sweep-file reference",
        "====================",
        "",
        "Every key of a sweep file (schema ``msens.sweep/1``) of ``msens design``",
        "(:mod:`msens.design.sweep`), generated like the :ref:`study-reference`. A sweep",
        "varies one MsS sensor of a study: each key of ``[coil]`` and ``[magnet]`` is a",
        "single value, a list of values, or a range table ``{start = ..., stop = ..., num =",
        "...}`` (both ends included) or ``{start = ..., stop = ..., step = ...}``; the designs",
        "are their Cartesian product (at most 200,000). A sweep with any ``[magnet]`` key is",
        "a magnet sweep (a field solve per design); otherwise one field model serves every",
        "coil. The allowed ranges below are those of each swept value; every design's parts",
        "are also checked for overlap before any solve. Examples: ``studies/sweep-coil.toml``",
        "and ``studies/sweep-magnet.toml``.",
        "",
    ]
    return _write(target, head + _tables_rst(sweep_reference()))


if __name__ == "__main__":  # python docs/_ext/studyref.py: list the keys
    here = Path(__file__).resolve().parents[2]
    for k in reference(here):
        print(f"{k.dotted:45s} {k.kind:8s} {k.unit:10s} {_fmt(k.default):14s} {_range(k):24s} "
              f"{'OK' if k.description else 'MISSING'}")

"""Study files (TOML, schema ``msens.study/1``) parsed once into frozen dataclasses.

The :class:`Study` record, reading and validating a file (:func:`load_study`) and changing
keys of a read study (:func:`replace_study`). This package is the single place where a
study's input is validated: the records are in :mod:`msens.config.schema`, the readers of
the tables in the ``read_*`` modules; every later stage receives typed, checked values.

A study describes one chain (beads, wall, striker) and one or more *setups* — the sensors,
inserted rods and static precompressions of one experiment. A plain study has its
``[[sensor]]``, ``[[chain.insert]]`` and ``[[precompression]]`` at top level (one setup,
named after the study); a comparison study such as the paper's Table 2 lists ``[[setup]]``
tables instead, each with its own ``sensor``/``insert``/``precompression``.

Units are SI throughout and appear in the key names.
"""

from __future__ import annotations

import copy
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from msens.config.read_chain import _chain, _striker
from msens.config.read_options import (
    _dissipation_fit,
    _electronics,
    _field,
    _measurement,
    _reference,
    _simulation,
)
from msens.config.read_setups import _setups
from msens.config.schema import (
    DEFAULT_STUDY,
    SCHEMA,
    ChainSpec,
    DissipationFitSpec,
    FieldSpec,
    ReferenceRow,
    SetupSpec,
    SimulationSpec,
    StrikerSpec,
)
from msens.errors import InputError, shorten
from msens.io.tomlreader import Table, document_table, read_document
from msens.readout.electronics import ElectronicsSpec


@dataclass(frozen=True)
class Study:
    """A validated study.

    Attributes
    ----------
    name : str
        The study's name (names its output folder and, in a plain study, its one setup):
        1 to 100 characters without ``/``, ``\\`` or control characters, not starting with
        a dot or a space.
    chain, striker, setups, simulation, electronics, field : records
        The ``[chain]``, ``[striker]``, ``[[sensor]]``/``[[setup]]``, ``[simulation]``,
        ``[electronics]`` and ``[field]`` tables (:mod:`msens.config.schema`).
    dissipation_fit : DissipationFitSpec or None
        The ``[calibration.dissipation]`` table.
    reference : tuple of ReferenceRow
        The ``[[reference.row]]`` tables.
    measurement_file : Path or None
        A measured waveform file of this study, the ``file`` key of ``[measurement]``
        (relative to the study file; it must exist).
    source : str
        Where the study was read from (file name, or the file and the replaced keys).
    schema : str
        The file's format, ``"msens.study/1"`` (the TOML key ``schema``, required; not a
        field of the record).
    """

    name: str
    chain: ChainSpec
    striker: StrikerSpec
    setups: tuple[SetupSpec, ...]
    simulation: SimulationSpec = field(default_factory=SimulationSpec)
    electronics: ElectronicsSpec = field(default_factory=ElectronicsSpec)
    field: FieldSpec = field(default_factory=FieldSpec)
    dissipation_fit: DissipationFitSpec | None = None
    reference: tuple[ReferenceRow, ...] = ()
    measurement_file: Path | None = None
    source: str = "<memory>"

    def setup(self, name: str) -> SetupSpec:
        """The setup called ``name``."""
        for s in self.setups:
            if s.name == name:
                return s
        raise KeyError(name)

    def replace(self, changes: Mapping[str, Any] | None = None, /, **more: Any) -> Study:
        """This study with some keys of its TOML changed, validated exactly like a file.

        Parameters
        ----------
        changes : Mapping[str, Any], optional
            Dotted key -> new value, the keys spelled as msens's messages name them:
            ``"striker.drop_height_m"``, ``"sensor[1].coil.turns"`` (``[[...]]`` arrays are
            indexed from 1: ``sensor[1]`` is the first ``[[sensor]]``),
            ``"setup[3].sensor[2].coil.turns"``. A value is a number, string, boolean, list
            or dict (a whole table); None removes the key (e.g. to give
            ``striker.velocity_m_per_s`` instead of ``striker.drop_height_m``). Tables that
            are missing are created.
        **more
            More changes, e.g. ``**{"striker.drop_height_m": 0.01}``.

        Returns
        -------
        Study
            A new study; this one is unchanged.

        Raises
        ------
        InputError
            For a key that does not fit the document (an index out of range, a value where
            a table is needed), or, from the validation, an unknown key or a value out of
            range, each naming the key.
        """
        return replace_study(self, {**(changes or {}), **more})


def load_study(path: str | Path) -> Study:
    """Read and validate a study file.

    Parameters
    ----------
    path : str or Path
        A ``.toml`` file following schema ``msens.study/1``.

    Raises
    ------
    InputError
        Missing or unreadable file, bad TOML, or any invalid key or value.
    """
    from msens.io._files import check_path, read_text

    if not isinstance(path, str | os.PathLike):
        raise InputError(f"a study is loaded from a path (str or pathlib.Path) to a .toml file, "
                         f"got {type(path).__name__} {shorten(path)}")
    path = check_path(path, "study file")  # empty, NUL, a name too long
    if not path.exists():
        raise InputError(f"study file '{path}' does not exist")
    # a regular file of bounded size: /dev/zero or a pipe would be read forever
    text = read_text(path, what="study file")
    return parse_study(text, source=str(path), base_dir=path.parent)


def builtin_study_path(name: str) -> Path:
    """A study shipped with the package (``paper-mss``, ``paper-table2``)."""
    return Path(str(resources.files("msens") / "data" / f"{name}.toml"))


def default_study_path() -> Path:
    """The built-in default study of ``msens run``."""
    return builtin_study_path(DEFAULT_STUDY)


def parse_study(text: str, *, source: str = "<memory>", base_dir: Path | None = None) -> Study:
    """Validate the TOML ``text`` of a study (see :func:`load_study`)."""
    return _study(read_document(text, source=source, schema=SCHEMA), source, base_dir)


def _study(root: Table, source: str, base_dir: Path | None) -> Study:
    name = root.label("name")
    chain_t = root.table("chain", required=True)
    chain = _chain(chain_t)
    top_inserts = chain_t.tables("insert")
    chain_t.finish()
    striker = _striker(root.table("striker", required=True))
    setups = _setups(root, chain, name, top_inserts)
    simulation = _simulation(root.table("simulation"))
    electronics = _electronics(root.table("electronics"))
    field_spec = _field(root.table("field"), chain, source)
    calib = root.table("calibration")
    fit = _dissipation_fit(calib, setups) if calib is not None else None
    reference = _reference(root.table("reference"), setups)
    measurement_file = _measurement(root.table("measurement"), base_dir)
    root.finish()
    study = Study(name=name, chain=chain, striker=striker, setups=setups,
                  simulation=simulation, electronics=electronics, field=field_spec,
                  dissipation_fit=fit, reference=reference,
                  measurement_file=measurement_file, source=source)
    # The parsed document rides beside the fields, not as one: the content hash and the
    # design cache keys are of the validated values only. Study.replace re-validates it.
    object.__setattr__(study, "_document", (root.data, base_dir))
    return study


#: One segment of a dotted key: a name, optionally with a 1-based array index.
_SEGMENT = re.compile(r"([^.\[\]\s]+)(?:\[(-?[0-9]+)\])?")


def replace_study(study: Study, changes: Mapping[str, Any]) -> Study:
    """``study`` with keys of its TOML document changed (see :meth:`Study.replace`).

    The changes are applied to a copy of the parsed document, which then goes through the
    same validation as a file, so a replaced study can hold nothing a file could not.
    """
    state = getattr(study, "_document", None)
    if state is None:
        raise InputError(f"study {study.name!r} was not read from a study file (load_study, "
                         "parse_study), so it has no keys to replace")
    document, base_dir = state
    if not changes:
        return study
    doc = copy.deepcopy(document)
    for key, value in changes.items():
        _set_key(doc, key, value, study.source)
    listed = ", ".join(f"{k}={_short(None if v is None else _toml_value(v, k, study.source))}"
                       for k, v in changes.items())
    source = f"{study.source} with {listed}"
    return _study(document_table(doc, source=source, schema=SCHEMA), source, base_dir)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _set_key(doc: dict, key: object, value: Any, source: str) -> None:
    """Set (or, for None, remove) the dotted ``key`` in the document ``doc``."""
    if not isinstance(key, str) or not key:
        raise InputError(f"{source}: replace key {key!r} must be a dotted key such as "
                         "'striker.drop_height_m'")
    segments = []
    for part in key.split("."):
        match = _SEGMENT.fullmatch(part)
        if match is None:
            raise InputError(f"{source}: replace key {key!r}: bad part {part!r}; keys are "
                             "names joined by dots, arrays of tables indexed from 1 "
                             "('sensor[1].coil.turns')")
        segments.append((match.group(1), None if match.group(2) is None
                         else int(match.group(2))))
    node: dict = doc
    done = ""
    for n, (name, index) in enumerate(segments):
        last = n == len(segments) - 1
        path = f"{done}.{name}" if done else name
        here = node.get(name)
        if index is not None:
            if not isinstance(here, list) or not all(isinstance(t, dict) for t in here):
                raise InputError(f"{source}: replace key {key!r}: '{path}' is not an array of "
                                 f"tables ([[{path}]]) in this study")
            if not 1 <= index <= len(here):
                hint = (" (indices count from 1, as msens's messages name them: "
                        f"{path}[1] is the first)" if index == 0 else "")
                raise InputError(f"{source}: replace key {key!r}: the study has {len(here)} "
                                 f"[[{path}]] table(s), {path}[1] to {path}[{len(here)}], "
                                 f"not {path}[{index}]{hint}")
            if last:
                if not isinstance(value, Mapping):
                    raise InputError(f"{source}: replace key {key!r}: a [[{path}]] table is "
                                     f"replaced by a dict, got {value!r}")
                here[index - 1] = _toml_value(value, key, source)
                return
            node, done = here[index - 1], f"{path}[{index}]"
            continue
        if last:
            if value is None:
                if name not in node:
                    raise InputError(f"{source}: replace key {key!r}: nothing to remove, "
                                     f"'{path}' is not in the study")
                del node[name]
            else:
                node[name] = _toml_value(value, key, source)
            return
        if here is None:
            here = node[name] = {}  # an optional table the file left out
        if isinstance(here, list):
            raise InputError(f"{source}: replace key {key!r}: '{path}' is an array of "
                             f"{len(here)} table(s): give an index, e.g. '{path}[1]'")
        if not isinstance(here, dict):
            raise InputError(f"{source}: replace key {key!r}: '{path}' is a value "
                             f"({here!r}), not a table")
        node, done = here, path


def _toml_value(value: Any, key: str, source: str) -> Any:
    """``value`` as TOML would give it (numpy scalars and arrays, tuples and paths become
    Python numbers, lists and strings), for the validation to judge."""
    if isinstance(value, np.generic | np.ndarray):  # before float: np.float64 is one
        return _toml_value(value.tolist(), key, source)
    if isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, list | tuple):
        return [_toml_value(v, key, source) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _toml_value(v, key, source) for k, v in value.items()}
    raise InputError(f"{source}: replace key {key!r}: {value!r} is not a TOML value (a "
                     "number, string, boolean, list or dict)")

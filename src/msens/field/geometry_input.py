"""Study tables -> :class:`~msens.field.geometry.SensorGeometry` (all checks in one place).

Reads the parts of a parsed study (TOML -> dict) that the field model needs::

    [chain]            beads (count below the striker), bead_diameter_m        (optional)
    [[sensor]]         kind = "mss", particle                                  (others ignored)
    [sensor.coil]      turns, length_m, inner_radius_m, wire, packing_factor, axial_offset_m
    [sensor.magnet]    enabled, grade | (remanence_T, recoil_permeability), inner_radius_m,
                       outer_radius_m, length_m, pole_inner_radius_m, pole_outer_radius_m,
                       pole_thickness_m, axial_offset_m
    [field]            beads = [first, last] (default: all, 2..count), contact_load_N,
                       min_flat_radius_m, contact_gap_m, air_radius_m, air_margin_m (optional)

Every key is optional and defaults to the paper's sensor (see :mod:`msens.field.geometry`);
unknown keys and wrong types raise :class:`msens.errors.InputError` naming the key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from msens.errors import require
from msens.field.geometry import (
    WIRES,
    AirBox,
    BeadChain,
    BiasMagnet,
    Coil,
    SensorGeometry,
    SensorUnit,
)
from msens.materials import MAGNET_GRADES

_COIL_KEYS = {"turns": "turns", "length_m": "length", "inner_radius_m": "inner_radius",
              "packing_factor": "packing_factor", "axial_offset_m": "axial_offset"}
_MAGNET_KEYS = {"inner_radius_m": "inner_radius", "outer_radius_m": "outer_radius",
                "length_m": "length", "pole_inner_radius_m": "pole_inner_radius",
                "pole_outer_radius_m": "pole_outer_radius",
                "pole_thickness_m": "pole_thickness", "axial_offset_m": "axial_offset",
                "remanence_T": "remanence", "recoil_permeability": "recoil_permeability"}
_FIELD_KEYS = {"beads", "contact_load_N", "min_flat_radius_m", "contact_gap_m",
               "air_radius_m", "air_margin_m"}


def _table(value: Any, where: str) -> Mapping[str, Any]:
    require(isinstance(value, Mapping), f"{where} must be a table, got {type(value).__name__}")
    return value


def _number(value: Any, where: str) -> float:
    require(isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value), f"{where} must be a finite number, got {value!r}")
    return float(value)


def _unknown(table: Mapping[str, Any], allowed: set[str], where: str) -> None:
    extra = sorted(set(table) - allowed)
    require(not extra, f"{where}: unknown key(s) {extra}; allowed: {sorted(allowed)}")


def _coil(table: Mapping[str, Any], particle: int, where: str) -> Coil:
    _unknown(table, set(_COIL_KEYS) | {"wire"}, where)
    kw: dict[str, Any] = {"particle": particle}
    for key, attr in _COIL_KEYS.items():
        if key in table:
            kw[attr] = _number(table[key], f"{where}.{key}")
    if "turns" in table:
        t = table["turns"]
        require(isinstance(t, int) and not isinstance(t, bool),
                f"{where}.turns must be an integer, got {t!r}")
        kw["turns"] = t
    if "wire" in table:
        w = table["wire"]
        require(w in WIRES, f"{where}.wire {w!r} is unknown; allowed: {sorted(WIRES)}")
        kw["wire"] = WIRES[w]
    return Coil(**kw)


def _magnet(table: Mapping[str, Any], particle: int, where: str) -> BiasMagnet | None:
    _unknown(table, set(_MAGNET_KEYS) | {"enabled", "grade"}, where)
    enabled = table.get("enabled", True)
    require(isinstance(enabled, bool), f"{where}.enabled must be true or false")
    if not enabled:
        return None
    kw: dict[str, Any] = {"particle": particle}
    if "grade" in table:
        require("remanence_T" not in table,
                f"{where}: give either grade or remanence_T (+ recoil_permeability), not both")
        grade = table["grade"]
        require(grade in MAGNET_GRADES,
                f"{where}.grade {grade!r} is unknown; allowed: {sorted(MAGNET_GRADES)}")
        g = MAGNET_GRADES[grade]
        kw.update(grade=grade, remanence=g.remanence, recoil_permeability=g.recoil_permeability)
    elif "remanence_T" in table:
        kw["grade"] = "custom"
    for key, attr in _MAGNET_KEYS.items():
        if key in table:
            kw[attr] = _number(table[key], f"{where}.{key}")
    return BiasMagnet(**kw)


def geometry_from_mapping(study: Mapping[str, Any]) -> SensorGeometry:
    """Build and validate the field-model geometry from a study mapping.

    Parameters
    ----------
    study : Mapping
        Parsed study (keys ``chain``, ``sensor``, ``field``; see the module docstring). Only
        sensors with ``kind = "mss"`` enter the field model.

    Returns
    -------
    SensorGeometry

    Raises
    ------
    msens.errors.InputError
        For unknown keys, wrong types, no MsS sensor, or an invalid geometry.
    """
    study = _table(study, "study")
    chain = _table(study.get("chain", {}), "[chain]")
    count = 30
    diameter = None
    if "beads" in chain:
        n = chain["beads"]
        require(isinstance(n, int) and not isinstance(n, bool) and n >= 1,
                f"[chain].beads must be a positive integer, got {n!r}")
        count = n + 1
    if "bead_diameter_m" in chain:
        diameter = _number(chain["bead_diameter_m"], "[chain].bead_diameter_m")

    sensors = study.get("sensor", [])
    require(isinstance(sensors, list), "[[sensor]] must be an array of tables")
    units = []
    for i, s in enumerate(sensors):
        where = f"sensor[{i}]"
        s = _table(s, where)
        if s.get("kind") != "mss":
            continue
        p = s.get("particle")
        require(isinstance(p, int) and not isinstance(p, bool),
                f"{where}.particle must be an integer, got {p!r}")
        coil = _coil(_table(s.get("coil", {}), f"{where}.coil"), p, f"{where}.coil")
        magnet = _magnet(_table(s.get("magnet", {}), f"{where}.magnet"), p,
                         f"{where}.magnet")
        units.append(SensorUnit(coil, magnet))
    require(bool(units), "the field model needs at least one [[sensor]] with kind = \"mss\"")

    fld = _table(study.get("field", {}), "[field]")
    _unknown(fld, _FIELD_KEYS, "[field]")
    parts = [u.coil.particle for u in units]
    for p in parts:
        require(2 <= p <= count, f"MsS sensor particle {p} is outside the chain 2..{count}")
    if "beads" in fld:
        fb = fld["beads"]
        require(isinstance(fb, list) and len(fb) == 2
                and all(isinstance(v, int) and not isinstance(v, bool) for v in fb),
                f"[field].beads must be [first, last] integers, got {fb!r}")
        first, last = fb
    else:  # the whole chain: cutting it 5 beads beyond the sensors moves their fields 2.6 %
        first, last = 2, count
    bead_kw: dict[str, Any] = {"first": first, "last": last, "count": count}
    if diameter is not None:
        bead_kw["diameter"] = diameter
    for key, attr in (("contact_load_N", "contact_load"),
                      ("min_flat_radius_m", "min_flat_radius"),
                      ("contact_gap_m", "contact_gap")):
        if key in fld:
            bead_kw[attr] = _number(fld[key], f"[field].{key}")
    air_kw = {}
    for key, attr in (("air_radius_m", "radius"), ("air_margin_m", "margin")):
        if key in fld:
            air_kw[attr] = _number(fld[key], f"[field].{key}")
    return SensorGeometry(beads=BeadChain(**bead_kw), sensors=tuple(units),
                          air=AirBox(**air_kw))

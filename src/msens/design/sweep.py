"""Sweep specifications (TOML, schema ``msens.sweep/1``): parsed and validated once.

A sweep varies one MsS sensor of a study. Every parameter is a list of values, a single
value, or a range table ``{start, stop, num}`` (``num`` points, both ends included) or
``{start, stop, step}``; the designs are the Cartesian product, in a fixed order (the
parameters in the order of :data:`COIL_PARAMETERS` then :data:`MAGNET_PARAMETERS`, the last
one varying fastest)::

    schema = "msens.sweep/1"
    name = "coil-13"
    sensor = 13                  # particle of the study's MsS sensor to vary (default: first)
    [coil]
    turns = [600, 1100, 1600]
    length_m = { start = 5e-3, stop = 9e-3, num = 5 }
    wire = ["AWG34", "AWG36"]
    [magnet]                     # any [magnet] entry makes it a magnet sweep
    grade = ["ceramic8", "N38"]
    radial_gap_m = [0.15e-3, 1e-3]
    [model]                      # optional
    bead_padding = 4             # magnet sweeps: a smaller per-design field model
    contact_map = false          # overrides the study's [field] contact_map (screening)
    verify = 3                   # magnet sweeps screened without maps: the 3 best again
                                 # with the study's maps, recommended among them ("auto":
                                 # until no unverified design screens above the best)
    [recommend]
    objective = "snr"            # or "peak_emf_V"
    min_bandwidth_Hz = 50e3
    max_precompression_N = 5.0

A coil-only sweep reuses one bias solve for all designs (:mod:`msens.design.coil_sweep`); a
sweep with any [magnet] parameter needs one nonlinear solve per design
(:mod:`msens.design.magnet_sweep`). ``radial_gap_m`` is the air gap between the tube and the
pole pieces' inner radius (pole_inner_radius = tube outer radius + gap).

Every design's parts are checked for overlap with the field model's own geometry
validation before any solve; a bad entry raises :class:`msens.errors.InputError` naming it.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from msens.config.fieldsetup import geometry_from_study, mss_setup
from msens.config.schema import SensorSpec
from msens.config.study import Study
from msens.errors import InputError, shorten
from msens.field.geometry import SensorGeometry
from msens.field.parts import BiasMagnet, SensorUnit, Tube
from msens.io.tomlreader import Table, read_document
from msens.params.materials import MAGNET_GRADES
from msens.readout.coil import wire_for

SCHEMA = "msens.sweep/1"

#: Coil parameters: name -> (kind, low, high) with kind "int", "float" or "wire"; SI units.
COIL_PARAMETERS: dict[str, tuple[str, float, float]] = {
    "turns": ("int", 1, 100_000),
    "length_m": ("float", 0.2e-3, 0.1),
    "inner_radius_m": ("float", 1e-3, 0.1),
    "wire": ("wire", 30, 40),  # AWG gauges with heavy-build data in msens.readout.coil
    "axial_offset_m": ("float", -0.05, 0.05),
}
#: Magnet parameters (see :class:`msens.field.parts.BiasMagnet`); SI units.
MAGNET_PARAMETERS: dict[str, tuple[str, float, float]] = {
    "grade": ("grade", 0, 0),
    "length_m": ("float", 0.5e-3, 0.1),
    "inner_radius_m": ("float", 1e-3, 0.1),
    "outer_radius_m": ("float", 1e-3, 0.2),
    "pole_outer_radius_m": ("float", 1e-3, 0.2),
    "pole_thickness_m": ("float", 0.0, 0.05),
    "radial_gap_m": ("float", 0.0, 0.05),
    "axial_offset_m": ("float", -0.05, 0.05),
}
#: Most designs a sweep may hold (a guard against typos such as num = 1e6).
MAX_DESIGNS = 200_000
#: ``[model] verify = "auto"``: verify until no unverified design screens above the best.
VERIFY_AUTO = "auto"
OBJECTIVES = ("snr", "peak_voltage_V", "peak_emf_V", "bandwidth_Hz")


@dataclass(frozen=True)
class Recommend:
    """How the recommended design is chosen: the best ``objective`` (largest magnitude)
    among the designs meeting every given limit (the ``[recommend]`` table).

    Attributes
    ----------
    objective : str
        What to maximise: ``"snr"`` (peak DAQ voltage over the read-out's noise rms, the
        default), ``"peak_voltage_V"``, ``"peak_emf_V"`` or ``"bandwidth_Hz"``.
    min_bandwidth_hz : float or None
        Smallest read-out bandwidth a recommended design may have, Hz.
    max_precompression_n : float or None
        Largest static magnetic compression of a contact a recommended design may cause, N.
    min_snr : float or None
        Smallest signal-to-noise ratio (peak DAQ voltage over noise rms). Unit: 1.
    min_resonance_hz : float or None
        Lowest read-out resonance a recommended design may have, Hz.
    """

    objective: str = "snr"
    min_bandwidth_hz: float | None = None
    max_precompression_n: float | None = None
    min_snr: float | None = None
    min_resonance_hz: float | None = None


@dataclass(frozen=True)
class Design:
    """One candidate: its index in the sweep and the swept values, ``(("coil.turns",
    1100), ...)`` in the sweep's parameter order."""

    index: int
    values: tuple[tuple[str, Any], ...]

    def label(self) -> str:
        """``turns=1100, length_m=0.007`` for messages."""
        return ", ".join(f"{k.split('.', 1)[1]}={v!r}" for k, v in self.values)


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep.

    Attributes
    ----------
    name : str
        The sweep's name (for reports).
    source : str
        Where the sweep was read from.
    sensor : int
        Particle of the varied MsS sensor (0 or absent: the study's first MsS). Unit:
        particle number.
    axes : tuple of (str, tuple)
        ``("coil.turns", (600, 1100))`` ... in design order.
    bead_padding : int or None
        Beads modelled on either side of the outermost sensor in a magnet sweep's model;
        None (default): the study's whole field model, as ``msens run``. A padded model is
        faster but its end beads carry the field's ends: with strong magnets their pull can
        put an end contact in tension that the whole chain does not have. Unit: beads.
    contact_map : bool or None
        ``[model] contact_map``: the nonlinear contact maps on or off for this sweep; None
        (default): the study's ``[field] contact_map``. Off, a magnet design is a few times
        faster (no maps to solve in its bias field), for screening.
    verify : int or "auto"
        ``[model] verify``: in a magnet sweep screened without the maps (``contact_map =
        false``) of a study that has them, the number of best screened designs evaluated
        again with the study's maps (each solving its own); the recommendation is made
        among them. 0 (default): none; more than the sweep's designs: all of them.
        ``"auto"`` (:data:`VERIFY_AUTO`): the best screened designs one at a time, until
        no unverified design screens above the best verified one. Unit: designs.
    recommend : Recommend
        The ``[recommend]`` table.
    schema : str
        The file's format, ``"msens.sweep/1"`` (the TOML key ``schema``, required; not a
        field of the record).
    radial_gap_m : float
        ``[magnet] radial_gap_m`` (a sweep parameter, not a field): the air gap between the
        tube and the pole pieces' inner radius (pole_inner_radius = tube outer radius + gap), m.
    """

    name: str
    source: str
    sensor: int
    axes: tuple[tuple[str, tuple[Any, ...]], ...]
    bead_padding: int | None = None
    contact_map: bool | None = None
    verify: int | str = 0
    recommend: Recommend = Recommend()

    @property
    def kind(self) -> str:
        """``"magnet"`` if any magnet parameter is swept, else ``"coil"``."""
        return "magnet" if any(k.startswith("magnet.") for k, _ in self.axes) else "coil"

    @property
    def parameters(self) -> tuple[str, ...]:
        return tuple(k for k, _ in self.axes)

    def designs(self) -> list[Design]:
        """All designs in the deterministic order (last axis fastest)."""
        names = self.parameters
        return [Design(i, tuple(zip(names, combo, strict=True)))
                for i, combo in enumerate(itertools.product(*(v for _, v in self.axes)))]


# ----------------------------------------------------------------------------- parsing

def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep file (raises :class:`InputError`)."""
    from msens.io._files import check_path, read_text

    if not check_path(path, "sweep file").exists():
        raise InputError(f"sweep file '{path}' does not exist")
    text = read_text(path, what="sweep file")  # a regular file of bounded size
    return parse_sweep(text, source=str(path))


def parse_sweep(text: str, *, source: str = "<memory>") -> SweepSpec:
    """Validate the TOML ``text`` of a sweep (see the module docstring)."""
    root = read_document(text, source=source, schema=SCHEMA)
    name = root.string("name", required=True)
    sensor = root.integer("sensor", 0, low=0)
    axes: list[tuple[str, tuple[Any, ...]]] = []
    for section, params in (("coil", COIL_PARAMETERS), ("magnet", MAGNET_PARAMETERS)):
        t = root.table(section)
        if t is None:
            continue
        for key in t.keys():
            if key not in params:
                raise t.error(key, f"is not a sweep parameter; allowed in [{section}]: "
                                   f"{', '.join(params)}")
        for key, (kind, low, high) in params.items():
            if t.has(key):
                axes.append((f"{section}.{key}", _values(t, key, t.raw(key), kind, low, high)))
        t.finish()
    if not axes:
        raise InputError(f"{source}: the sweep varies nothing: give at least one parameter in "
                         f"[coil] ({', '.join(COIL_PARAMETERS)}) or [magnet] "
                         f"({', '.join(MAGNET_PARAMETERS)})")
    count = math.prod(len(v) for _, v in axes)
    if count > MAX_DESIGNS:
        raise InputError(f"{source}: the sweep has {count} designs, more than {MAX_DESIGNS}")
    model = root.table("model")
    padding = None
    contact_map = None
    verify = 0
    if model is not None:
        if model.raw("bead_padding") is not None:
            padding = model.integer("bead_padding", low=1, high=30)
        if model.raw("contact_map") is not None:
            contact_map = model.boolean("contact_map", False)
        if isinstance(model.raw("verify"), str):
            verify = model.string("verify", choices=(VERIFY_AUTO,))
        else:
            verify = model.integer("verify", 0, low=0, high=MAX_DESIGNS)  # > count: every one
        if verify and contact_map is not False:
            raise model.error("verify", "re-evaluates designs screened without the contact "
                                        "maps: it needs contact_map = false in [model]")
        if verify and not any(k.startswith("magnet.") for k, _ in axes):
            raise model.error("verify", "applies to magnet sweeps (a coil sweep reads the "
                                        "study's contact maps in every design)")
        model.finish()
    rec = _recommend(root.table("recommend"))
    root.finish()
    return SweepSpec(name=name, source=source, sensor=sensor, axes=tuple(axes),
                     bead_padding=padding, contact_map=contact_map, verify=verify,
                     recommend=rec)


def _values(t: Table, key: str, raw: Any, kind: str, low: float, high: float) -> tuple:
    where = t.key(key)
    if isinstance(raw, dict):
        values = _range(t, key, raw)
        if kind == "int":  # integer ranges are computed in floats
            values = [round(v) if abs(v - round(v)) < 1e-9 else v for v in values]
    elif isinstance(raw, list):
        values = list(raw)
    else:
        values = [raw]
    if not values:
        raise InputError(f"{t._source}: '{where}' is an empty range: give at least one value")
    out = []
    for i, v in enumerate(values):
        entry = f"{t._source}: '{where}[{i}]'" if len(values) > 1 else f"{t._source}: '{where}'"
        out.append(_check_value(entry, v, kind, low, high))
    if len(set(out)) != len(out):
        raise InputError(f"{t._source}: '{where}' lists a value twice: {out}")
    return tuple(out)


def _range(t: Table, key: str, raw: dict) -> list[float]:
    where = f"{t._source}: '{t.key(key)}'"
    extra = sorted(set(raw) - {"start", "stop", "num", "step"})
    if extra or "start" not in raw or "stop" not in raw or ("num" in raw) == ("step" in raw):
        raise InputError(f"{where}: a range table needs start, stop and exactly one of num or "
                         f"step, got keys {sorted(raw)}")
    for k, v in raw.items():
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise InputError(f"{where}.{k} must be a finite number, got {v!r}")
    start, stop = float(raw["start"]), float(raw["stop"])
    if "num" in raw:
        num = raw["num"]
        if isinstance(num, bool) or not isinstance(num, int) or not 0 <= num <= MAX_DESIGNS:
            raise InputError(f"{where}.num must be an integer from 0 to {MAX_DESIGNS}, got "
                             f"{num!r}")
        if num == 1:
            return [start] if start == stop else []
        return [start + (stop - start) * i / (num - 1) for i in range(num)]
    step = float(raw["step"])
    if step == 0 or (stop - start) / step < 0:
        return []
    count = (stop - start) / step * (1 + 1e-12) + 1e-9  # inf for a subnormal step
    if not count < MAX_DESIGNS:
        raise InputError(f"{where}: the range has more than {MAX_DESIGNS} values "
                         f"(step {step!r})")
    n = math.floor(count) + 1
    return [start + i * step for i in range(n)]


def _check_value(entry: str, v: Any, kind: str, low: float, high: float) -> Any:
    if kind == "grade":
        if not isinstance(v, str) or v not in MAGNET_GRADES:
            raise InputError(f"{entry}: unknown magnet grade {shorten(v)}; allowed: "
                             f"{', '.join(sorted(MAGNET_GRADES))}")
        return v
    if kind == "wire":
        text = str(v).strip().upper()
        gauge = text.removeprefix("AWG")
        if not gauge.isdigit() or not low <= int(gauge) <= high:
            raise InputError(f"{entry}: wire must be 'AWG{int(low)}' .. 'AWG{int(high)}' "
                             f"(gauges with heavy-build data), got {shorten(v)}")
        return f"AWG{int(gauge)}"
    if kind == "int":
        if isinstance(v, bool) or not isinstance(v, int):
            raise InputError(f"{entry} must be an integer, got {shorten(v)}")
    elif isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise InputError(f"{entry} must be a finite number, got {shorten(v)}")
    if not low <= v <= high:
        raise InputError(f"{entry} = {shorten(v)} is out of range: allowed {low:g} .. {high:g}")
    return int(v) if kind == "int" else float(v) + 0.0  # -0.0 -> 0.0


def _recommend(t: Table | None) -> Recommend:
    if t is None:
        return Recommend()
    rec = Recommend(
        objective=t.string("objective", "snr", choices=OBJECTIVES),
        min_bandwidth_hz=t.number("min_bandwidth_Hz", None, low=0.0, allow_none=True),
        max_precompression_n=t.number("max_precompression_N", None, low=0.0,
                                      allow_none=True),
        min_snr=t.number("min_snr", None, low=0.0, allow_none=True),
        min_resonance_hz=t.number("min_resonance_Hz", None, low=0.0, allow_none=True))
    t.finish()
    return rec


# ----------------------------------------------------------------------------- geometry

def sweep_sensor(study: Study, spec: SweepSpec) -> SensorSpec:
    """The study's MsS sensor the sweep varies."""
    mss = [s for s in mss_setup(study).sensors if s.kind.value == "mss"]
    if spec.sensor == 0:
        return mss[0]
    for s in mss:
        if s.particle == spec.sensor:
            return s
    raise InputError(f"{spec.source}: 'sensor' = {spec.sensor} is not an MsS sensor of study "
                     f"{study.name!r} (MsS particles: {[s.particle for s in mss]})")


def base_geometry(study: Study, bead_padding: int = 4) -> SensorGeometry:
    """Field-model geometry of the study's MsS setup (all its MsS sensors, the study's
    ``[field]`` options and steel), beads from ``bead_padding`` above the top sensor to
    ``bead_padding`` below the bottom one."""
    full = geometry_from_study(study)
    parts = [u.coil.particle for u in full.sensors]
    beads = replace(full.beads, first=max(2, min(parts) - bead_padding),
                    last=min(full.beads.count, max(parts) + bead_padding))
    return replace(full, beads=beads)


def design_unit(unit: SensorUnit, values: tuple[tuple[str, Any], ...], tube: Tube
                ) -> SensorUnit:
    """``unit`` with the design's values applied (no validation of the whole geometry)."""
    coil_kw: dict[str, Any] = {}
    mag_kw: dict[str, Any] = {}
    for key, v in values:
        section, name = key.split(".", 1)
        if section == "coil":
            if name == "wire":
                coil_kw["wire"] = wire_for(v)
            else:
                coil_kw[name.removesuffix("_m")] = v
        elif name == "grade":
            g = MAGNET_GRADES[v]
            mag_kw.update(grade=v, remanence=g.remanence,
                          recoil_permeability=g.recoil_permeability)
        elif name == "radial_gap_m":
            mag_kw["pole_inner_radius"] = tube.outer_radius + v
        else:
            mag_kw[name.removesuffix("_m")] = v
    coil = replace(unit.coil, **coil_kw)
    magnet = unit.magnet
    if mag_kw:
        magnet = replace(magnet or BiasMagnet(particle=coil.particle), **mag_kw)
    return SensorUnit(coil, magnet)


def design_geometry(base: SensorGeometry, particle: int, design: Design) -> SensorGeometry:
    """The base geometry with ``design`` applied to the sensor at ``particle``, validated."""
    units = tuple(design_unit(u, design.values, base.tube) if u.coil.particle == particle
                  else u for u in base.sensors)
    return replace(base, sensors=units)


def validate_designs(base: SensorGeometry, particle: int, designs: list[Design],
                     source: str) -> None:
    """Build every design's geometry; the first invalid one raises an InputError naming it."""
    for d in designs:
        try:
            design_geometry(base, particle, d)
        except (InputError, ValueError) as exc:
            raise InputError(f"{source}: design {d.index} ({d.label()}) is invalid: {exc}") \
                from None


__all__ = ["COIL_PARAMETERS", "MAGNET_PARAMETERS", "SCHEMA", "VERIFY_AUTO", "Design",
           "Recommend", "SweepSpec", "base_geometry", "design_geometry", "design_unit",
           "load_sweep", "parse_sweep", "sweep_sensor", "validate_designs"]

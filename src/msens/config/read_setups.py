"""Readers of a study's sensors and setups: coils, magnets, sensors, ``[[setup]]`` tables.

A plain study's top-level ``[[sensor]]``, ``[[chain.insert]]`` and ``[[precompression]]``
form one setup; a comparison study lists ``[[setup]]`` tables, each with its own.
"""

from __future__ import annotations

from msens.config import plausible as P
from msens.config.read_chain import _insert, _offset, _particle, _precompression
from msens.config.schema import ChainSpec, CoilSpec, MagnetSpec, MssModel, SensorSpec, SetupSpec
from msens.io.tomlreader import Table
from msens.params.materials import (
    MAGNET_GRADES,
)
from msens.readout.sensors import SensorKind


def _coil(t: Table, chain: ChainSpec) -> CoilSpec:
    d = CoilSpec()
    spec = CoilSpec(
        turns=t.integer("turns", d.turns, low=1, high=10**6),
        length_m=t.number("length_m", d.length_m, low=P.SENSOR_SIZE_M[0],
                          high=P.SENSOR_SIZE_M[1]),
        inner_radius_m=t.number("inner_radius_m", d.inner_radius_m, low=P.SENSOR_SIZE_M[0],
                                high=P.SENSOR_SIZE_M[1]),
        wire=t.string("wire", d.wire),
        axial_offset_m=_offset(t, chain),
        packing_factor=t.number("packing_factor", None, low=0.0, high=0.907, low_open=True,
                                allow_none=True),
    )
    if not spec.wire.upper().startswith("AWG") or not spec.wire[3:].isdigit() \
            or not 10 <= int(spec.wire[3:]) <= 50:
        raise t.error("wire", f"must be an AWG gauge from 'AWG10' to 'AWG50', got {spec.wire!r}")
    t.finish()
    return spec


def _magnet(t: Table, chain: ChainSpec) -> MagnetSpec:
    dims = {}
    for key in ("inner_radius_m", "outer_radius_m", "length_m", "pole_inner_radius_m",
                "pole_outer_radius_m", "pole_thickness_m"):
        dims[key] = t.number(key, None, low=P.SENSOR_SIZE_M[0], high=P.SENSOR_SIZE_M[1],
                             allow_none=True)
    grade = t.string("grade", None, choices=sorted(MAGNET_GRADES))
    br = t.number("remanence_T", None, low=0.0, high=2.0, low_open=True, allow_none=True)
    mu = t.number("recoil_permeability", None, low=1.0, high=100.0, allow_none=True)
    if grade is not None and (br is not None or mu is not None):
        raise t.error("grade", "cannot be combined with remanence_T/recoil_permeability: "
                               "give a grade or both values")
    if grade is None and (br is None or mu is None):
        if br is None and mu is None:
            grade = "ceramic8"
        else:
            raise t.error("remanence_T", "and 'recoil_permeability' must be given together")
    spec = MagnetSpec(enabled=t.boolean("enabled", True), grade=grade, remanence_t=br,
                      recoil_permeability=mu,
                      axial_offset_m=_offset(t, chain),
                      **dims)
    t.finish()
    return spec


def _sensor(t: Table, chain: ChainSpec) -> SensorSpec:
    kind = SensorKind(t.string("kind", required=True, choices=[k.value for k in SensorKind]))
    particle = _particle(t, "particle", chain, first=3 if kind is SensorKind.MSS else 2)
    model = coil = magnet = None
    if kind is SensorKind.MSS:
        model = MssModel(t.string("model", MssModel.FOUR_CONTACT.value,
                                  choices=[m.value for m in MssModel]))
        if model is MssModel.FOUR_CONTACT and particle > chain.n_particles - 1:
            raise t.error("particle", f"of a four-contact MsS must be at most "
                                      f"{chain.n_particles - 1}, got {particle}")
        ct, mt = t.table("coil"), t.table("magnet")
        # without a table, SensorSpec applies the default coil and magnet
        coil = _coil(ct, chain) if ct is not None else None
        magnet = _magnet(mt, chain) if mt is not None else None
    t.finish()
    return SensorSpec(kind=kind, particle=particle, model=model, coil=coil, magnet=magnet)


def _setup(t: Table, name: str, chain: ChainSpec, inserts: list[Table],
           sensors: list[Table], pre: list[Table]) -> SetupSpec:
    ins = tuple(_insert(i, chain) for i in inserts)
    sens = tuple(_sensor(s, chain) for s in sensors)
    if not sens:
        raise t.error("sensor", "is missing: a setup needs at least one [[sensor]]")
    seen: dict[int, SensorKind] = {}
    for s in sens:
        if s.particle in seen:
            # two sensors on one particle read the same force: Eq. 10 and the wave speed
            # would take one particle as both top and bottom
            raise t.error("sensor", f"lists {seen[s.particle].value}@{s.particle} and "
                                    f"{s.kind.value}@{s.particle}: one sensor per particle")
        seen[s.particle] = s.kind
    rods = {i.particle for i in ins}
    if len(rods) != len(ins):
        raise t.error("insert", "replaces the same particle twice")
    # the chain model has sphere-sphere and sphere-flat contacts only
    for r in sorted(rods):
        if r + 1 in rods:
            raise t.error("insert", f"rods at particles {r} and {r + 1} touch flat on flat, "
                                    "which the chain model does not have; keep a bead "
                                    "between two rods")
    if chain.n_particles in rods:
        raise t.error("insert", f"rod at particle {chain.n_particles} would stand on the "
                                "wall (flat on flat, not modelled); the last particle must "
                                "be a bead")
    for s in sens:
        if s.kind is SensorKind.ROD and s.particle not in rods:
            raise t.error("sensor", f"rod sensor at particle {s.particle} needs an "
                                    f"[[insert]] rod at that particle")
    return SetupSpec(name=name, sensors=sens, inserts=ins,
                     precompression=tuple(_precompression(p, chain) for p in pre))


def _setups(root: Table, chain: ChainSpec, name: str,
            top_inserts: list[Table]) -> tuple[SetupSpec, ...]:
    setup_tables = root.tables("setup")
    sensors, pre = root.tables("sensor"), root.tables("precompression")
    if setup_tables:
        if sensors or pre or top_inserts:
            raise root.error("setup", "cannot be combined with top-level [[sensor]], "
                                      "[[precompression]] or [[chain.insert]]")
        out = []
        for st in setup_tables:
            sname = st.label("name")
            out.append(_setup(st, sname, chain, st.tables("insert"), st.tables("sensor"),
                              st.tables("precompression")))
            st.finish()
        names = [s.name for s in out]
        if len(set(names)) != len(names):
            raise root.error("setup", f"names must be unique, got {names}")
        return tuple(out)
    return (_setup(root, name, chain, top_inserts, sensors, pre),)

"""How much a contact map's shape depends on the coil that reads it (prints JSON).

:meth:`msens.magnetics.transducer.Transducer.shifted` and the coil sweep read a moved or
redesigned coil's contacts through the study coil's contact maps (a Hammerstein model: the
map's shape is assumed to be the contact's, whatever coil reads it). The main study's
committed maps are tabulated for both of its coils (13 and 18, five beads apart), which is a
far larger move than any coil design or ``coil_position`` fit makes. For each mapped contact
this compares the two coils' maps Λ_c(δ) − Λ_c(δ_s) over δ from −12 µm (open) to 2.5 µm:
the best scale factor between them and the largest misfit after scaling, relative to the
reading coil's range; and each map's static slope against the linear source's ∂Λ/∂δ_c of
the same coil (the two slopes the maps' shape reading joins).

``--moved`` also measures the moves a design or a ``coil_position`` fit makes: for a few
contacts (default 12, 13 at coil 13 and 17, 18 at coil 18) every table state of the contact
map is solved again (:func:`msens.magnetics.contact_map.state_potential`) and read by the
nearest coil and by that coil moved by ±1 and ±2.5 mm (a summed-area table of the state's
potential, :func:`msens.magnetics.potentials.linkage_table`, the same quadrature for all).

``--remanence`` asks the same of the magnets: the maps of those contacts solved again with
all magnets' remanence scaled by 0.7 and 1.3 (:func:`msens.magnetics.variants.scaled_geometry`,
the ``magnet_remanence`` effect's variants), read by the same coil, against the study's maps
at the same table nodes.

``--magnet`` asks it of a magnet sweep: for the corner designs of
``studies/sweep-magnet.toml`` (:data:`MAGNET_CORNERS`, the last one the study's own magnet)
the maps of coil 13's mapped contacts are solved in the design's own bias field, and the
design's coil 13 is read three ways on the study's wave with that design's pull: linear
sources, the study's maps carried over
(:meth:`msens.magnetics.transducer.Transducer.reading_maps_of`) and the design's own maps
(what a magnet sweep with ``contact_map = true`` does). The figures are the peak EMF and the
peak DAQ voltage, and each map's shape misfit against the study's.

Run: ``python benchmarks/contact_map_transfer.py [--moved] [--remanence] [--magnet]``
(seconds: the maps are committed; each option about 12 s per contact and case).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from msens.config.fieldsetup import geometry_from_study
from msens.config.study import default_study_path, load_study
from msens.magnetics.transducer_cache import transducers_for


def shape_misfit(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Best scale s of ``y`` onto ``x`` and max |x − s y| / max |x|."""
    scale = float(np.dot(x, y) / np.dot(y, y))
    return scale, float(np.max(np.abs(x - scale * y)) / np.max(np.abs(x)))


def moved_coils(geometry, contacts, offsets) -> dict:
    """Each contact's map states read by its nearest coil and by that coil moved."""
    from msens.magnetics.contact_map import (
        AIR_GAPS,
        CLOSED_THICKNESS,
        STEEL_NODES,
        layer_model,
        state_potential,
        static_approach,
    )
    from msens.magnetics.potentials import linkage_table, rect_integral

    ds = static_approach(geometry)
    states = ([("steel", ds)] + [("steel", d) for d in STEEL_NODES]
              + [("air", ds - g) for g in (CLOSED_THICKNESS, *AIR_GAPS[1:])])
    offsets = np.asarray([0.0, *offsets])
    span = float(np.max(np.abs(offsets)))
    out = {}
    for c in contacts:
        model = layer_model(geometry, c)
        unit = min(model.geometry.sensors, key=lambda u: abs(u.coil.particle - c - 0.5))
        rect, coil = model.geometry.coil_rect(unit), unit.coil
        ones = np.ones(offsets.size)
        flux = []
        for state, delta in states:
            sol, a = state_potential(model, state, delta)
            table = linkage_table(sol, a[None], (rect.r0, rect.r1),
                                  (rect.z0 - span - 1e-4, rect.z1 + span + 1e-4), 0.05e-3)
            flux.append(coil.turns / coil.area * rect_integral(
                table, rect.r0 * ones, rect.r1 * ones, rect.z0 + offsets,
                rect.z1 + offsets)[:, 0])
        change = np.array(flux[1:]) - flux[0]  # (n_states, n_offsets)
        out[str(c)] = {"coil": coil.particle, **{
            f"moved_{o * 1e3:+.1f}_mm": dict(zip(("scale", "shape_misfit"),
                                                shape_misfit(change[:, 0], change[:, k]),
                                                strict=True))
            for k, o in enumerate(offsets) if k}}
    return out


def remanence_scaled(geometry, transducers, contacts, factors) -> dict:
    """Each contact's map with the magnets' remanence scaled, against the study's map."""
    from msens.magnetics.contact_map import contact_maps, layer_model
    from msens.magnetics.variants import scaled_geometry

    out = {}
    for c in contacts:
        p = min(transducers, key=lambda q: abs(q - c - 0.5))
        nominal = next(m for m in transducers[p].approach_map.maps if m.contact == c)
        x = np.concatenate([nominal.steel_flux, nominal.air_flux])
        row: dict = {"coil": p}
        for f in factors:
            g = scaled_geometry(geometry, f)
            coil = next(u.coil for u in g.sensors if u.coil.particle == p)
            m = contact_maps(layer_model(g, c), [coil])[0]
            scale, misfit = shape_misfit(x, np.concatenate([m.steel_flux, m.air_flux]))
            row[f"remanence_x{f}"] = {"scale": scale, "shape_misfit": misfit}
        out[str(c)] = row
    return out


#: Corner designs of ``studies/sweep-magnet.toml``: (grade, length, radial gap, axial offset).
MAGNET_CORNERS = (("N38", 16e-3, 0.15e-3, 0.0), ("N38", 12e-3, 2.0e-3, 2e-3),
                  ("ceramic8", 12e-3, 2.0e-3, 2e-3), ("ceramic8", 16e-3, 0.15e-3, 0.0))


def magnet_designs(study, geometry, transducers, particle: int = 13) -> dict:
    """Coil ``particle`` of each corner design read linearly, with the study's maps carried
    over and with the design's own maps: peak EMF and DAQ voltage."""
    from dataclasses import replace

    from msens.design.metrics import design_rows
    from msens.design.physics import study_wave
    from msens.design.sweep import Design, design_geometry
    from msens.magnetics.contact_map import ApproachMap, contact_maps, layer_model
    from msens.magnetics.transducer import compute_transducers

    keys = ("magnet.grade", "magnet.length_m", "magnet.radial_gap_m", "magnet.axial_offset_m")
    own_contacts = [m.contact for m in transducers[particle].approach_map.maps
                    if particle - 3 <= m.contact < particle + 3]
    out = {}
    for k, values in enumerate(MAGNET_CORNERS):
        design = Design(k, tuple(zip(keys, values, strict=True)))
        g = design_geometry(geometry, particle, design)
        report = compute_transducers(g)
        linear = dict(report.transducers)
        tr = linear[particle]
        coil = next(u.coil for u in g.sensors if u.coil.particle == particle)
        start = time.perf_counter()
        maps = tuple(contact_maps(layer_model(g, c), [coil])[0] for c in own_contacts)
        seconds = time.perf_counter() - start
        variants = {"linear": tr, "carried_over": tr.reading_maps_of(transducers[particle]),
                    "own_maps": replace(tr, approach_map=ApproachMap(maps))}
        row: dict = {"design": dict(zip(keys, values, strict=True)),
                     "own_maps_s_per_contact": seconds / len(own_contacts)}
        for name, t in variants.items():
            wave = study_wave(study, {**linear, particle: t}, particle)
            r = design_rows([coil], np.array([t.resistance_ohm]), np.array([t.inductance_H]),
                            t.sensitivity_villari[None], t.dlambda_dapproach[None], wave,
                            study.electronics)[0]
            row[name] = {"peak_emf_V": r["peak_emf_V"], "peak_voltage_V": r["peak_voltage_V"]}
        own = row["own_maps"]
        for name in ("linear", "carried_over"):
            row[name]["error_vs_own_maps"] = {
                q: row[name][q] / own[q] - 1.0 for q in ("peak_emf_V", "peak_voltage_V")}
        nominal = {m.contact: m for m in transducers[particle].approach_map.maps}
        row["shape_misfit"] = {str(m.contact): shape_misfit(
            np.concatenate([m.steel_flux, m.air_flux]),
            np.concatenate([nominal[m.contact].steel_flux, nominal[m.contact].air_flux]))[1]
            for m in maps}
        out[str(k)] = row
    return out


def main() -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moved", action="store_true")
    parser.add_argument("--remanence", action="store_true")
    parser.add_argument("--magnet", action="store_true")
    parser.add_argument("--contacts", default="12,13,17,18")
    args = parser.parse_args()
    study = load_study(default_study_path())
    geometry = geometry_from_study(study)
    transducers = transducers_for(geometry, contact_maps=True)
    maps = {p: {m.contact: m for m in tr.approach_map.maps} for p, tr in transducers.items()}
    delta = np.linspace(-12e-6, 2.5e-6, 600)
    (a, b) = sorted(maps)
    out = {}
    for c in sorted(set(maps[a]) & set(maps[b])):
        row = {}
        for own, other in ((a, b), (b, a)):
            scale, misfit = shape_misfit(maps[own][c](delta), maps[other][c](delta))
            row[f"coil_{own}_read_by_{other}"] = {"scale": scale, "shape_misfit": misfit}
        for p in (a, b):  # the map's own static slope against the linear source's
            k = int(np.flatnonzero(transducers[p].contacts == c)[0])
            row[f"coil_{p}_static_slope_over_linear"] = (
                maps[p][c].static_slope / float(transducers[p].dlambda_dapproach[k]))
        out[str(c)] = row
    result = {"study": "paper-mss", "coils": [a, b], "delta_range_m": [-12e-6, 2.5e-6],
              "contacts": out}
    if args.moved:
        contacts = [int(c) for c in args.contacts.split(",")]
        result["moved"] = moved_coils(geometry, contacts, (-2.5e-3, -1e-3, 1e-3, 2.5e-3))
    if args.remanence:
        contacts = [int(c) for c in args.contacts.split(",")]
        result["remanence"] = remanence_scaled(geometry, transducers, contacts, (0.7, 1.3))
    if args.magnet:
        result["magnet"] = magnet_designs(study, geometry, transducers)
    return result


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))

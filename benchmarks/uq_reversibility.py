"""The reversibility surrogate of ``msens uq`` against direct field solves at held-out values.

``field.reversibility`` (the reversible part c of the steel's differential susceptibility,
1 = differential, ~0.1 = reversible) is propagated by ``msens uq`` through
:class:`msens.magnetics.reversibility.ReversibilityFamily`: the study's transducers solved at
the nodes :data:`msens.magnetics.reversibility.NODES` and interpolated by cubic splines in
log c. This script solves the main study directly at :data:`HELD_OUT` seeded log-uniform
reversibilities in [0.1, 1] (none within 2 % of a node; each solve is cached in the user
cache, so a rerun takes seconds) and compares, for each coil, the peak DAQ voltage and peak
EMF of the nominal chain run read through the surrogate's and the directly solved coil
(contact maps read as ``msens uq`` reads them), and the magnets' pull on the beads (largest
difference over the particles relative to the largest pull). With ``--composed`` it also
checks the surrogate composed with a remanence change
(:func:`msens.uq.model.at_reversibility`) against direct solves of both changes at once.
With ``--eddy`` the main study has eddy currents and the coils are read with their frequency
responses: the surrogate's (:class:`msens.magnetics.reversibility.ReversibilityResponses`,
splines in log c over the eddy-current models at the nodes) against the eddy-current model
solved at each held-out value (about 140 s each on 2 cores, then cached).

Run: ``python benchmarks/uq_reversibility.py [--held-out 24] [--nodes 5] [--composed]
[--eddy]``
(prints JSON: seconds per direct solve, the relative errors per held-out value and their
maximum).
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace

import numpy as np

from msens import api
from msens.config.fieldsetup import coil_geometry, eddy_settings, geometry_from_study
from msens.config.schema import CoilSpec
from msens.magnetics import reversibility
from msens.magnetics.dynamic_cache import dynamic_report
from msens.magnetics.transducer import magnetic_precompression
from msens.magnetics.transducer_cache import transducers_for
from msens.magnetics.variants import remanence_family, scaled_geometry
from msens.pipeline import run_study
from msens.readout.mss import MssSensor, mss_signals, readout
from msens.uq.model import at_reversibility

#: Held-out reversibilities drawn (seeded, log-uniform in [0.1, 1]).
HELD_OUT = 24
SEED = 34
#: Composed checks: (reversibility, remanence factor).
COMPOSED = ((0.2051, 0.75), (0.4241, 1.25), (0.7387, 0.75))


def held_out(count: int, nodes: tuple[float, ...], seed: int = SEED) -> list[float]:
    """``count`` log-uniform reversibilities in [0.1, 1] rounded to 4 digits, none within 2 %
    of a node, sorted."""
    rng, out = np.random.default_rng(seed), []
    while len(out) < count:
        c = float(np.round(np.exp(rng.uniform(np.log(0.1), 0.0)), 4))
        if min(abs(np.log(c / n)) for n in nodes) > 0.02 and c not in out:
            out.append(c)
    return sorted(out)


def peaks(study, setup, tr, response=None) -> tuple[float, float]:
    """Peak |DAQ voltage| and peak |EMF| (V) of the nominal chain run read through ``tr``
    (with eddy currents: and its frequency ``response``)."""
    spec = next(s for s in study.setups[0].sensors if s.particle == tr.particle)
    sensor = MssSensor(tr, readout(coil_geometry(spec.coil or CoilSpec(), tr.particle),
                                   tr.resistance_ohm, tr.inductance_H, study.electronics))
    h = setup.history
    rec = mss_signals(sensor, h.t, h.force, study.electronics.sample_rate_hz,
                      approach=h.approach, static=setup.static_force, response=response)
    return float(np.max(np.abs(rec.voltage))), float(np.max(np.abs(rec.emf)))


def compare(study, setup, nominal, approx: dict, direct: dict, pull_approx, pull_direct,
            responses: tuple[dict, dict] | None = None) -> dict:
    """Relative errors of the surrogate's coils and pull against the direct solve's
    (``responses``: the direct and the surrogate's eddy-current responses by particle)."""
    row = {}
    for p, tr0 in nominal.items():
        r1, r2 = (None, None) if responses is None else (responses[0][p], responses[1][p])
        (v1, e1) = peaks(study, setup, direct[p].reading_maps_of(tr0), r1)
        (v2, e2) = peaks(study, setup, approx[p], r2)
        row[str(p)] = {"peak_voltage_V": [v1, v2], "voltage_error": v2 / v1 - 1.0,
                       "peak_emf_V": [e1, e2], "emf_error": e2 / e1 - 1.0}
    row["pull_error"] = float(np.max(np.abs(pull_approx - pull_direct))
                              / np.max(np.abs(pull_direct)))
    return row


def worst(rows: dict) -> dict:
    """Largest |relative error| of voltage, EMF and pull over ``rows``."""
    coils = [v for r in rows.values() for v in r.values() if isinstance(v, dict)]
    return {"voltage": max(abs(v["voltage_error"]) for v in coils),
            "emf": max(abs(v["emf_error"]) for v in coils),
            "pull": max(r["pull_error"] for r in rows.values())}


def main(argv: list[str] | None = None) -> dict:
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--held-out", type=int, default=HELD_OUT)
    args.add_argument("--nodes", type=int, default=0,
                      help="log-spaced nodes over [0.1, 1] (0: the module's NODES)")
    args.add_argument("--composed", action="store_true")
    args.add_argument("--eddy", action="store_true",
                      help="the main study with eddy currents: the coils' frequency "
                           "responses through ReversibilityResponses against direct "
                           "eddy-current models (137 s each, cached)")
    opts = args.parse_args(argv)
    nodes = reversibility.NODES if opts.nodes == 0 else tuple(
        float(v) for v in np.round(np.geomspace(0.1, 1.0, opts.nodes), 4))
    study = api.load_default(eddy_currents=bool(opts.eddy))
    geometry = geometry_from_study(study)
    setup = run_study(study).setups[0]
    nominal = setup.transducers
    start = time.perf_counter()
    family = reversibility.reversibility_family(geometry, nodes)
    if opts.eddy:
        eddy = eddy_settings(study)
        kwargs = {"options": eddy.options, "steel": eddy.steel}
        responses = reversibility.reversibility_responses(geometry, nodes, **kwargs)
    report = {"study": study.name + (" with eddy currents" if opts.eddy else ""),
              "nodes": list(nodes), "family_seconds": time.perf_counter() - start,
              "solve_seconds": {}, "held_out": {}}
    for c in held_out(opts.held_out, nodes):
        start = time.perf_counter()
        at_c = replace(geometry, reversibility=c)
        direct = transducers_for(at_c)
        pair = None
        if opts.eddy:
            pair = (dynamic_report(at_c, **kwargs).responses,
                    {p: responses.response(p, c) for p in nominal})
        report["solve_seconds"][str(c)] = time.perf_counter() - start
        approx = {p: family.transducer(p, c).reading_maps_of(tr0) for p, tr0 in nominal.items()}
        report["held_out"][str(c)] = compare(study, setup, nominal, approx, direct,
                                             family.particle_force(c),
                                             magnetic_precompression(direct), pair)
        print(json.dumps({"reversibility": c, **worst({c: report["held_out"][str(c)]})}),
              flush=True)
    report["max_relative_error"] = worst(report["held_out"])
    if opts.composed:
        remanence = remanence_family(geometry)
        report["composed"] = {}
        for c, r in COMPOSED:
            direct = transducers_for(scaled_geometry(replace(geometry, reversibility=c), r))
            approx = {p: at_reversibility(family.transducer(p, c), tr0,
                                          remanence.transducer(p, r))
                      for p, tr0 in nominal.items()}
            pull0 = magnetic_precompression(nominal)
            pull_c = family.particle_force(c)
            scale = np.linalg.norm(pull_c) / np.linalg.norm(pull0)
            pull = pull_c + scale * (remanence.particle_force(r) - pull0)
            report["composed"][f"{c}x{r}"] = compare(study, setup, nominal, approx, direct,
                                                     pull, magnetic_precompression(direct))
        report["composed_max_relative_error"] = worst(report["composed"])
    print(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()

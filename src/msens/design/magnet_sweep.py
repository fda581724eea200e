"""Magnet sweeps: one field model per design, run through the executor.

Per design (a pure function of its payload, so local and Dask runs agree): the transducer
core on the design's geometry (:func:`msens.magnetics.transducer.compute_transducers`: mesh
cached by content hash, nonlinear bias solve, both mechanisms, the coil's incremental
inductance, the magnets' pull on the beads), the study's wave with that pull
(:func:`msens.design.physics.study_wave`) and the figures of merit of
:mod:`msens.design.metrics` — the same chain of functions as ``msens run``.
With contact maps (``[field] contact_map``) each design solves the maps of the swept coil's
contacts in its own bias field (:func:`msens.magnetics.contact_map.approach_maps`, about
12 s per contact on a core, cached as ``msens run`` caches them): a magnet changes their
shape. With eddy
currents each design also gets its own eddy-current model
(:func:`msens.magnetics.dynamic_cache.dynamic_report` with the run's mesh options and conductivity,
cached beside the meshes) and its row is the frequency-domain read-out of
:func:`msens.design.metrics.dynamic_design_rows`.

Own maps cost about a minute per design, several times the rest, so a sweep may screen
without them (``[model] contact_map = false``, the linear contact sources) and evaluate
only its best designs again with them (``[model] verify``, a number or ``"auto"``,
:func:`msens.design.run_design`): the recommendation is then made among the verified
designs.

Model size: by default the study's whole field model (every MsS sensor: the other sensor's
magnet changes the forces near this one; every bead), as ``msens run``. ``[model]
bead_padding`` keeps only that many beads beyond the outermost sensors
(:func:`msens.design.sweep.base_geometry`): faster, but the truncated column's end beads carry
the field's ends, and with strong magnets their pull can put an end contact in tension.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msens.config.fieldsetup import eddy_settings
from msens.config.study import Study
from msens.design.metrics import design_rows, dynamic_design_rows
from msens.design.physics import study_wave
from msens.field.geometry import SensorGeometry
from msens.magnetics.dynamic_cache import dynamic_report
from msens.magnetics.transducer import compute_transducers
from msens.magnetics.transducer_cache import transducer_report
from msens.store import Store


@dataclass(frozen=True)
class MagnetTask:
    """Payload of one magnet design (picklable).

    Attributes
    ----------
    study : Study
    geometry : SensorGeometry
        The design's field-model geometry.
    particle : int
        The swept sensor's coil particle.
    store : Store
        Where the design's meshes, transducers, contact maps and responses are found and
        written (absolute folders: workers may run in another working directory).
    """

    study: Study
    geometry: SensorGeometry
    particle: int
    store: Store


def evaluate_design(task: MagnetTask) -> dict:
    """Metrics of one magnet (and coil) design; raises on failure (the runner records it)."""
    store = task.store
    if task.study.field.contact_map:
        # the design's own maps: the study magnet's do not carry over to another magnet
        # (benchmarks/contact_map_transfer.py --magnet)
        # (cached as msens run caches them: the study's own magnet reads its committed maps)
        report = transducer_report(task.geometry, store=store, contact_maps=True,
                                   map_particles=(task.particle,))
    else:
        report = compute_transducers(task.geometry, store=store)
    tr = report.transducers[task.particle]
    coil = next(u.coil for u in task.geometry.sensors if u.coil.particle == task.particle)
    wave = study_wave(task.study, report.transducers, task.particle)
    resistance, inductance = np.array([tr.resistance_ohm]), np.array([tr.inductance_H])
    if task.study.field.eddy_currents:
        eddy = eddy_settings(task.study)
        rsp = dynamic_report(task.geometry, options=eddy.options, steel=eddy.steel,
                             store=store, start=report.bias).responses[task.particle]
        row = dynamic_design_rows([coil], resistance, inductance, rsp.frequencies,
                                  rsp.villari[None], rsp.approach[None],
                                  np.asarray(rsp.inductance)[None], wave,
                                  task.study.electronics)[0]
    else:
        row = design_rows([coil], resistance, inductance, tr.sensitivity_villari[None],
                          tr.dlambda_dapproach[None], wave, task.study.electronics)[0]
    return {**row, "contacts": [int(k) for k in tr.contacts],
            "dLambda_dF_Wb_per_N": [float(v) for v in tr.sensitivity_villari],
            "dLambda_ddelta_Wb_per_m": [float(v) for v in tr.dlambda_dapproach],
            "newton_iterations": report.details["newton_iterations"],
            "contact_maps": bool(task.study.field.contact_map)}


__all__ = ["MagnetTask", "evaluate_design"]

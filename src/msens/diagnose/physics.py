"""Physics MsS sensors inside a diagnosis: the run's transducer core, varied by effects.

A :class:`~msens.diagnose.effects.base.PhysicsMss` in a model state names its field model by
key and carries what effects may change (coil offset, magnet remanence, cable). This module
holds the field models (the study's transducers, and on demand their
:class:`~msens.magnetics.variants.RemanenceFamily`) and turns a ``PhysicsMss`` into the
:class:`~msens.magnetics.mss.MssSensor` whose DAQ voltage is the sensor's record — the same
functions ``msens run`` uses, so an undisturbed diagnosis reproduces the run exactly.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import numpy as np

from msens.config.fieldsetup import coil_geometry, geometry_from_study
from msens.config.schema import CoilSpec, MssModel
from msens.diagnose.effects.base import Context, PhysicsMss
from msens.errors import internal
from msens.field.geometry import SensorGeometry
from msens.magnetics.mss import MssSensor, readout
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import Transducer, cache_key, magnetic_precompression
from msens.magnetics.transducer_cache import transducers_for
from msens.magnetics.variants import RemanenceFamily, remanence_family
from msens.params.materials import BEAD_STEEL

# Field models of this process by key: geometry and nominal transducers (families lazily).
_MODELS: dict[str, tuple[SensorGeometry, dict[int, Transducer]]] = {}
_FAMILIES: dict[str, RemanenceFamily] = {}


def register(geometry: SensorGeometry) -> str:
    """Solve (or read from the cache) a geometry's transducers; return its model key."""
    key = cache_key(geometry, stress_force=geometry.beads.contact_load,
                    law=law_for_steel(geometry.steel), material=BEAD_STEEL, approach=True)
    if key not in _MODELS:
        _MODELS[key] = (geometry, transducers_for(geometry))
    return key


def transducers(model: str) -> dict[int, Transducer]:
    """The nominal transducers of a registered model."""
    return _MODELS[model][1]


def family(model: str) -> RemanenceFamily:
    """The remanence family of a registered model (solved on first use, then cached)."""
    if model not in _FAMILIES:
        _FAMILIES[model] = remanence_family(_MODELS[model][0])
    return _FAMILIES[model]


def setup_physics(ctx: Context) -> tuple[PhysicsMss | None, ...]:
    """Per sensor of the setup, its physics MsS (None for other sensors); empty if none."""
    sensors = ctx.setup.sensors
    if not any(s.model is MssModel.PHYSICS for s in sensors):
        return ()
    model = register(geometry_from_study(ctx.study, ctx.setup))
    return tuple(
        PhysicsMss(model=model, particle=s.particle,
                   coil=coil_geometry(s.coil or CoilSpec(), s.particle),
                   electronics=ctx.study.electronics)
        if s.model is MssModel.PHYSICS else None for s in sensors)


def magnetic_force(physics: tuple[PhysicsMss | None, ...]) -> np.ndarray | None:
    """Static magnetic force on each particle of the states' magnets, N (None: no magnets)."""
    spec = next((p for p in physics if p is not None), None)
    if spec is None:
        return None
    if spec.remanence_factor == 1.0:
        return magnetic_precompression(transducers(spec.model))
    return family(spec.model).particle_force(spec.remanence_factor)


@lru_cache(maxsize=4096)
def sensor(spec: PhysicsMss) -> MssSensor:
    """The transducer and read-out circuit of a physics MsS as ``spec`` says."""
    if spec.remanence_factor == 1.0:
        tr = transducers(spec.model)[spec.particle]
    else:
        tr = family(spec.model).transducer(spec.particle, spec.remanence_factor)
    if spec.offset_m != 0.0:
        tr = tr.shifted(spec.offset_m)
    return MssSensor(tr, readout(spec.coil, tr.resistance_ohm, tr.inductance_H,
                                 spec.electronics))


def with_physics(physics: tuple[PhysicsMss | None, ...], **changes) -> tuple:
    """The specs with ``changes`` applied to every physics MsS."""
    internal(any(p is not None for p in physics), "internal: the state has no physics MsS")
    return tuple(None if p is None else dataclasses.replace(p, **changes) for p in physics)


__all__ = ["family", "magnetic_force", "register", "sensor", "setup_physics", "transducers",
           "with_physics"]

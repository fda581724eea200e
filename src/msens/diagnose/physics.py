"""Physics MsS sensors inside a diagnosis: the run's transducer core, varied by effects.

A :class:`~msens.diagnose.effects.base.PhysicsMss` in a model state names its field model by
key and carries what effects may change (coil offset, magnet remanence, cable). This module
holds the field models (the study's transducers, and on demand their
:class:`~msens.magnetics.variants.RemanenceFamily`) and turns a ``PhysicsMss`` into the
:class:`~msens.magnetics.mss.MssSensor` whose DAQ voltage is the sensor's record — the same
functions ``msens run`` uses, so an undisturbed diagnosis reproduces the run exactly. With
eddy currents (``[field] eddy_currents = true``) a model also holds each coil's frequency
response (the run's :func:`msens.magnetics.dynamic.dynamic_report`) and :func:`signals` is
the frequency-domain read-out of :func:`msens.magnetics.eddy_readout.dynamic_signals`; the effects
that need field-model variants (coil offset, magnet remanence) are then not searched.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import numpy as np

from msens.config.fieldsetup import EddySettings, coil_geometry, eddy_settings, geometry_from_study
from msens.config.schema import CoilSpec, MssModel
from msens.diagnose.effects.base import Context, PhysicsMss
from msens.errors import internal
from msens.field.geometry import SensorGeometry
from msens.magnetics.dynamic import dynamic_report
from msens.magnetics.eddy_readout import dynamic_signals
from msens.magnetics.frequency_response import FrequencyResponse
from msens.magnetics.mss import MssRecord, MssSensor, mss_signals, readout
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import Transducer, cache_key, magnetic_precompression
from msens.magnetics.transducer_cache import transducers_for
from msens.magnetics.variants import RemanenceFamily, remanence_family
from msens.params.materials import BEAD_STEEL

# Field models of this process by key: geometry, nominal transducers and (with eddy
# currents) frequency responses; remanence families lazily.
_MODELS: dict[str, tuple[SensorGeometry, dict[int, Transducer],
                         dict[int, FrequencyResponse] | None]] = {}
_FAMILIES: dict[str, RemanenceFamily] = {}


def register(geometry: SensorGeometry, eddy: EddySettings | None = None, *,
             contact_maps: bool = False) -> str:
    """Solve (or read from the cache) a geometry's transducers (with ``contact_maps`` their
    nonlinear contact maps), and with ``eddy`` its coils' frequency responses (as
    ``msens run``); return its model key."""
    key = cache_key(geometry, stress_force=geometry.beads.contact_load,
                    law=law_for_steel(geometry.steel), material=BEAD_STEEL, approach=True)
    if eddy is not None:
        key += f"+eddy:{eddy.options!r}:{eddy.steel!r}"
    if contact_maps:
        key += "+contact-maps"
    if key not in _MODELS:
        # with the coils' offset profiles: the coil_position effect moves them
        responses = None if eddy is None else dynamic_report(
            geometry, options=eddy.options, steel=eddy.steel, offsets=True).responses
        _MODELS[key] = (geometry, transducers_for(geometry, contact_maps=contact_maps),
                        responses)
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
    eddy = eddy_settings(ctx.study) if ctx.study.field.eddy_currents else None
    model = register(geometry_from_study(ctx.study, ctx.setup), eddy,
                     contact_maps=ctx.study.field.contact_map)
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
    tr = transducers(spec.model)[spec.particle]
    if spec.remanence_factor != 1.0:
        # the variants are solved without contact maps: they read the study's (if any)
        tr = family(spec.model).transducer(spec.particle,
                                           spec.remanence_factor).reading_maps_of(tr)
    if spec.offset_m != 0.0:
        tr = tr.shifted(spec.offset_m)
    return MssSensor(tr, readout(spec.coil, tr.resistance_ohm, tr.inductance_H,
                                 spec.electronics))


def signals(spec: PhysicsMss, t: np.ndarray, force: np.ndarray, *,
            approach: np.ndarray | None = None, columns: np.ndarray | None = None,
            static: np.ndarray | None = None) -> MssRecord:
    """The noise-free coil signals of a physics MsS for a chain's contact forces (and
    approaches), as ``msens run`` forms them: :func:`msens.magnetics.mss.mss_signals`, or with
    eddy currents :func:`msens.magnetics.eddy_readout.dynamic_signals` (arguments as those)."""
    mss = sensor(spec)
    rate = spec.electronics.sample_rate_hz
    if not eddy_currents(spec.model):
        return mss_signals(mss, t, force, rate, approach=approach, columns=columns,
                           static=static)
    return dynamic_signals(mss.transducer, response(spec), mss.circuit, t, force, rate,
                           approach=approach, columns=columns)


@lru_cache(maxsize=4096)
def response(spec: PhysicsMss) -> FrequencyResponse:
    """The eddy-current frequency response of a physics MsS as ``spec`` says (its coil moved
    by ``offset_m``), of a model registered with eddy currents."""
    internal(spec.remanence_factor == 1.0,
             "internal: no eddy-current variants for magnet remanence")
    nominal = _MODELS[spec.model][2][spec.particle]
    return nominal if spec.offset_m == 0.0 else nominal.shifted(spec.offset_m)


def eddy_currents(model: str) -> bool:
    """Whether a registered model reads its coils with eddy currents."""
    return _MODELS[model][2] is not None


def with_physics(physics: tuple[PhysicsMss | None, ...], **changes) -> tuple:
    """The specs with ``changes`` applied to every physics MsS."""
    internal(any(p is not None for p in physics), "internal: the state has no physics MsS")
    return tuple(None if p is None else dataclasses.replace(p, **changes) for p in physics)


__all__ = ["eddy_currents", "family", "magnetic_force", "register", "response", "sensor",
           "setup_physics", "signals", "transducers", "with_physics"]

"""Physics MsS sensors inside a diagnosis: the run's transducer core, varied by effects.

A :class:`~msens.diagnose.models.PhysicsMss` in a model state carries its field model and
what effects may change (coil offset, magnet remanence, cable). The field models (the
study's transducers, and on demand their :class:`~msens.magnetics.variants.RemanenceFamily`)
belong to the diagnosis run (:class:`~msens.diagnose.models.ModelBank` in its context); this
module turns a ``PhysicsMss`` into the :class:`~msens.readout.mss.MssSensor` whose DAQ
voltage is the sensor's record — the same functions ``msens run`` uses, so an undisturbed
diagnosis reproduces the run exactly. With eddy currents (``[field] eddy_currents = true``)
a model also holds each coil's frequency response (the run's
:func:`msens.magnetics.dynamic_cache.dynamic_report`) and :func:`signals` is the frequency-domain
read-out of :func:`msens.readout.mss.mss_signals`; the effects that need
field-model variants (coil offset, magnet remanence) are then not searched.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from msens.config.fieldsetup import coil_geometry, eddy_settings, geometry_from_study
from msens.config.schema import MssModel
from msens.diagnose.effects.base import Context
from msens.diagnose.models import FieldModel, PhysicsMss
from msens.errors import internal
from msens.magnetics.frequency_response import FrequencyResponse
from msens.magnetics.transducer import Transducer, magnetic_precompression
from msens.readout.mss import MssRecord, MssSensor, mss_signals


def transducers(model: FieldModel) -> dict[int, Transducer]:
    """The nominal transducers of a field model."""
    return model.transducers


def setup_physics(ctx: Context) -> tuple[PhysicsMss | None, ...]:
    """Per sensor of the setup, its physics MsS (None for other sensors); empty if none."""
    sensors = ctx.setup.sensors
    if not any(s.model is MssModel.PHYSICS for s in sensors):
        return ()
    eddy = eddy_settings(ctx.study) if ctx.study.field.eddy_currents else None
    model = ctx.models.register(geometry_from_study(ctx.study, ctx.setup), eddy,
                                contact_maps=ctx.study.field.contact_map)
    return tuple(
        PhysicsMss(model=model, particle=s.particle,
                   coil=coil_geometry(s.coil, s.particle),
                   electronics=ctx.study.electronics)
        if s.model is MssModel.PHYSICS else None for s in sensors)


def magnetic_force(physics: tuple[PhysicsMss | None, ...]) -> np.ndarray | None:
    """Static magnetic force on each particle of the states' magnets, N (None: no magnets)."""
    spec = next((p for p in physics if p is not None), None)
    if spec is None:
        return None
    if spec.remanence_factor == 1.0:
        return magnetic_precompression(spec.model.transducers)
    return spec.model.family().particle_force(spec.remanence_factor)


def sensor(spec: PhysicsMss) -> MssSensor:
    """The transducer and read-out circuit of a physics MsS as ``spec`` says (kept by its
    field model)."""
    return spec.model.sensor(spec)


def signals(spec: PhysicsMss, t: np.ndarray, force: np.ndarray, *,
            approach: np.ndarray | None = None, columns: np.ndarray | None = None,
            static: np.ndarray | None = None) -> MssRecord:
    """The noise-free coil signals of a physics MsS for a chain's contact forces (and
    approaches), by the read-out ``msens run`` uses: :func:`msens.readout.mss.mss_signals`
    (with eddy currents with the coil's frequency response; arguments as that)."""
    return mss_signals(sensor(spec), t, force, spec.electronics.sample_rate_hz,
                       response=response(spec) if spec.model.eddy_currents else None,
                       approach=approach, columns=columns, static=static)


def response(spec: PhysicsMss) -> FrequencyResponse:
    """The eddy-current frequency response of a physics MsS as ``spec`` says (its coil moved
    by ``offset_m``), of a model registered with eddy currents (kept by the model)."""
    return spec.model.response(spec)


def with_physics(physics: tuple[PhysicsMss | None, ...], **changes) -> tuple:
    """The specs with ``changes`` applied to every physics MsS."""
    internal(any(p is not None for p in physics), "internal: the state has no physics MsS")
    return tuple(None if p is None else dataclasses.replace(p, **changes) for p in physics)


__all__ = ["magnetic_force", "response", "sensor", "setup_physics", "signals", "transducers",
           "with_physics"]

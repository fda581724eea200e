"""The field models of one diagnosis run (its model bank).

A diagnosis varies physics MsS sensors through their field model: the study's transducers,
with eddy currents their coils' frequency responses, and on demand the
:class:`~msens.magnetics.variants.RemanenceFamily` of the geometry (with eddy currents also
its :class:`~msens.magnetics.variants.RemanenceResponses`). A :class:`ModelBank`
belongs to one diagnosis run (its :class:`~msens.diagnose.effects.base.Context`): it solves or
reads each geometry's :class:`FieldModel` once, and each model keeps the sensors and
responses made from it. Nothing is kept at module level: two runs share nothing but the
artifact store (:mod:`msens.store`), and a model lives as long as its run.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from msens.config.fieldsetup import EddySettings
from msens.errors import internal
from msens.field.geometry import SensorGeometry
from msens.field.parts import Coil
from msens.magnetics.dynamic_cache import dynamic_report
from msens.magnetics.frequency_response import FrequencyResponse
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import Transducer, cache_key
from msens.magnetics.transducer_cache import transducers_for
from msens.magnetics.variants import (
    RemanenceFamily,
    RemanenceResponses,
    remanence_family,
    remanence_responses,
)
from msens.params.materials import BEAD_STEEL
from msens.readout.electronics import ElectronicsSpec
from msens.readout.mss import MssSensor, readout
from msens.store import Store

#: Sensors and responses a model keeps (the most recently used): a search over coil offsets
#: makes a new one per trial offset.
KEPT = 4096


class FieldModel:
    """One geometry's field model inside a diagnosis run.

    Parameters
    ----------
    key : str
        The model's key in its bank (transducer key, eddy and contact-map choices).
    geometry : SensorGeometry
    transducers : dict of int -> Transducer
        The nominal transducers, by coil particle.
    responses : dict of int -> FrequencyResponse, optional
        With eddy currents: each coil's frequency response (with offset profiles).
    store : Store, optional
        Where the remanence family's transducers are found or written.
    eddy : EddySettings, optional
        With eddy currents: the model's mesh options and steel conductivity (those of the
        remanence family's responses).
    """

    def __init__(self, key: str, geometry: SensorGeometry,
                 transducers: dict[int, Transducer],
                 responses: dict[int, FrequencyResponse] | None = None,
                 store: Store | None = None, eddy: EddySettings | None = None):
        self.key = key
        self.geometry = geometry
        self.transducers = transducers
        self.responses = responses
        self.store = store
        self.eddy = eddy
        self._family: RemanenceFamily | None = None
        self._response_family: RemanenceResponses | None = None
        # per model, not per process: they go when the run's bank goes
        self.sensor = lru_cache(maxsize=KEPT)(self._sensor)
        self.response = lru_cache(maxsize=KEPT)(self._response)

    def __repr__(self) -> str:
        return f"FieldModel({self.key!r})"

    @property
    def eddy_currents(self) -> bool:
        """Whether the model reads its coils with eddy currents."""
        return self.responses is not None

    def family(self) -> RemanenceFamily:
        """The remanence family of the geometry (solved or read on first use, then kept)."""
        if self._family is None:
            self._family = remanence_family(self.geometry, store=self.store)
        return self._family

    def response_family(self) -> RemanenceResponses:
        """The eddy-current responses of the geometry over the remanence factors (solved or
        read on first use, then kept)."""
        internal(self.eddy is not None, "internal: the model was registered without eddy "
                 "currents")
        if self._response_family is None:
            self._response_family = remanence_responses(
                self.geometry, options=self.eddy.options, steel=self.eddy.steel,
                store=self.store)
        return self._response_family

    def _sensor(self, spec: PhysicsMss) -> MssSensor:
        """The transducer and read-out circuit of a physics MsS as ``spec`` says."""
        tr = self.transducers[spec.particle]
        if spec.remanence_factor != 1.0:
            # the variants are solved without contact maps: they read the study's (if any)
            tr = self.family().transducer(spec.particle,
                                          spec.remanence_factor).reading_maps_of(tr)
        if spec.offset_m != 0.0:
            tr = tr.shifted(spec.offset_m)
        return MssSensor(tr, readout(spec.coil, tr.resistance_ohm,
                                     tr.inductance_H * spec.inductance_factor,
                                     spec.electronics))

    def _response(self, spec: PhysicsMss) -> FrequencyResponse:
        """The eddy-current frequency response of a physics MsS as ``spec`` says (its coil
        moved by ``offset_m``)."""
        internal(self.responses is not None,
                 "internal: the model was registered without eddy currents")
        if spec.remanence_factor != 1.0:
            internal(spec.offset_m == 0.0,
                     "internal: no eddy-current offset profiles at another remanence")
            resp = self.response_family().response(spec.particle, spec.remanence_factor)
        else:
            resp = self.responses[spec.particle]
            resp = resp if spec.offset_m == 0.0 else resp.shifted(spec.offset_m)
        f = spec.inductance_factor
        if f == 1.0:
            return resp
        z = np.asarray(resp.impedance)
        return replace(resp, impedance=resp.resistance_ohm + f * (z - resp.resistance_ohm),
                       static_inductance_H=f * resp.static_inductance_H)


@dataclass(frozen=True)
class PhysicsMss:
    """What a diagnosis may change about one physics MsS (see :mod:`msens.diagnose.physics`).

    Attributes
    ----------
    model : FieldModel
        The sensor's field model (registered in the run's :class:`ModelBank`).
    particle : int
        The coil's particle.
    coil : Coil
        The coil's geometry (winding capacitance of its circuit).
    electronics : ElectronicsSpec
        Cable and DAQ of its read-out.
    offset_m : float
        Axial offset of the coil from its nominal position, m (+ toward the striker).
    remanence_factor : float
        Remanence of every bias magnet over its nominal value.
    inductance_factor : float
        The coil's inductance over the field model's (with eddy currents: its impedance
        beyond the copper resistance, ``R_dc + f (Z - R_dc)``): a nuisance within the field
        model's accuracy, profiled by :mod:`msens.diagnose.inductance`.
    """

    model: FieldModel
    particle: int
    coil: Coil
    electronics: ElectronicsSpec
    offset_m: float = 0.0
    remanence_factor: float = 1.0
    inductance_factor: float = 1.0


class ModelBank:
    """The field models of one diagnosis run, by key.

    Parameters
    ----------
    store : Store, optional
        Where transducers, responses and meshes are found or written (default
        :meth:`msens.store.Store.default`, made on first use).
    """

    def __init__(self, store: Store | None = None):
        self._store = store
        self._models: dict[str, FieldModel] = {}

    def __repr__(self) -> str:
        return f"ModelBank({len(self._models)} models)"

    @property
    def store(self) -> Store:
        """The bank's artifact store."""
        if self._store is None:
            self._store = Store.default()
        return self._store

    def register(self, geometry: SensorGeometry, eddy: EddySettings | None = None, *,
                 contact_maps: bool = False) -> FieldModel:
        """The field model of ``geometry``: its transducers (with ``contact_maps`` their
        nonlinear contact maps), and with ``eddy`` its coils' frequency responses (as
        ``msens run``), solved or read once per run."""
        key = cache_key(geometry, stress_force=geometry.beads.contact_load,
                        law=law_for_steel(geometry.steel), material=BEAD_STEEL, approach=True)
        if eddy is not None:
            key += f"+eddy:{eddy.options!r}:{eddy.steel!r}"
        if contact_maps:
            key += "+contact-maps"
        if key not in self._models:
            # with the coils' offset profiles: the coil_position effect moves them
            responses = None if eddy is None else dynamic_report(
                geometry, options=eddy.options, steel=eddy.steel, offsets=True,
                store=self.store).responses
            self._models[key] = FieldModel(
                key, geometry, transducers_for(geometry, contact_maps=contact_maps,
                                               store=self.store),
                responses, self.store, eddy)
        return self._models[key]


__all__ = ["KEPT", "FieldModel", "ModelBank", "PhysicsMss"]

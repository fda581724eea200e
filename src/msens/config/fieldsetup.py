"""Build the field model's geometry from a validated study.

The field package knows nothing of studies; this module maps a setup's MsS sensors (coil and
magnet tables) and the study's ``[field]`` options onto :class:`SensorGeometry`, the way
:mod:`msens.config.assemble` maps a setup onto the chain. Dimensions a study leaves out take the
field model's documented defaults (the paper's coil; an *equivalent* ring magnet with two
pole pieces standing in for the undocumented bridge magnet; 1018 steel unless ``[field]``
gives a ``steel_bh`` table).
"""

from __future__ import annotations

from dataclasses import dataclass

from msens.config.schema import CoilSpec, MagnetSpec, SensorSpec, SetupSpec
from msens.config.study import Study
from msens.errors import InputError
from msens.field.build import MeshOptions
from msens.field.eddy import SKIN_SIZE
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.params.materials import MAGNET_GRADES, SIGMA_1018
from msens.readout.coil import wire_for
from msens.readout.sensors import SensorKind


def mss_setup(study: Study) -> SetupSpec:
    """The first setup with an MsS sensor."""
    for s in study.setups:
        if any(x.kind is SensorKind.MSS for x in s.sensors):
            return s
    raise InputError(f"{study.source}: the field model needs a [[sensor]] with kind = 'mss'")


def _given(**kw: float | None) -> dict[str, float]:
    return {k: v for k, v in kw.items() if v is not None}


def coil_geometry(spec: CoilSpec, particle: int) -> Coil:
    """The field model's coil for a study's coil table."""
    return Coil(particle=particle, turns=spec.turns, length=spec.length_m,
                inner_radius=spec.inner_radius_m, wire=wire_for(spec.wire),
                axial_offset=spec.axial_offset_m,
                **_given(packing_factor=spec.packing_factor))


def magnet_geometry(spec: MagnetSpec, particle: int) -> BiasMagnet | None:
    """The field model's bias magnet, or None when the study disables it."""
    if not spec.enabled:
        return None
    if spec.grade is not None:
        g = MAGNET_GRADES[spec.grade]
        material = {"grade": spec.grade, "remanence": g.remanence,
                    "recoil_permeability": g.recoil_permeability}
    else:
        material = {"grade": "custom", "remanence": spec.remanence_t,
                    "recoil_permeability": spec.recoil_permeability}
    dims = _given(inner_radius=spec.inner_radius_m, outer_radius=spec.outer_radius_m,
                  length=spec.length_m, pole_inner_radius=spec.pole_inner_radius_m,
                  pole_outer_radius=spec.pole_outer_radius_m,
                  pole_thickness=spec.pole_thickness_m)
    return BiasMagnet(particle=particle, axial_offset=spec.axial_offset_m, **material, **dims)


def sensor_unit(sensor: SensorSpec) -> SensorUnit:
    """Coil and magnet of one MsS sensor."""
    return SensorUnit(coil_geometry(sensor.coil, sensor.particle),
                      magnet_geometry(sensor.magnet, sensor.particle))


def geometry_from_study(study: Study, setup: SetupSpec | None = None) -> SensorGeometry:
    """The axisymmetric field-model geometry of ``setup`` (default: the first MsS setup).

    Raises
    ------
    InputError
        No MsS sensor, or parts that overlap, a magnet inside the tube, a coil at a
        particle outside the modelled chain (checked by :class:`SensorGeometry`).
    """
    setup = setup or mss_setup(study)
    if not any(s.kind is SensorKind.MSS for s in setup.sensors):
        raise InputError(f"{study.source}: setup {setup.name!r} has no MsS sensor")
    try:
        return _geometry(study, setup)
    except InputError as exc:  # name the study and the keys the geometry comes from
        hint = (" (give a larger 'field.air_radius_m', or smaller coil and magnet radii)"
                if "air box" in str(exc) else "")
        raise InputError(f"{study.source}: the field model of setup {setup.name!r} (its "
                         f"[[sensor]] coil and magnet tables and [field]): {exc}{hint}"
                         ) from None


def _geometry(study: Study, setup: SetupSpec) -> SensorGeometry:
    units = tuple(sensor_unit(s) for s in setup.sensors if s.kind is SensorKind.MSS)
    f = study.field
    count = study.chain.n_particles
    first, last = f.beads if f.beads is not None else (2, count)
    beads = BeadChain(first=first, last=last, count=count,
                      diameter=study.chain.bead_diameter_m,
                      **_given(contact_load=f.contact_load_n,
                               min_flat_radius=f.min_flat_radius_m,
                               contact_gap=f.contact_gap_m))
    air = AirBox(**_given(radius=f.air_radius_m, margin=f.air_margin_m))
    # A study without [field] steel_bh keeps the geometry's default 1018 curve.
    steel = {} if f.steel_bh is None else {"steel": f.steel_bh}
    return SensorGeometry(beads=beads, sensors=units, air=air,
                          reversibility=f.steel_reversibility, **steel)


@dataclass(frozen=True)
class EddySettings:
    """How a study's eddy-current model is built (``[field] eddy_currents = true``).

    Attributes
    ----------
    options : MeshOptions
        Mesh graded to ``skin_size`` at the surfaces of the beads near a coil.
    steel : float
        Conductivity of beads and pole pieces, S/m.
    """

    options: MeshOptions
    steel: float


def eddy_settings(study: Study) -> EddySettings:
    """The eddy-current model's mesh options and steel conductivity from the study's
    ``[field]`` (whether the study uses the model is ``study.field.eddy_currents``).
    ``msens run``, design and diagnose all take them from here, so they solve one model."""
    f = study.field
    return EddySettings(options=MeshOptions(skin_size=f.skin_size_m or SKIN_SIZE),
                        steel=f.steel_conductivity_s_per_m or SIGMA_1018)

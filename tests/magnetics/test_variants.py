"""Transducers of a moved coil and of magnets of another strength, against direct solves.

Small coarse model (beads 9..17, one sensor at 13) so the default suite stays fast. The moved
coil is read from the same source potentials (the coil is air): its table quadrature must
match a field model built with the coil there. The remanence family interpolates five field
models with a cubic spline: between nodes the magnets' pull and the total sensitivity must
match a direct solve within 1 % (measured: 0.1-0.3 %). The Villari part alone, 1-2 % of the
total, varies less smoothly with the remanence (the Villari reversal): within 5 % (measured up
to 4.3 % at 0.875).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.magnetics.transducer import magnetic_precompression
from msens.magnetics.transducer_cache import transducers_for
from msens.magnetics.variants import remanence_family, scaled_geometry
from msens.store import Store

COARSE = MeshOptions(bead_size=0.6e-3, centre_size=0.3e-3, flat_fraction=0.8, wedge_factor=4.0)


def _geometry(offset: float = 0.0) -> SensorGeometry:
    return SensorGeometry(beads=BeadChain(first=9, last=17),
                          sensors=(SensorUnit(Coil(particle=13, axial_offset=offset),
                                              BiasMagnet(particle=13)),),
                          air=AirBox(0.06, 0.05))


@pytest.fixture(scope="module")
def dirs(tmp_path_factory):
    return {"store": Store.at(tmp_path_factory.mktemp("artifacts")), "options": COARSE}


def _close(a, b, rel):
    scale = float(np.max(np.abs(b)))
    assert float(np.max(np.abs(np.asarray(a) - np.asarray(b)))) <= rel * scale


@pytest.mark.parametrize("offset", [0.0, 1.0e-3, -2.2e-3])
def test_shifted_coil_equals_a_model_with_the_coil_there(dirs, offset):
    nominal = transducers_for(_geometry(), **dirs)[13]
    moved = transducers_for(_geometry(offset), **dirs)[13]
    got = nominal.shifted(offset)
    # a different mesh (the coil region moved) and the table's bilinear quadrature
    _close(got.sensitivity_villari, moved.sensitivity_villari, 2e-2)
    _close(got.dlambda_dapproach, moved.dlambda_dapproach, 2e-2)
    if offset == 0.0:  # same mesh: table against exact quadrature
        _close(got.dlambda_dapproach, nominal.dlambda_dapproach, 1e-4)
    with pytest.raises(Exception, match="outside the tabulated"):
        nominal.shifted(1.0)


def test_remanence_family_between_nodes_matches_a_direct_solve(dirs):
    family = remanence_family(_geometry(), **dirs)
    for factor in (0.875, 1.3):
        direct = transducers_for(scaled_geometry(_geometry(), factor), **dirs)
        spline = family.transducer(13, factor)
        _close(family.particle_force(factor), magnetic_precompression(direct), 1e-2)
        _close(spline.dlambda_dapproach, direct[13].dlambda_dapproach, 1e-2)
        _close(spline.sensitivity("both"), direct[13].sensitivity("both"), 1e-2)
        _close(spline.sensitivity_villari, direct[13].sensitivity_villari, 5e-2)
        assert spline.inductance_H == pytest.approx(direct[13].inductance_H, rel=1e-3)
    # at a node the family is the solve itself
    _close(family.particle_force(1.0), magnetic_precompression(family.members[2]), 1e-12)
    # stronger magnets pull harder
    f = [np.max(np.abs(family.particle_force(x))) for x in (0.6, 1.0, 1.4)]
    assert f[0] < f[1] < f[2]
    assert dataclasses.replace(_geometry()).sensors[0].magnet.remanence == \
        scaled_geometry(_geometry(), 1.0).sensors[0].magnet.remanence


@pytest.mark.slow
def test_remanence_responses_between_nodes_match_a_direct_eddy_solve(dirs):
    """The eddy-current responses over the remanence factors (what a diagnosis of an eddy
    study reads for magnet_remanence) against a direct eddy-current model between nodes."""
    from msens.magnetics.dynamic_cache import dynamic_report
    from msens.magnetics.variants import remanence_responses

    kw = {**dirs, "frequencies": (0.0, 1e4, 3e4, 1e5)}
    family = remanence_responses(_geometry(), **kw)
    for factor in (0.875, 1.3):
        direct = dynamic_report(scaled_geometry(_geometry(), factor), **kw).responses[13]
        spline = family.response(13, factor)
        _close(spline.approach, direct.approach, 1e-2)
        _close(spline.villari, direct.villari, 5e-2)
        _close(spline.impedance, direct.impedance, 1e-3)
        assert spline.static_inductance_H == pytest.approx(direct.static_inductance_H,
                                                           rel=1e-3)
        assert spline.offsets is None
    # at a node the family is the solve itself
    node = family.members[2][13]
    assert np.array_equal(family.response(13, 1.0).approach, node.approach)
    with pytest.raises(Exception, match="outside the solved range"):
        family.response(13, 1.6)

"""The reversibility surrogate within 1 % of direct field solves at held-out values (issue 34).

Each held-out value is a field solve (about 10 s with the mesh cached, then read from the
user cache). ``benchmarks/uq_reversibility.py`` measures all 24 held-out values.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from msens import api
from msens.config.fieldsetup import coil_geometry, geometry_from_study
from msens.config.schema import CoilSpec
from msens.magnetics.reversibility import reversibility_family
from msens.magnetics.transducer import magnetic_precompression
from msens.magnetics.transducer_cache import transducers_for
from msens.pipeline import run_study
from msens.readout.mss import MssSensor, mss_signals, readout

pytestmark = pytest.mark.slow

#: Held-out reversibilities (between the nodes, one per interval and one near each end).
HELD_OUT = (0.1234, 0.2441, 0.4241, 0.7387, 0.9208)


def _peaks(study, setup, tr) -> np.ndarray:
    # peak |DAQ voltage| and peak |EMF| of the nominal chain run read through the coil, V
    spec = next(s for s in study.setups[0].sensors if s.particle == tr.particle)
    sensor = MssSensor(tr, readout(coil_geometry(spec.coil or CoilSpec(), tr.particle),
                                   tr.resistance_ohm, tr.inductance_H, study.electronics))
    h = setup.history
    rec = mss_signals(sensor, h.t, h.force, study.electronics.sample_rate_hz,
                      approach=h.approach)
    return np.array([np.max(np.abs(rec.voltage)), np.max(np.abs(rec.emf))])


@pytest.mark.parametrize("c", HELD_OUT)
def test_surrogate_within_one_percent_of_direct_solves(c):
    study = api.load_default()
    geometry = geometry_from_study(study)
    setup = run_study(study).setups[0]
    family = reversibility_family(geometry)
    direct = transducers_for(replace(geometry, reversibility=c))
    for p, tr0 in setup.transducers.items():
        exact = _peaks(study, setup, direct[p].reading_maps_of(tr0))
        approx = _peaks(study, setup, family.transducer(p, c).reading_maps_of(tr0))
        assert np.all(np.abs(approx / exact - 1.0) < 0.01), (p, c, approx, exact)
    pull = magnetic_precompression(direct)
    assert np.max(np.abs(family.particle_force(c) - pull)) < 0.01 * np.max(np.abs(pull))

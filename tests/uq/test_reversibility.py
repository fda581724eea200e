"""The steel's reversibility is propagated through a spline surrogate of the field model
(issue 34): at a node it is the direct solve, at the study's value it is ``msens run``, and a
uq row at another value is ``msens run`` of the study with that value.

The surrogate's node transducers of the main study are committed (no field solve).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from msens import api
from msens.config.fieldsetup import geometry_from_study
from msens.errors import InputError
from msens.magnetics.reversibility import NODES, QUANTITIES, reversibility_family
from msens.magnetics.transducer import magnetic_precompression
from msens.magnetics.transducer_cache import transducers_for
from msens.uq.inputs import FIELD_SURROGATE, parse_inputs
from msens.uq.model import Task, at_reversibility, evaluate

REVERSIBILITY = """schema = "msens.uncertainty/1"
[[input]]
name = "field.reversibility"
distribution = "loguniform"
lower = 0.1
upper = 1.0
reason = "test"
"""


@pytest.fixture(scope="module")
def study():
    return api.load_default()


@pytest.fixture(scope="module")
def run(study):
    return api.run(study)


@pytest.fixture(scope="module")
def family(study):
    return reversibility_family(geometry_from_study(study))


def test_surrogate_at_a_node_is_the_direct_solve(study, family):
    c = NODES[2]
    direct = transducers_for(replace(geometry_from_study(study), reversibility=c))
    for p, tr in direct.items():
        approx = family.transducer(p, c)
        for name in QUANTITIES:
            assert np.allclose(getattr(approx, name), getattr(tr, name), rtol=1e-12,
                               atol=0.0), name
        assert approx.inductance_H == pytest.approx(tr.inductance_H, rel=1e-12)
        assert approx.turns == tr.turns and approx.resistance_ohm == tr.resistance_ohm
    assert np.allclose(family.particle_force(c), magnetic_precompression(direct), rtol=1e-12,
                       atol=0.0)


def test_surrogate_moves_the_coil_between_the_nodes(family):
    # a larger small-signal permeability: more inductance, a larger approach source, and the
    # same bias state (the magnets' pull does not depend on c)
    trs = [family.transducer(13, c) for c in (0.1, 0.15, 0.3, 0.7, 1.0)]
    inductance = [t.inductance_H for t in trs]
    approach = [np.abs(t.dlambda_dapproach).max() for t in trs]
    assert np.all(np.diff(inductance) > 0) and np.all(np.diff(approach) > 0)
    pulls = [family.particle_force(c) for c in (0.1, 0.15, 0.3, 0.7, 1.0)]
    assert all(np.allclose(p, pulls[-1], rtol=1e-9, atol=1e-12) for p in pulls)
    with pytest.raises(InputError, match="outside the solved range"):
        family.transducer(13, 0.05)


def test_remanence_change_composes_on_top(run, family):
    nominal = run.setups[0].transducers[13]
    c = 0.3
    plain = at_reversibility(family.transducer(13, c), nominal)
    assert plain.approach_map is nominal.approach_map
    same = at_reversibility(family.transducer(13, c), nominal, nominal)
    assert np.array_equal(same.sensitivity_villari, plain.sensitivity_villari)
    stronger = replace(nominal, sensitivity_villari=1.1 * np.asarray(
        nominal.sensitivity_villari))
    composed = at_reversibility(family.transducer(13, c), nominal, stronger)
    # the +10 % change at the nominal c, scaled by the size of the coil's linkage at c
    change = composed.sensitivity_villari - plain.sensitivity_villari
    scale = np.linalg.norm(plain.sensitivity_villari) / np.linalg.norm(
        nominal.sensitivity_villari)
    assert np.allclose(change, 0.1 * scale * np.asarray(nominal.sensitivity_villari))


def test_route_and_range(study):
    inputs = parse_inputs(REVERSIBILITY, study, source="r.toml")
    (p,) = inputs.propagated
    assert p.route == FIELD_SURROGATE and p.nominal == 1.0 and not inputs.held
    assert p.physical == (NODES[0], NODES[-1])


def test_uq_row_is_msens_run_at_that_reversibility(study, run):
    inputs = parse_inputs(REVERSIBILITY, study, source="r.toml")
    c = NODES[1]  # a node: the surrogate is the direct solve there (to rounding)
    ev = evaluate(Task(study, inputs, np.array([[1.0], [c]]), np.array([False, False])))
    nominal = run
    other = api.run(study.replace({"field.small_signal_permeability": "reversible",
                                   "field.reversibility": c}))
    for col, result in ((0, nominal), (1, other)):
        for r, spec in zip(result.rows(), result.setups[0].sensors, strict=True):
            name = f"paper-mss/mss@{r['particle']}"
            peak = np.max(np.abs(spec.mss.voltage))
            if col == 0:  # the study's own field model: exactly msens run
                assert ev.features[f"{name}/peak_voltage_V"][col] == peak
                assert ev.features[f"{name}/tof_us"][col] == r["tof_us"]
            else:
                assert ev.features[f"{name}/peak_voltage_V"][col] == pytest.approx(peak,
                                                                                   rel=1e-9)
                assert ev.features[f"{name}/peak_emf_V"][col] == pytest.approx(
                    np.max(np.abs(spec.mss.emf)), rel=1e-9)
                assert ev.features[f"{name}/tof_us"][col] == pytest.approx(r["tof_us"],
                                                                           rel=1e-9)
    # the permeability choice moves coil 13's peak voltage by about a factor of two
    v = ev.features["paper-mss/mss@13/peak_voltage_V"]
    assert v[1] < 0.8 * v[0]

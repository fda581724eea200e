"""The steel's reversibility with eddy currents: the coils' frequency responses through a
spline surrogate over eddy-current models at the nodes (issue 33: the uncertainty of the
main study's prediction survives turning eddy currents on).

The eddy-current models of the main study at the nodes are committed (no field solve); the
surrogate's error between the nodes is measured by ``python benchmarks/uq_reversibility.py
--eddy`` (direct solves take minutes each).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from tests.uq.test_reversibility import REVERSIBILITY

from msens import api
from msens.config.fieldsetup import eddy_settings, geometry_from_study
from msens.errors import InputError
from msens.magnetics.dynamic_cache import dynamic_report
from msens.magnetics.family import RESPONSE_QUANTITIES
from msens.magnetics.reversibility import (
    NODES,
    ReversibilityResponses,
    reversibility_responses,
)
from msens.uq.inputs import FIELD_SURROGATE, parse_inputs
from msens.uq.model import Task, evaluate, response_at


@pytest.fixture(scope="module")
def study():
    return api.load_default().replace({"field.eddy_currents": True})


@pytest.fixture(scope="module")
def kwargs(study):
    eddy = eddy_settings(study)
    return {"options": eddy.options, "steel": eddy.steel}


@pytest.fixture(scope="module")
def family(study, kwargs):
    return reversibility_responses(geometry_from_study(study), **kwargs)


def test_response_surrogate_at_a_node_is_the_eddy_current_model(study, kwargs, family):
    c = NODES[2]
    direct = dynamic_report(replace(geometry_from_study(study), reversibility=c),
                            **kwargs).responses
    for p, r in direct.items():
        approx = family.response(p, c)
        for name in RESPONSE_QUANTITIES:
            np.testing.assert_allclose(getattr(approx, name), getattr(r, name), rtol=1e-12,
                                       atol=0.0, err_msg=name)
        assert approx.static_inductance_H == pytest.approx(r.static_inductance_H, rel=1e-12)
        assert approx.resistance_ohm == r.resistance_ohm
        assert approx.offsets is None and "reversibility 0.316" in approx.source


@pytest.mark.parametrize("drop", [1, 2, 3])
def test_the_spline_predicts_a_left_out_model(family, drop):
    """Leave one inner node out (twice the node spacing there): the spline through the other
    four predicts the left-out eddy-current model's D_c(ω) of the coil's own contacts within
    0.5 % and Z(ω) within 0.05 % at every frequency (measured 0.15-0.33 % and 0.013-0.021 %;
    with every node the error at held-out values is `benchmarks/uq_reversibility.py
    --eddy`'s)."""
    keep = [i for i in range(len(NODES)) if i != drop]
    loo = ReversibilityResponses(family.geometry, tuple(NODES[i] for i in keep),
                                 tuple(family.members[i] for i in keep))
    for p, direct in family.members[drop].items():
        approx = loo.response(p, NODES[drop])
        own = [list(direct.contacts).index(c) for c in (p - 1, p)]
        np.testing.assert_allclose(approx.approach[:, own], direct.approach[:, own],
                                   rtol=5e-3, atol=0.0)
        np.testing.assert_allclose(approx.impedance, direct.impedance, rtol=5e-4, atol=0.0)
    with pytest.raises(InputError, match="outside the solved range"):
        family.response(13, 0.05)


def test_reversibility_is_propagated_with_eddy_currents(study):
    inputs = parse_inputs(REVERSIBILITY, study, source="r.toml")
    (p,) = inputs.propagated
    assert p.route == FIELD_SURROGATE and not inputs.held
    assert p.physical == (NODES[0], NODES[-1])


def test_uq_row_is_msens_run_at_that_reversibility_with_eddy_currents(study):
    inputs = parse_inputs(REVERSIBILITY, study, source="r.toml")
    c = NODES[1]  # a node: the surrogates are the direct solves there (to rounding)
    ev = evaluate(Task(study, inputs, np.array([[1.0], [c]]), np.array([False, False])))
    nominal = api.run(study)
    other = api.run(study.replace({"field.small_signal_permeability": "reversible",
                                   "field.reversibility": c}))
    peaks = {}
    for col, result in ((0, nominal), (1, other)):
        for r, spec in zip(result.rows(), result.setups[0].sensors, strict=True):
            name = f"paper-mss/mss@{r['particle']}"
            peak = np.max(np.abs(spec.mss.voltage))
            got = ev.features[f"{name}/peak_voltage_V"][col]
            if col == 0:  # the study's own models: exactly msens run
                assert got == peak
            else:
                assert got == pytest.approx(peak, rel=1e-9)
                assert ev.features[f"{name}/tof_us"][col] == pytest.approx(r["tof_us"],
                                                                           rel=1e-9)
            peaks[(col, r["particle"])] = got
    # the reversible permeability lowers the eddy-current prediction too
    assert peaks[(1, 13)] < 0.8 * peaks[(0, 13)]


# ------------------------------------------------ every field input with eddy currents

def _field_model(study):
    from msens.config.fieldsetup import eddy_settings as settings
    from msens.diagnose.models import ModelBank

    return ModelBank().register(geometry_from_study(study), settings(study),
                                contact_maps=study.field.contact_map)


def test_response_at_each_field_input(study, family):
    """msens.uq.model.response_at: remanence alone is the remanence family's response (as
    the diagnosis reads it), an offset alone the offset profiles' shift, turns scale S_c,
    D_c and R_dc as N and Z - R_dc as N^2, and a change of nothing is the run's response."""
    model = _field_model(study)
    nominal = api.run(study).setups[0].responses[13]
    assert response_at(nominal) is nominal
    remanent = model.response_family().response(13, 0.75)
    assert response_at(nominal, remanent=remanent) == remanent
    profiles = model.responses[13]
    moved = response_at(profiles, moved=(profiles, 1e-3))
    np.testing.assert_allclose(moved.approach, profiles.shifted(1e-3).approach, rtol=1e-12)
    assert moved.offsets is None and np.array_equal(moved.impedance, profiles.impedance)
    more = response_at(nominal, turns_ratio=1.1)
    np.testing.assert_allclose(more.villari, 1.1 * nominal.villari, rtol=1e-15)
    np.testing.assert_allclose(more.approach, 1.1 * nominal.approach, rtol=1e-15)
    assert more.resistance_ohm == pytest.approx(1.1 * nominal.resistance_ohm, rel=1e-15)
    np.testing.assert_allclose(more.inductance, 1.21 * nominal.inductance, rtol=1e-12)
    # at another c, a remanence change equal to nothing adds nothing
    at_c = family.response(13, 0.3)
    same = response_at(nominal, at_c, remanent=nominal)
    np.testing.assert_array_equal(same.approach, at_c.approach)
    np.testing.assert_allclose(same.impedance, at_c.impedance, rtol=1e-15)


#: The field inputs a table or family reads (uniform, test ranges).
FIELD_INPUTS = 'schema = "msens.uncertainty/1"\n' + "".join(
    f'[[input]]\nname = "{name}"\ndistribution = "uniform"\nlower = {lo!r}\nupper = {hi!r}\n'
    'reason = "test"\n' for name, lo, hi in (("sensor[1].coil.turns", 1000, 1200),
                                             ("sensor.magnet.remanence_factor", 0.7, 1.3),
                                             ("sensor[1].coil.axial_offset_m", -1e-3, 1e-3)))


def test_uq_propagates_turns_offset_and_remanence_with_eddy_currents(study):
    """Each field input is propagated on the eddy-current main study (none held); the
    nominal row is msens run, more turns scale the coil's EMF exactly (the chain does not
    change), and weaker magnets delay the pulse."""
    inputs = parse_inputs(FIELD_INPUTS, study, source="f.toml")
    assert not inputs.held and len(inputs.propagated) == 3
    rows = np.array([[1100, 1.0, 0.0], [1000, 1.0, 0.0], [1100, 0.75, 0.0],
                     [1100, 1.0, 1e-3]])
    ev = evaluate(Task(study, inputs, rows, np.zeros(4, bool)))
    run = api.run(study)
    coil = run.setups[0].sensors[0]
    emf = ev.features["paper-mss/mss@13/peak_emf_V"]
    volts = ev.features["paper-mss/mss@13/peak_voltage_V"]
    assert volts[0] == np.max(np.abs(coil.mss.voltage))
    assert emf[1] / emf[0] == pytest.approx(1000 / 1100, rel=1e-12)
    # weaker magnets pull the beads less: the pulse arrives later, by as much as in the
    # magnetostatic model (same pull; measured +4.50 and +4.65 us)
    tof = ev.features["paper-mss/mss@13/tof_us"]
    ms = evaluate(Task(study.replace({"field.eddy_currents": False}),
                       parse_inputs(FIELD_INPUTS, study, source="f.toml"), rows[[0, 2]],
                       np.zeros(2, bool))).features["paper-mss/mss@13/tof_us"]
    assert tof[2] - tof[0] > 2.0
    assert tof[2] - tof[0] == pytest.approx(ms[1] - ms[0], abs=0.5)
    assert abs(volts[3] / volts[0] - 1) > 1e-3  # the moved coil reads another signal
    # the other coil is not moved and its turns are the study's
    other = ev.features["paper-mss/mss@18/peak_emf_V"]
    assert other[1] == other[0] and other[3] == other[0]

"""Uncertain inputs as data: the built-in file, and bad files refused in one message before
any solve (issue 34)."""

from __future__ import annotations

import numpy as np
import pytest

from msens import api
from msens.errors import InputError
from msens.uq.inputs import (
    CHAIN,
    FIELD_SURROGATE,
    FIELD_TABLE,
    HELD,
    TAIL,
    Distribution,
    default_inputs_path,
    load_inputs,
    parse_inputs,
)


@pytest.fixture(scope="module")
def study():
    return api.load_default()


def _file(*inputs: str, study: str = "") -> str:
    head = 'schema = "msens.uncertainty/1"\n' + (f'study = "{study}"\n' if study else "")
    return head + "".join(f"[[input]]\n{i}\nreason = 'test'\n" for i in inputs)


def test_builtin_inputs_of_the_main_study(study):
    inputs = load_inputs(None, study)
    assert inputs.source == str(default_inputs_path(study))
    assert len(inputs.propagated) >= 8
    assert all(i.reason and i.source for i in inputs.inputs)
    routes = {i.name: i.route for i in inputs.inputs}
    assert routes["striker.drop_height_m"] == CHAIN
    assert routes["sensor.magnet.remanence_factor"] == FIELD_TABLE
    assert routes["field.reversibility"] == FIELD_SURROGATE
    held = {i.name: i.held_reason for i in inputs.held}
    assert study.field.eddy_currents
    assert "eddy-current models over the conductivity" in held[
        "field.steel_conductivity_S_per_m"]
    assert "field.reversibility" not in held
    assert routes["field.steel_conductivity_S_per_m"] == HELD
    # each distribution lies inside the input's physical range, around the study's value
    for i in inputs.inputs:
        lo, hi = i.distribution.support
        assert i.physical[0] <= lo <= i.nominal <= hi <= i.physical[1], i.name


def test_the_magnetostatic_variant_holds_the_conductivity_for_its_own_reason():
    study = api.load_default(eddy_currents=False)
    assert not study.field.eddy_currents
    held = {i.name: i.held_reason for i in load_inputs(None, study).held}
    assert "eddy_currents = false" in held["field.steel_conductivity_S_per_m"]
    with pytest.raises(InputError, match="eddy_currents = false"):
        parse_inputs(_file('name = "field.steel_conductivity_S_per_m"\ndistribution = '
                           '"uniform"\nlower = 5e6\nupper = 7e6'), study, source="u.toml")


def test_builtin_inputs_of_paper_table2():
    inputs = load_inputs(None, api.load_paper_table2())
    assert len(inputs.propagated) == 7 and not inputs.held
    assert {i.route for i in inputs.inputs} == {CHAIN}


def test_values_are_the_inverse_cdf(study):
    u = np.array([[0.0, 0.5], [1.0, 0.25]])
    d = Distribution("uniform", (2.0, 4.0))
    assert d.values(u[:, 1]).tolist() == [3.0, 2.5]
    n = Distribution("normal", (1.0, 0.1))
    lo, hi = n.support
    assert n.values(np.array([0.0, 1.0])).tolist() == pytest.approx([lo, hi])
    assert lo == pytest.approx(1.0 - 0.1 * 4.753, abs=1e-3) and TAIL == 1e-6


@pytest.mark.parametrize(("text", "words"), [
    (_file('name = "chain.bead_colour"\ndistribution = "uniform"\nlower = 0\nupper = 1'),
     ["input[1].name", "chain.bead_colour", "allowed:", "striker.drop_height_m"]),
    (_file('name = "sensor.magnet.remanence_factor"\ndistribution = "uniform"\n'
           'lower = 0.3\nupper = 1.3'),
     ["input[1].distribution", "physical range", "0.3..1.3", "allowed 0.5..1.5"]),
    (_file('name = "striker.drop_height_m"\ndistribution = "normal"\nmean = 0.004\n'
           'std = 0.002'),
     ["normal(0.004, 0.002)", "quantiles", "physical range"]),
    (_file('name = "chain.youngs_modulus_pa"\ndistribution = "uniform"\nlower = 2e11\n'
           'upper = 1.9e11'), ["input[1].upper", "must be above 'lower'"]),
    (_file('name = "chain.bead_mass_kg"\ndistribution = "uniform"\nlower = 4.4e-4\n'
           'upper = 4.6e-4', 'name = "chain.bead_mass_kg"\ndistribution = "uniform"\n'
           'lower = 4.4e-4\nupper = 4.6e-4'), ["input[2].name", "repeats"]),
    (_file('name = "sensor[3].coil.turns"\ndistribution = "uniform"\nlower = 1000\n'
           'upper = 1200'), ["sensor[3] is not a physics MsS"]),
    (_file('name = "chain.bead_mass_kg"\ndistribution = "beta"\nlower = 4.4e-4\n'
           'upper = 4.6e-4'), ["input[1].distribution", "must be one of"]),
    (_file('name = "chain.bead_mass_kg"\ndistribution = "uniform"\nlower = 4.4e-4\n'
           'upper = 4.6e-4', study="paper-table2"), ["'study'", "paper-table2"]),
    ('schema = "msens.uncertainty/1"\n', ["no [[input]] tables"]),
    (_file('name = "field.steel_conductivity_S_per_m"\ndistribution = "uniform"\n'
           'lower = 5e6\nupper = 7e6'), ["every input is held", "eddy-current models over"]),
    (_file('name = "field.reversibility"\ndistribution = "loguniform"\nlower = 0.05\n'
           'upper = 1.0'), ["physical range", "allowed 0.1..1", "surrogate"]),
])
def test_bad_files_name_what_is_wrong(study, text, words):
    with pytest.raises(InputError) as err:
        parse_inputs(text, study, source="u.toml")
    message = str(err.value)
    assert message.startswith("u.toml") and "\n" not in message
    for w in words:
        assert w in message, (w, message)


def test_a_study_without_a_builtin_file_is_told_to_give_one(study, tmp_path):
    other = study.replace({"name": "my-rig", "reference": None})
    with pytest.raises(InputError, match="--inputs FILE"):
        load_inputs(None, other)
    with pytest.raises(InputError, match="not found"):
        load_inputs(tmp_path / "missing.toml", other)


@pytest.mark.parametrize("where", ["/dev/zero", "folder", "binary"])
def test_an_uncertainty_file_that_cannot_be_read(study, tmp_path, where):
    """/dev/zero was read until memory ran out (found by the fuzz campaign)."""
    path = {"/dev/zero": "/dev/zero", "folder": str(tmp_path)}.get(where, tmp_path / "b.toml")
    if where == "binary":
        path.write_bytes(b"\xff\xfe\x00bad")
    with pytest.raises(InputError, match="uncertainty file") as info:
        load_inputs(path, study)
    assert "\n" not in str(info.value)

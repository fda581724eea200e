"""Forward propagation: the nominal row is ``msens run``, the scheme is SALib's, the indices
find the input that matters, the same seed gives the same numbers (issue 34).

The main study's transducers are committed (no field solve); a few rows cost ~0.35 s each.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from msens import api
from msens.cli import main
from msens.config.fieldsetup import geometry_from_study
from msens.magnetics.transducer_cache import transducers_for
from msens.uq.inputs import InputSet, parse_inputs
from msens.uq.model import Task, evaluate, with_turns
from msens.uq.propagate import ab_rows, propagate, sobol_indices, unit_samples

CHAIN_INPUTS = """schema = "msens.uncertainty/1"
[[input]]
name = "striker.drop_height_m"
distribution = "uniform"
lower = 6.7e-3
upper = 7.7e-3
reason = "test"
[[input]]
name = "electronics.cable_capacitance_F"
distribution = "uniform"
lower = 50e-12
upper = 200e-12
reason = "test"
"""


@pytest.fixture(scope="module")
def study():
    return api.load_default()


@pytest.fixture(scope="module")
def inputs(study):
    return parse_inputs(CHAIN_INPUTS, study, source="chain.toml")


def test_nominal_row_is_msens_run(study):
    from msens.uq.inputs import load_inputs

    builtin = load_inputs(None, study)  # every route: chain, field tables (x nominal)
    row = np.array([[p.nominal for p in builtin.propagated]])
    ev = evaluate(Task(study, builtin, row, np.array([True])))
    result = api.run(study)
    for r, spec in zip(result.rows(), result.setups[0].sensors, strict=True):
        name = f"paper-mss/mss@{r['particle']}"
        assert ev.features[f"{name}/tof_us"][0] == r["tof_us"]
        assert ev.features[f"{name}/ar"][0] == r["ar"]
        assert ev.features[f"{name}/peak_voltage_V"][0] == np.max(np.abs(spec.mss.voltage))
        assert ev.features[f"{name}/peak_emf_V"][0] == np.max(np.abs(spec.mss.emf))
        assert np.array_equal(ev.waveforms[name][0], spec.voltage_shape.astype(np.float32))
    assert ev.features["paper-mss/speed_incident_m_per_s"][0] == r["speed_m_per_s"]


def test_turns_scale_linkage_inductance_and_resistance(study):
    tr = transducers_for(geometry_from_study(study))[13]
    more = with_turns(tr, 1210)
    assert more.turns == 1210
    assert np.allclose(more.sensitivity_villari, 1.1 * np.asarray(tr.sensitivity_villari))
    assert np.allclose(more.dlambda_dapproach, 1.1 * np.asarray(tr.dlambda_dapproach))
    assert more.inductance_H == pytest.approx(1.21 * tr.inductance_H)
    assert more.resistance_ohm == pytest.approx(1.1 * tr.resistance_ohm)
    assert more.magnetic_particle_force is tr.magnetic_particle_force


def test_saltelli_layout_and_seed(inputs):
    u = unit_samples(inputs, 8, seed=3)
    assert u.shape == (8 * 4, 2)
    assert np.array_equal(u, unit_samples(inputs, 8, seed=3))
    assert not np.array_equal(u, unit_samples(inputs, 8, seed=4))
    rows = ab_rows(2, 8)
    a, b = u[rows[0::2]], u[rows[1::2]]
    # the mixed rows are A with column j from B: that is what SALib's analysis assumes
    blocks = u.reshape(8, 4, 2)
    assert np.array_equal(blocks[:, 1, 1], a[:, 1]) and np.array_equal(blocks[:, 1, 0], b[:, 0])
    assert np.array_equal(blocks[:, 2, 0], a[:, 0]) and np.array_equal(blocks[:, 2, 1], b[:, 1])


def test_indices_of_a_known_function(inputs):
    # y = 4 x1 + x2 on independent uniforms: S1 = ST = 16/17 and 1/17
    u = unit_samples(inputs, 1024, seed=0)
    ix = sobol_indices(inputs, 4.0 * u[:, 0] + u[:, 1], seed=0)
    assert ix.first == pytest.approx([16 / 17, 1 / 17], abs=0.03)
    assert ix.total == pytest.approx([16 / 17, 1 / 17], abs=0.03)
    assert np.all(ix.first_conf > 0) and ix.note == ""
    flat = sobol_indices(inputs, np.ones(u.shape[0]), seed=0)
    assert flat.note == "does not vary with the inputs" and np.all(flat.total == 0)
    holes = sobol_indices(inputs, np.where(u[:, 0] > 0.9, np.nan, u[:, 1]), seed=0)
    assert "not found" in holes.note and np.all(np.isnan(holes.total))


def test_propagation_bands_and_indices(study, inputs):
    result = propagate(study, inputs, samples=4, seed=0, workers=1)
    assert result.runs == 16 and result.values.shape == (16, 2)
    tof = "paper-mss/mss@13/tof_us"
    lo, mid, hi = result.band(tof)
    assert lo < mid < hi
    # the cable acts after the EMF: no index of it there; a higher drop, a larger EMF
    emf = "paper-mss/mss@13/peak_emf_V"
    ix = result.indices[emf]
    assert ix.total[1] == 0.0 and ix.first[1] == 0.0 and ix.total[0] > 0.0
    order = np.argsort(result.values[:, 0])
    assert np.all(np.diff(result.features[emf][order]) >= 0.0)
    assert result.waveforms["paper-mss/mss@13"].shape == (8, result.t.size)
    band = result.waveform_band("paper-mss/mss@13")
    assert np.all(band[0] <= band[1]) and np.all(band[1] <= band[2])
    # the same values, the same numbers (rows evaluated again in another chunk)
    again = evaluate(Task(study, inputs, result.values[5:8], np.zeros(3, dtype=bool)))
    assert all(np.array_equal(result.features[k][5:8], again.features[k])
               for k in result.features)


@pytest.mark.parametrize(("args", "words"), [
    (["--samples", "100"], "--samples must be a power of two"),
    (["--inputs", "BAD"], "is not an input msens can vary"),
    (["--inputs", "RANGE"], "leaves the input's physical range"),
    (["--workers", "0"], "--workers must be >= 1"),
])
def test_bad_input_exits_2_before_any_solve(tmp_path, capsys, monkeypatch, args, words):
    import msens.uq.workflow as wf

    def no_work(*a, **k):
        raise AssertionError("work started")

    monkeypatch.setattr(wf, "propagate", no_work)
    monkeypatch.setattr(wf, "nominal_features", no_work)
    monkeypatch.setattr(wf, "_calibrated", no_work)
    files = {"BAD": CHAIN_INPUTS.replace("striker.drop_height_m", "striker.mass_kg"),
             "RANGE": CHAIN_INPUTS.replace("upper = 200e-12", "upper = 20e-9")}
    for i, a in enumerate(args):
        if a in files:
            path = tmp_path / f"{a}.toml"
            path.write_text(files[a])
            args = [*args[:i], str(path), *args[i + 1:]]
    code = main(["uq", "--out", str(tmp_path / "out"), *args])
    err = [line for line in capsys.readouterr().err.strip().splitlines()
           if line.startswith("msens: error:")]  # (progress messages aside)
    assert code == 2 and len(err) == 1
    assert words in err[0]
    assert not (tmp_path / "out" / "uq.json").exists()


def test_command_writes_strict_json_and_figures(tmp_path, capsys):
    path = tmp_path / "chain.toml"
    path.write_text(CHAIN_INPUTS)
    code = main(["uq", "--inputs", str(path), "--out", str(tmp_path / "out"), "--samples",
                 "4", "--workers", "1", "-q"])
    assert code == 0
    text = (tmp_path / "out" / "uq.json").read_text()
    report = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict JSON: {c}"))
    assert report["cost"]["model_runs"] == 16 and report["cost"]["field_solves"] == 0
    o = report["outputs"]["paper-mss/mss@13/peak_voltage_V"]
    assert o["unit"] == "V" and o["quantiles"]["p05"] <= o["quantiles"]["p95"]
    assert set(o["sobol"]) == {"striker.drop_height_m", "electronics.cable_capacitance_F"}
    assert {"S1", "S1_conf", "ST", "ST_conf"} <= set(o["sobol"]["striker.drop_height_m"])
    assert report["waveforms"]["paper-mss/mss@13"]["unit"] == "V"
    cover = {(r["position"], r["output"].rsplit("/", 1)[1]): r
             for r in report["reference_coverage"]}
    assert set(cover) == {(p, f) for p in ("top", "bottom") for f in ("tof_us", "ar")}
    top = cover[("top", "tof_us")]
    assert top["experiment"] == 287.3 and top["output"] == "paper-mss/mss@13/tof_us"
    assert top["inside"] == (top["band_5_95"][0] <= 287.3 <= top["band_5_95"][1])
    for f in ("uq_waveforms.png", "uq_sobol.png"):
        assert (tmp_path / "out" / f).stat().st_size > 10_000
    assert "paper-mss/mss@13/tof_us" in capsys.readouterr().out


def test_one_uncertain_input_draws_its_figures(tmp_path, capsys):
    """With one input the Sobol panels had no room (tight_layout warned: an error under
    pytest's warnings-as-errors, an internal error for a user running with -W error)."""
    path = tmp_path / "one.toml"
    path.write_text(CHAIN_INPUTS.split("[[input]]\nname = \"electronics")[0])
    code = main(["uq", "--inputs", str(path), "--out", str(tmp_path / "out"), "--samples",
                 "4", "--workers", "1", "-q"])
    assert code == 0, capsys.readouterr().err
    report = json.loads((tmp_path / "out" / "uq.json").read_text())
    sobol = report["outputs"]["paper-mss/mss@13/peak_voltage_V"]["sobol"]
    assert set(sobol) == {"striker.drop_height_m"}
    assert (tmp_path / "out" / "uq_sobol.png").stat().st_size > 10_000


def test_inputs_set_is_frozen(inputs):
    assert isinstance(inputs, InputSet)
    with pytest.raises(AttributeError):
        inputs.source = "x"


def test_confidence_intervals_are_reproducible_with_seed_zero():
    """SALib leaves its bootstrap unseeded for seed 0: msens's default seed must still give
    the same intervals every time."""
    import numpy as np

    from msens.uq.inputs import parse_inputs
    from msens.uq.propagate import sobol_indices, unit_samples

    text = ('schema = "msens.uncertainty/1"\n'
            + "".join(f'[[input]]\nname = "{n}"\ndistribution = "uniform"\nlower = {lo}\n'
                      f'upper = {hi}\nreason = "test"\n'
                      for n, lo, hi in (("striker.drop_height_m", 6.7e-3, 7.7e-3),
                                        ("chain.gamma_contact_kg_per_s", 4.0, 5.0))))
    from msens import api

    inputs = parse_inputs(text, api.load_default())
    u = unit_samples(inputs, 16, 0)
    y = u[:, 0] + 0.3 * u[:, 1] ** 2
    a, b = sobol_indices(inputs, y, 0), sobol_indices(inputs, y, 0)
    np.testing.assert_array_equal(a.first_conf, b.first_conf)
    np.testing.assert_array_equal(a.total_conf, b.total_conf)

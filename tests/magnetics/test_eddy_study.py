"""``[field] eddy_currents = true``: a study's physics MsS through the eddy-current transducer.

A small study (ten beads, one coil) run twice, magnetostatic and with eddy currents: the
chain is the same, the eddy currents screen the beads, so the coil's voltage is smaller and
later; the study key is validated like every other.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from msens import api
from msens.errors import InputError
from msens.store import Store

TINY = (Path(__file__).parents[1] / "data" / "tiny-mss.toml").read_text().replace(
    "[[sensor]]", "[electronics]\nsample_rate_hz = 5e6\n[[sensor]]")


#: Eddy currents with a coarse skin mesh (0.3 mm; the default 30 µm is for accuracy, see
#: benchmarks/dynamic_mesh_convergence.py): the tests check the path, not the numbers.
EDDY = "[field]\neddy_currents = true\nskin_size_m = 3e-4\n"


def _study(tmp_path, extra: str = ""):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY + extra)
    return api.load(path)


@pytest.fixture(scope="module")
def eddy_runs(tmp_path_factory):
    """The tiny study run with and without eddy currents (own mesh cache): folder, eddy
    study, eddy result, static result."""
    tmp = tmp_path_factory.mktemp("eddy")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MSENS_MESH_DIR", str(tmp / "cache"))
        study = _study(tmp, EDDY)
        return tmp, study, api.run(study), api.run(_study(tmp))


def _coil_summary(result) -> dict:
    return api.physics_summary(result)["coils"][0]


def test_eddy_currents_screen_the_coil_signal(eddy_runs):
    _, eddy_study, result, static_result = eddy_runs
    static = static_result.setups[0].sensors[0]
    assert eddy_study.field.eddy_currents
    eddy = result.setups[0].sensors[0]
    # the mechanisms' EMFs with eddy currents add up to the record's EMF
    from msens.magnetics.eddy_readout import mechanism_emfs
    from msens.magnetics.emf import contact_rates

    setup = result.setups[0]
    tr = setup.transducers[eddy.sensor.particle]
    h = setup.history
    rates = contact_rates(h.t, h.force, tr.contacts, tr.contact_stiffness, approach=h.approach)
    parts = mechanism_emfs(setup.responses[eddy.sensor.particle], rates)
    np.testing.assert_allclose(parts["villari"] + parts["approach"], eddy.mss.emf, rtol=0,
                               atol=1e-12 * np.max(np.abs(eddy.mss.emf)))
    share = api.physics_summary(result)["coils"][0]["mechanism_share"]
    assert share["approach"]["peak_emf_V"] == pytest.approx(np.max(np.abs(parts["approach"])))
    # summary.json carries each coil's frequency response
    fr = api.physics_summary(result)["coils"][0]["frequency_response"]
    assert fr["frequencies_Hz"][0] == 0.0 and fr["contacts"] == [5, 6]
    mag = np.array(fr["approach_ratio_magnitude"])
    np.testing.assert_allclose(mag[0], 1.0, rtol=1e-12)
    assert np.all(mag[-1] < 0.9) and np.all(np.array(fr["approach_ratio_phase_deg"])[-1] < 0)
    assert fr["resistance_ohm"][-1] > fr["resistance_ohm"][0]  # eddy losses
    assert "frequency_response" not in _coil_summary(static_result)
    v0, v1 = static.mss.voltage, eddy.mss.voltage
    assert v1.shape == v0.shape and np.all(np.isfinite(v1))
    assert 0.3 * np.max(np.abs(v0)) < np.max(np.abs(v1)) < np.max(np.abs(v0))
    # screening is a lag: the eddy record best matches the static one shifted later
    lags = np.arange(-50, 51)
    corr = [np.dot(v1[max(k, 0):v1.size + min(k, 0)], v0[max(-k, 0):v0.size - max(k, 0)])
            for k in lags]
    assert lags[int(np.argmax(corr))] > 0


def test_eddy_currents_key_is_validated(tmp_path, capsys):
    with pytest.raises(InputError, match="eddy_currents"):
        _study(tmp_path, "[field]\neddy_currents = 1\n")
    with pytest.raises(InputError, match="steel_conductivity_S_per_m"):
        _study(tmp_path, "[field]\nsteel_conductivity_S_per_m = 1e12\n")
    with pytest.raises(InputError, match="skin_size_m"):
        _study(tmp_path, "[field]\nskin_size_m = 4e-5\n")        # without eddy currents
    with pytest.raises(InputError, match="skin_size_m"):
        _study(tmp_path, EDDY.replace("3e-4", "1e-8"))


def test_small_signal_permeability_key(tmp_path):
    from msens.config.fieldsetup import geometry_from_study
    from msens.params.materials import STEEL_REVERSIBILITY

    study = _study(tmp_path)
    assert study.field.steel_reversibility == 1.0
    rev = _study(tmp_path, '[field]\nsmall_signal_permeability = "reversible"\n')
    assert rev.field.steel_reversibility == STEEL_REVERSIBILITY
    geometry = geometry_from_study(rev, rev.setups[0])
    assert geometry.reversibility == STEEL_REVERSIBILITY
    chosen = _study(tmp_path, '[field]\nsmall_signal_permeability = "reversible"\n'
                              'reversibility = 0.25\n')
    assert chosen.field.steel_reversibility == 0.25
    for bad, key in (('small_signal_permeability = "initial"', "small_signal_permeability"),
                     ("reversibility = 0.3", "reversibility"),
                     ('small_signal_permeability = "reversible"\nreversibility = 0',
                      "reversibility"),
                     ('small_signal_permeability = "reversible"\nreversibility = 1.5',
                      "reversibility")):
        with pytest.raises(InputError, match=key):
            _study(tmp_path, f"[field]\n{bad}\n")


def test_eddy_current_records_carry_the_coils_thermal_noise(eddy_runs, monkeypatch):
    """With eddy currents the coil's Johnson noise comes from 4kT Re Z(f) of the field model.

    The run adds exactly :func:`add_readout_noise` with the coil's Z(f) to the noise-free
    record; a long realisation has the variance ∫S df; and, Z(f) being a passive impedance,
    the total is kT/C of the read-out's capacitance (equipartition) whatever the losses."""
    from msens.params.units import K_B
    from msens.readout.noise import NoiseModel, add_readout_noise, thermal_noise_psd

    tmp_path, _, quiet, _ = eddy_runs
    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp_path / "cache"))
    noisy = TINY.replace("[electronics]\n", "[electronics]\njohnson_noise = true\n")
    path = tmp_path / "noisy.toml"
    path.write_text(noisy + EDDY)
    study = api.load(path)
    setup = api.run(study).setups[0]
    rec, rec0 = setup.sensors[0].mss, quiet.setups[0].sensors[0].mss
    impedance = setup.responses[setup.sensors[0].sensor.particle].impedance_at
    e = study.electronics
    nm = NoiseModel(e.temperature_k)
    added = add_readout_noise(np.zeros(rec0.voltage.size), rec.circuit, nm, e.sample_rate_hz,
                              rng=e.seed, coil_impedance=impedance)
    np.testing.assert_allclose(rec.voltage - rec0.voltage, added, rtol=0, atol=1e-15)
    long = np.concatenate([add_readout_noise(np.zeros(100_000), rec.circuit, nm,
                                             e.sample_rate_hz, rng=k, coil_impedance=impedance)
                           for k in range(4)])
    f = np.linspace(0.0, e.sample_rate_hz / 2, 500_001)
    psd = thermal_noise_psd(rec.circuit, e.temperature_k, f, coil_impedance=impedance(f))
    assert np.var(long) == pytest.approx(np.trapezoid(psd, f), rel=0.04)
    f = np.linspace(0.0, 5e8, 2_000_001)
    total = np.trapezoid(thermal_noise_psd(rec.circuit, e.temperature_k, f,
                                           coil_impedance=impedance(f)), f)
    assert total == pytest.approx(K_B * e.temperature_k / rec.circuit.total_capacitance,
                                  rel=0.01)


def test_diagnose_baseline_with_eddy_currents_is_the_run(eddy_runs, monkeypatch):
    """diagnose on an eddy-current study: its baseline record is the run's DAQ voltage (the
    same frequency-domain read-out); the coil offset (the responses' offset profiles) and the
    magnet remanence (eddy-current models over the remanence factors) are searched.
    End to end on the main study: tests/verification/test_eddy_roundtrip.py (slow)."""
    from msens.diagnose.effects import Context, registry
    from msens.diagnose.predict import Predictor, baseline_state, setup_result
    from msens.diagnose.workflow import baseline_dissipation
    from msens.pipeline import output_times

    tmp, study, result, static = eddy_runs
    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp / "cache"))
    ctx = Context(study, study.setups[0])
    base = baseline_state(ctx, *baseline_dissipation(study))
    predicted = setup_result(ctx, base, Predictor(output_times(study))).sensors[0].mss
    run = result.setups[0].sensors[0].mss
    np.testing.assert_allclose(predicted.voltage, run.voltage, rtol=0,
                               atol=1e-9 * np.max(np.abs(run.voltage)))
    assert np.max(np.abs(run.voltage - static.setups[0].sensors[0].mss.voltage)) > 0.01
    searched = {name for name, e in registry().items() if e.applies(ctx)}
    assert {"cable_capacitance", "striker_velocity", "coil_position",
            "magnet_remanence"} <= searched
    static_ctx = Context(static.study, static.study.setups[0])
    assert {"coil_position", "magnet_remanence"} <= {
        name for name, e in registry().items() if e.applies(static_ctx)}


def test_moved_coil_response_equals_the_moved_coils_own_model(eddy_runs):
    """FrequencyResponse.shifted (offset profiles from the same harmonic source potentials)
    against the eddy-current model of the coil built 1 mm and −2 mm away (its own mesh):
    S_c(ω) and D_c(ω) within 1e-3 of their largest value at every frequency (measured
    2.9e-4 and 6.7e-5); at no offset the profiles equal the coil's reciprocity reading to
    1e-5 (measured 3e-6)."""
    from dataclasses import replace

    from msens.config.fieldsetup import eddy_settings, geometry_from_study
    from msens.magnetics.dynamic_cache import dynamic_report

    tmp, study, _, _ = eddy_runs
    g, e = geometry_from_study(study), eddy_settings(study)
    kw = {"options": e.options, "steel": e.steel, "store": Store.at(tmp / "cache")}
    (response,) = dynamic_report(g, offsets=True, **kw).responses.values()
    assert response.offsets[0] == pytest.approx(-3e-3) and response.offsets[-1] == 3e-3
    unit = g.sensors[0]
    for offset, tol in ((0.0, 1e-5), (1e-3, 1e-3), (-2e-3, 1e-3)):
        coil = replace(unit.coil, axial_offset=unit.coil.axial_offset + offset)
        moved = replace(g, sensors=(replace(unit, coil=coil),))
        (own,) = dynamic_report(moved, **kw).responses.values()
        shifted = response.shifted(offset)
        for name in ("villari", "approach"):
            a, b = getattr(shifted, name), getattr(own, name)
            assert np.all(np.max(np.abs(a - b), axis=1) <= tol * np.max(np.abs(b), axis=1))
        np.testing.assert_array_equal(shifted.impedance, response.impedance)
    with pytest.raises(InputError, match="outside the tabulated"):
        response.shifted(4e-3)


def _design_rows(eddy_runs, name: str, body: str) -> list[dict]:
    import csv

    tmp, study, _, _ = eddy_runs
    (tmp / f"{name}.toml").write_text(f'schema = "msens.sweep/1"\nname = "{name}"\n' + body)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MSENS_MESH_DIR", str(tmp / "cache"))
        api.design(study, tmp / f"{name}.toml", tmp / name, progress=False)
    with (tmp / name / "designs.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert all(r["status"] == "ok" for r in rows)
    return rows


def _equals_run(row: dict, run: dict, static: dict, tol: float) -> None:
    for key in ("peak_emf_V", "peak_voltage_V"):
        assert float(row[key]) == pytest.approx(run[key], rel=tol)
        assert float(row[key]) < static[key]  # the eddy currents screen
    for key in ("inductance_H", "resistance_ohm", "resonance_Hz"):
        assert float(row[key]) == pytest.approx(run[key], rel=1e-9)


def test_coil_design_with_eddy_currents_equals_msens_run(eddy_runs):
    """Coil sweep on the eddy-current model (table quadrature of every source's harmonic
    potential): the study's own coil gives the run's EMF and DAQ voltage (measured 6e-6),
    and the coil moved 2 mm off its bead reads a different signal."""
    rows = _design_rows(eddy_runs, "coil", "[coil]\nturns = [1100]\n"
                                           "axial_offset_m = [0.0, 2e-3]\n")
    _, _, run, static = eddy_runs
    _equals_run(rows[0], _coil_summary(run), _coil_summary(static), 1e-4)
    assert float(rows[1]["peak_emf_V"]) != pytest.approx(float(rows[0]["peak_emf_V"]),
                                                         rel=1e-3)


@pytest.mark.slow
def test_magnet_design_with_eddy_currents_equals_msens_run(eddy_runs):
    """Magnet sweep with eddy currents: the design's own eddy-current model; the study's own
    magnet gives the run's numbers (same model, same read-out)."""
    rows = _design_rows(eddy_runs, "magnet", '[magnet]\ngrade = ["ceramic8"]\n')
    _, _, run, static = eddy_runs
    _equals_run(rows[0], _coil_summary(run), _coil_summary(static), 1e-8)


def test_summary_says_what_rests_on_the_equivalent_magnet(eddy_runs):
    """Issue 33 item 4: summary.json splits the screening between the equivalent magnet's
    pole pieces and the beads."""
    split = _coil_summary(eddy_runs[2])["frequency_response"]["screening_by_part"]
    assert split["frequencies_Hz"] == [1e4, 3e4, 1e5]
    beads = np.asarray(split["beads"]["approach_ratio_magnitude"])
    full = np.asarray(split["all"]["approach_ratio_magnitude"])
    assert beads.shape == full.shape == (3, 2) and np.all(beads >= full)
    share = np.asarray(split["magnet_share_of_screening"])
    assert np.all((share >= 0) & (share <= 1))




def test_summary_puts_the_magnetostatic_values_beside_the_eddy_current_ones(eddy_runs):
    """Issue 33: with eddy currents summary.json reports each coil's peak DAQ voltage, its
    time and the read-out's resonance gain, and the same for the magnetostatic model, which
    is exactly ``msens run`` of the study without eddy currents."""
    _, _, result, static_result = eddy_runs
    eddy, static = _coil_summary(result), _coil_summary(static_result)
    ms = eddy["magnetostatic"]
    for key in ("peak_voltage_V", "peak_voltage_time_us", "peak_emf_V"):
        assert ms[key] == static[key]
    assert ms["readout_peak"] == static["readout_peak"]
    assert "magnetostatic" not in static
    # eddy currents screen the beads (smaller peak) and their losses damp the resonance
    assert eddy["peak_voltage_V"] < ms["peak_voltage_V"]
    assert eddy["readout_peak"]["gain"] < ms["readout_peak"]["gain"]
    # the lumped circuit's peak gain sits at its resonance (Q >> 1)
    assert static["readout_peak"]["frequency_Hz"] == pytest.approx(static["resonance_Hz"],
                                                                   rel=1e-3)


CHANGED = TINY.replace('model = "physics"', 'model = "physics"\n[sensor.coil]\nturns = 900\n'
                       'length_m = 8e-3\n') + EDDY


def _changed_run(tmp_path):
    path = tmp_path / "changed.toml"
    path.write_text(CHANGED)
    return api.run(api.load(path))


def test_a_changed_coil_with_eddy_currents_is_read_not_rebuilt(eddy_runs, monkeypatch,
                                                               tmp_path, caplog):
    """``msens run`` of the eddy-current study with its coil changed, after the default run:
    the coil's response is read from the solved model's harmonic tables
    (msens.magnetics.eddy_coil_read), nothing is meshed. Against a rebuild:
    tests/verification/test_eddy_coil_change.py (slow)."""
    tmp, _, result, _ = eddy_runs
    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp / "cache"))
    meshes = sorted((tmp / "cache").glob("sensor-*.msh"))
    with caplog.at_level("INFO"):
        read = _changed_run(tmp_path)
    assert "read from the model of the solved coils" in caplog.text
    assert sorted((tmp / "cache").glob("sensor-*.msh")) == meshes
    coil, solved = (api.physics_summary(r)["coils"][0] for r in (read, result))
    assert coil["resistance_ohm"] != solved["resistance_ohm"]
    assert coil["frequency_response"]["resistance_ohm"][0] == coil["resistance_ohm"]
    assert "screening_by_part" not in coil["frequency_response"]

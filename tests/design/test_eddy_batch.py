"""The batched eddy-current design rows equal the design-by-design read-out."""

from __future__ import annotations

import csv
import importlib
import pickle
from pathlib import Path

import numpy as np
import pytest
import scipy.fft

from msens.cli import main
from msens.design.metrics import SPECTRUM_CHUNK, dynamic_design_rows
from msens.errors import InputError
from msens.field.parts import Coil
from msens.magnetics.eddy_readout import PAD, emf_spectra
from msens.magnetics.frequency_response import coil_impedance
from msens.magnetics.harmonic_tables import HarmonicTables
from msens.magnetics.potentials import LinkageTable, rect_integral
from msens.readout.electronics import (
    ElectronicsSpec,
    coil_transfer_function,
    coil_transfer_functions,
)
from msens.readout.mss import readout

from .test_design_cli import TINY_COIL
from .test_metrics import _wave

metrics = importlib.import_module("msens.design.metrics")  # msens.design is the workflow

ROOT = Path(__file__).resolve().parents[2]


def _responses(freqs: np.ndarray, n_d: int, rng: np.random.Generator):
    """Smooth, lagging responses of n_d designs (shape (n_d, n_f, 3)) and L(ω) (n_d, n_f)."""
    lag = 1.0 / (1.0 + 1j * freqs / rng.uniform(2e4, 8e4, (n_d, 1)))  # (n_d, n_f)
    s0 = rng.uniform(-2e-8, 2e-8, (n_d, 1, 3))
    d0 = rng.uniform(-3e-2, 1e-2, (n_d, 1, 3))
    villari = s0 * lag[..., None] ** rng.uniform(0.5, 1.5, (1, 1, 3))
    approach = d0 * lag[..., None] ** rng.uniform(0.5, 1.5, (1, 1, 3))
    villari[:, 0] = villari[:, 0].real  # static values are real
    approach[:, 0] = approach[:, 0].real
    ind = rng.uniform(5e-3, 3e-2, (n_d, 1)) * (0.8 + 0.2 * lag)
    ind[:, 0] = ind[:, 0].real
    return villari, approach, ind


def _reference(coil, res, ind_static, freqs, villari, approach, ind_w, wave, elec):
    """One design the way dynamic_design_rows read it before batching: interp on every bin."""
    t = wave.rates.t
    n = scipy.fft.next_fast_len(int(np.ceil(PAD * t.size)), real=True)
    f = np.fft.rfftfreq(n, float(t[1] - t[0]))
    force = scipy.fft.rfft(wave.rates.force, n, axis=0)
    app = scipy.fft.rfft(wave.rates.approach, n, axis=0)
    e_hat = emf_spectra(freqs, villari, approach, f, force, app)
    z = coil_impedance(freqs, ind_w, res, f)
    h = coil_transfer_function(readout(coil, res, ind_static, elec), f, z)
    e = scipy.fft.irfft(e_hat, n)[:t.size]
    v = scipy.fft.irfft(h * e_hat, n)[:t.size]
    return float(np.max(np.abs(e))), float(np.max(np.abs(v)))


@pytest.mark.parametrize("freqs", [np.array([0.0, 10.0, 300.0, 3e3, 1e4, 3e4, 1e5, 2e5]),
                                   np.array([0.0, 5e4])])
def test_batched_rows_equal_the_design_by_design_readout(freqs):
    rng = np.random.default_rng(7)
    wave, elec = _wave(), ElectronicsSpec()
    n_d = SPECTRUM_CHUNK + 6  # two chunks
    coils = [Coil(particle=13, turns=400 + 100 * (k % 5), length=(7 + k % 3) * 1e-3)
             for k in range(n_d)]
    res = rng.uniform(30.0, 120.0, n_d)
    villari, approach, ind_w = _responses(freqs, n_d, rng)
    ind = ind_w[:, 0].real
    rows = dynamic_design_rows(coils, res, ind, freqs, villari, approach, ind_w, wave, elec)
    assert len(rows) == n_d
    for k in range(0, n_d, 7):
        peak_e, peak_v = _reference(coils[k], res[k], ind[k], freqs, villari[k],
                                    approach[k], ind_w[k], wave, elec)
        assert rows[k]["peak_emf_V"] == pytest.approx(peak_e, rel=1e-12)
        assert rows[k]["peak_voltage_V"] == pytest.approx(peak_v, rel=1e-12)
        assert rows[k]["snr"] == rows[k]["peak_voltage_V"] / rows[k]["noise_rms_V"]
        assert rows[k]["sensitivity_villari_Wb_per_N"] == float(np.sum(villari[k, 0].real))
    # a design's row does not depend on the designs evaluated with it
    alone = dynamic_design_rows(coils[3:4], res[3:4], ind[3:4], freqs, villari[3:4],
                                approach[3:4], ind_w[3:4], wave, elec)[0]
    assert alone["peak_voltage_V"] == pytest.approx(rows[3]["peak_voltage_V"], rel=1e-13)


def test_few_column_basis_above_the_last_frequency_is_exact():
    """Designs whose sensitivities at f_n span 2 of 2 n_c = 16 columns: the batch reads them
    through a 2-column basis (_top_basis) and still equals the design-by-design read-out; on
    two threads the rows are the same bits."""
    rng = np.random.default_rng(11)
    freqs = np.array([0.0, 10.0, 300.0, 3e3, 1e4, 3e4, 1e5, 2e5])
    wave, elec = _wave(n_c=8), ElectronicsSpec()
    n_d = SPECTRUM_CHUNK + 9
    coils = [Coil(particle=13, turns=400 + 100 * (k % 5)) for k in range(n_d)]
    res = rng.uniform(30.0, 120.0, n_d)
    # two contact profiles per mechanism, mixed by the same design-dependent lags
    base_s = rng.uniform(-2e-8, 2e-8, (2, 8))
    base_d = rng.uniform(-3e-2, 1e-2, (2, 8))
    lag = 1.0 / (1.0 + 1j * freqs[None, :, None] / rng.uniform(2e4, 8e4, (n_d, 1, 2)))
    mix = rng.uniform(0.5, 2.0, (n_d, 1, 2)) * lag  # (n_d, n_f, 2)
    mix[:, 0] = mix[:, 0].real
    villari = mix @ base_s
    approach = mix @ base_d
    ind_w = rng.uniform(5e-3, 3e-2, (n_d, 1)) * (0.8 + 0.2 * lag[..., 0])
    ind_w[:, 0] = ind_w[:, 0].real
    ind = ind_w[:, 0].real
    sp = metrics._chain_spectra(wave, freqs)
    basis = metrics._top_basis(sp, np.concatenate([villari[:, -1], approach[:, -1]], axis=1))
    assert basis.weights.shape == (16, 2)
    rows = dynamic_design_rows(coils, res, ind, freqs, villari, approach, ind_w, wave, elec)
    for k in range(0, n_d, 5):
        peak_e, peak_v = _reference(coils[k], res[k], ind[k], freqs, villari[k],
                                    approach[k], ind_w[k], wave, elec)
        assert rows[k]["peak_emf_V"] == pytest.approx(peak_e, rel=1e-12)
        assert rows[k]["peak_voltage_V"] == pytest.approx(peak_v, rel=1e-12)
    threaded = dynamic_design_rows(coils, res, ind, freqs, villari, approach, ind_w, wave,
                                   elec, threads=2)
    assert threaded == rows


def test_coil_transfer_functions_are_the_circuits_own():
    elec = ElectronicsSpec()
    f = np.geomspace(1.0, 1e7, 50)
    circuits = [readout(Coil(particle=13, turns=n), 50.0 + n / 10, 1e-2, elec)
                for n in (300, 700, 1100)]
    z = np.array([c.resistance + 2j * np.pi * f * c.inductance * (1 - 0.1j) for c in circuits])
    c_w = [c.winding_capacitance for c in circuits]
    assert len(set(c_w)) == 3
    h = coil_transfer_functions(circuits[0], c_w, f, z)
    for k, c in enumerate(circuits):
        np.testing.assert_allclose(h[k], coil_transfer_function(c, f, z[k]), rtol=1e-14)
    with pytest.raises(InputError, match="shape"):
        coil_transfer_functions(circuits[0], c_w, f, z[:2])


def test_harmonic_linkage_is_each_frequency_table_read_alone():
    rng = np.random.default_rng(3)
    r, z = np.linspace(8e-3, 12e-3, 41), np.linspace(-6e-3, 6e-3, 121)
    cum = rng.standard_normal((3, 4, r.size, z.size)) + 1j * rng.standard_normal(
        (3, 4, r.size, z.size))
    tables = HarmonicTables(np.array([0.0, 1e3, 1e4]), r, z, cum)
    n = 150  # more than one block
    r0 = rng.uniform(8e-3, 10e-3, n)
    r1 = r0 + rng.uniform(1e-4, 1.9e-3, n)
    z0 = rng.uniform(-6e-3, 0.0, n)
    z1 = z0 + rng.uniform(1e-3, 5.9e-3, n)
    turns = rng.integers(100, 1200, n).astype(float)
    link = tables.linkage(turns, r0, r1, z0, z1)
    per_area = turns / ((r1 - r0) * (z1 - z0))
    for k, c in enumerate(cum):
        expected = per_area[:, None] * rect_integral(LinkageTable(r, z, c), r0, r1, z0, z1)
        assert np.array_equal(link[:, k], expected)
    # the per-node layout is rebuilt after pickling, not shipped
    copy = pickle.loads(pickle.dumps(tables))
    assert "by_node" not in copy.__dict__
    assert np.array_equal(copy.linkage(turns, r0, r1, z0, z1), link)


TINY = (ROOT / "tests" / "data" / "tiny-mss.toml").read_text().replace(
    "[[sensor]]", "[electronics]\nsample_rate_hz = 5e6\n[[sensor]]")
#: Coarse skin mesh (as tests/magnetics/test_eddy_study.py): the path, not the numbers.
EDDY = "[field]\neddy_currents = true\nskin_size_m = 3e-4\n"
def _design_rows(tmp_path: Path, study_text: str, sweep_text: str, name: str) -> list[dict]:
    study, sweep, out = tmp_path / f"{name}.toml", tmp_path / f"{name}-sweep.toml", \
        tmp_path / name
    study.write_text(study_text)
    sweep.write_text(sweep_text)
    assert main(["design", str(study), "--sweep", str(sweep), "--out", str(out), "-q"]) == 0
    with (out / "designs.csv").open() as fh:
        return list(csv.DictReader(fh))


@pytest.mark.slow  # 48 s; the default suite keeps the API's eddy design = run test
def test_design_cli_with_eddy_currents_on_the_tiny_study(tmp_path, monkeypatch):
    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp_path / "cache"))
    eddy = _design_rows(tmp_path, TINY + EDDY, TINY_COIL, "eddy")
    static = _design_rows(tmp_path, TINY, TINY_COIL, "static")
    assert [r["status"] for r in eddy] == ["ok"] * 4
    for e, s in zip(eddy, static, strict=True):
        # the eddy currents in the beads screen the coil: a smaller EMF than magnetostatic
        assert 0.0 < float(e["peak_emf_V"]) < float(s["peak_emf_V"])
        assert 0.0 < float(e["peak_voltage_V"])
        assert e["resistance_ohm"] == s["resistance_ohm"]


@pytest.mark.slow
def test_design_cli_sweep_coil_on_the_main_study_with_eddy_currents(tmp_path):
    """studies/sweep-coil.toml (400 designs) on the main study with eddy currents."""
    study = (ROOT / "studies" / "paper-mss.toml").read_text()
    assert "eddy_currents = true" in study  # the main study's default
    rows = _design_rows(tmp_path, study, (ROOT / "studies" / "sweep-coil.toml").read_text(),
                        "paper-eddy")
    ok = [r for r in rows if r["status"] == "ok"]
    assert len(rows) == 400 and len(ok) > 0
    assert all(float(r["peak_voltage_V"]) > 0 and float(r["snr"]) > 0 for r in ok)

"""The hostile inputs of issue 24, each at the command line: one message naming the key or
file, exit 2, no traceback, within seconds."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
from tests.hostile.conftest import assert_input_error, run_cli

from msens.cli import main

PAPER = Path(__file__).parents[2] / "studies" / "paper-mss.toml"


@pytest.mark.parametrize(("change", "fragments"), [
    # values that used to end in a traceback
    (("bead_diameter_m", "bead_diameter_m = 1e-300"), ["'chain.bead_diameter_m'", ">= 0.0001"]),
    (("youngs_modulus_pa", "youngs_modulus_pa = 1e-300"), ["'chain.youngs_modulus_pa'"]),
    # values that used to hang
    (("youngs_modulus_pa", "youngs_modulus_pa = 1e20"), ["'chain.youngs_modulus_pa'", "1.5e+12"]),
    (("youngs_modulus_pa", "youngs_modulus_pa = 1e308"), ["'chain.youngs_modulus_pa'"]),
    (("gamma_contact_kg_per_s = 4.7", "gamma_contact_kg_per_s = 1e12"),
     ["'chain.gamma_contact_kg_per_s'", "dashpot"]),
    (("gamma_contact_kg_per_s = 4.7", "gamma_contact_kg_per_s = 1e6"),
     ["'chain.gamma_contact_kg_per_s'"]),
    (("bead_mass_kg", "bead_mass_kg = 1e-12"), ["'chain.bead_mass_kg'", "density"]),
    (("beads = 10", "beads = 10000"), ["'chain.beads'", "<= 1000"]),
    (("sample_rate_hz = 5e6", "sample_rate_hz = 5e6\ndt_s = 1e-12"), ["'simulation.dt_s'"]),
    (("sample_rate_hz = 5e6", "sample_rate_hz = 1e10"), ["'simulation.sample_rate_hz'"]),
])
def test_chain_values_refused_by_name(tiny, tmp_path, capsys, change, fragments):
    old, new = change
    if old in ("bead_diameter_m", "youngs_modulus_pa", "bead_mass_kg"):
        change = ("damping = ", f"{new}\ndamping = ")
    path = tiny(change)
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, *fragments)


@pytest.mark.parametrize(("extra", "fragments"), [
    ("[[precompression]]\ncontacts = [2, 5]\nforce_N = 1e308\n", ["'precompression[1].force_N'"]),
    ("[[precompression]]\ncontacts = [2, 5]\nforce_N = 2000\n",
     ["'precompression[1].force_N'", "GPa"]),
    ("[electronics]\ninput_resistance_ohm = 1e-300\n", ["'electronics.input_resistance_ohm'"]),
])
def test_loads_and_electronics_refused_by_name(tiny, tmp_path, capsys, extra, fragments):
    path = tiny(extra=extra)
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, *fragments)


def test_rod_on_the_wall(tiny, tmp_path, capsys):
    path = tiny(("[striker]", "[[chain.insert]]\nparticle = 11\n[striker]"))
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, "'insert'", "wall")


def test_memory_budget_names_keys_and_estimate(tiny, tmp_path, capsys):
    """t_end_s = 1 s at 5 MHz is within each key's range; together they are 5e6 samples."""
    path = tiny(("t_end_s = 3.0e-4", "t_end_s = 1.0"))
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, "'simulation.t_end_s'", "GiB", "budget")


def test_too_short_run_is_not_fitted(tiny, tmp_path, capsys):
    """t_end_s = 25 us: the wave never comes back from the wall; no features of round-off
    (refused before the run since issue 38: the record cannot hold the reflection)."""
    path = tiny(("t_end_s = 3.0e-4", "t_end_s = 2.5e-5"))
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, "holds no reflected pulse", "'simulation.t_end_s'")
    assert not (tmp_path / "o" / "summary.json").exists()


def test_two_sensors_on_one_particle(tiny, tmp_path, capsys):
    path = tiny(("particle = 8", "particle = 4"))
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, "'sensor'", "one sensor per particle")


def test_coil_far_from_its_particle(tiny, tmp_path, capsys):
    path = tiny(extra='[[sensor]]\nkind = "mss"\nparticle = 6\n[sensor.coil]\n'
                      "axial_offset_m = 1.0\n")
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, "'sensor[3].coil.axial_offset_m'", "half a bead")


def test_zero_reference_values(tmp_path, capsys):
    text = PAPER.read_text().replace("tof_us = 287.3", "tof_us = 0", 1)
    path = tmp_path / "p.toml"
    path.write_text(text)
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, "'reference.row[1].tof_us'", "> 0")


def test_deeply_nested_toml(tmp_path, capsys):
    path = tmp_path / "n.toml"
    path.write_text('schema = "msens.study/1"\nx = ' + "[" * 600 + "]" * 600 + "\n")
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o")], capsys, seconds=5)
    assert_input_error(code, err, "n.toml", "nested too deeply")


def test_bom_in_toml_is_accepted(tiny, tmp_path, capsys):
    path = tiny()
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=20)
    assert code == 0, err


def test_synth_seed_checked_before_work(tiny, tmp_path, capsys):
    code, err = run_cli(["synth", str(tiny()), "--out", str(tmp_path / "w.csv"), "--seed",
                         "-1"], capsys, seconds=3)
    assert_input_error(code, err, "--seed")


def test_sweep_num_huge(tmp_path, capsys):
    sweep = tmp_path / "s.toml"
    sweep.write_text('schema = "msens.sweep/1"\nname = "big"\nsensor = 6\n[coil]\n'
                     "turns = { start = 400, stop = 1200, num = 1000000000 }\n")
    study = Path(__file__).parents[1] / "data" / "tiny-mss.toml"
    code, err = run_cli(["design", str(study), "--sweep", str(sweep), "--out",
                         str(tmp_path / "o")], capsys, seconds=10)
    assert_input_error(code, err, "'coil.turns'", "num")


def test_design_out_is_a_file(tmp_path, capsys):
    mine = tmp_path / "mine.txt"
    mine.write_text("mine")
    study = Path(__file__).parents[1] / "data" / "tiny-mss.toml"
    sweep = Path(__file__).parents[2] / "studies" / "sweep-coil.toml"
    code, err = run_cli(["design", str(study), "--sweep", str(sweep), "--out", str(mine)],
                        capsys, seconds=10)
    assert_input_error(code, err, "mine.txt")
    assert mine.read_text() == "mine"


def test_npz_member_not_an_array(tmp_path, capsys):
    path = tmp_path / "bad.npz"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("time_s.npy", b"not an npy file")
        z.writestr("bead@13.npy", b"\x93NUMPY garbage")
    code, err = run_cli(["check-waveform", str(path)], capsys, seconds=5)
    assert_input_error(code, err, "bad.npz")


def test_corrupt_tdms_message_is_short(tmp_path, capsys):
    path = tmp_path / "bad.tdms"
    path.write_bytes(b"TDSm" + np.random.default_rng(0).bytes(600_000))
    code, err = run_cli(["check-waveform", str(path)], capsys, seconds=5)
    assert_input_error(code, err, "bad.tdms")
    assert len(err) < 1000


def test_internal_error_is_reported_as_a_bug(monkeypatch, capsys):
    """A bug is exit 1 with one line saying so (no traceback unless asked for)."""
    import msens.cli as cli

    def broken(args):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setitem(cli._COMMANDS, "verify", broken)
    monkeypatch.delenv(cli.DEBUG_ENV, raising=False)
    assert main(["verify"]) == 1
    err = capsys.readouterr().err
    assert "internal error (ZeroDivisionError" in err and "bug in msens" in err
    assert "Traceback" not in err
    assert main(["--debug", "verify"]) == 1
    assert "Traceback" in capsys.readouterr().err


def test_overdamped_chain_faster_than_sound_is_refused(tmp_path, capsys):
    """gamma_contact = 2000 kg/s passes the dashpot bound but makes the dashpots carry the
    force: the modelled wave would outrun sound in steel (it reported 6,000 m/s)."""
    from tests.hostile.conftest import TWENTY

    path = tmp_path / "s.toml"
    path.write_text(TWENTY.replace("gamma_contact_kg_per_s = 4.7",
                                   "gamma_contact_kg_per_s = 2000"))
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=20)
    assert_input_error(code, err, "faster than sound", "'chain.gamma_contact_kg_per_s'")


@pytest.mark.parametrize(("t_end", "fragment"), [("1e-41", ">= 1e-06"),
                                                  ("2e-6", "fewer than 100 samples")])
def test_run_too_short_for_any_sample(tiny, tmp_path, capsys, t_end, fragment):
    """Found by the fuzz campaign: t_end_s = 1e-41 s left one output sample."""
    path = tiny(("t_end_s = 3.0e-4", f"t_end_s = {t_end}"))
    code, err = run_cli(["run", str(path), "--out", str(tmp_path / "o"), "--no-figures"],
                        capsys, seconds=10)
    assert_input_error(code, err, "'simulation.t_end_s'", fragment)

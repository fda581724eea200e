"""Field solver against exact solutions (msens.field.verify): the `msens verify` rows."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from msens.field import verify
from msens.field.analytic import (
    coil_inductance_filaments,
    loop_mutual_inductance,
    rectangle_gmd,
    ring_magnet_bz,
    thick_solenoid_bz,
    thin_solenoid_bz,
)
from msens.params.units import MU0


@pytest.mark.parametrize("check", verify.CHECKS, ids=lambda c: c.__name__)
def test_check_passes(check):
    rows = check()
    assert rows
    for row in rows:
        assert row.passed, row
        assert np.isfinite(row.computed) and np.isfinite(row.reference)


def test_msens_verify_runs_without_magpylib():
    """``msens verify`` on a plain install, where magpylib (a test extra) is absent: a fresh
    interpreter (so that module-level imports count too) in which ``import magpylib`` raises
    ImportError (a None entry in sys.modules)."""
    code = ("import sys; sys.modules['magpylib'] = None\n"
            "from msens.cli import main\n"
            "sys.exit(main(['verify']))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "ring magnet: on-axis Bz" in proc.stdout and "FAIL" not in proc.stdout


def test_format_table_lists_every_row():
    rows = [verify.Row("a check", 1.0, 1.001, "T", 1e-3, 3e-3, True),
            verify.Row("another", 2.0, 1.0, "N", 1.0, 2e-2, False)]
    table = verify.format_table(rows)
    lines = table.splitlines()
    assert len(lines) == 4
    assert "PASS" in lines[2] and "FAIL" in lines[3] and "a check" in lines[2]


# --- the references themselves -------------------------------------------------------------


def test_thick_solenoid_formula_tends_to_the_thin_one():
    z = np.linspace(-0.05, 0.05, 11)
    t = 1e-6
    thick = thick_solenoid_bz(z, 0.01 - t / 2, 0.01 + t / 2, 0.04, 1.0 / t)
    np.testing.assert_allclose(thick, thin_solenoid_bz(z, 0.01, 0.04, 1.0, 1.0), rtol=1e-8)


@pytest.mark.parametrize("r_in, r_out, length", [(0.005, 0.015, 0.01), (1e-3, 4e-3, 0.03)])
def test_ring_magnet_closed_form_equals_magpylib(r_in, r_out, length):
    """On axis, inside the bore, at the faces and far out (measured: 5e-16 and 3e-15 of
    the peak)."""
    import magpylib as magpy

    z = np.concatenate([np.linspace(-3.0, 3.0, 25) * length, [0.5 * length, -0.5 * length]])
    obs = np.c_[np.zeros_like(z), np.zeros_like(z), z]
    b_r = 1.2
    outer = magpy.magnet.Cylinder(polarization=(0, 0, b_r), dimension=(2 * r_out, length))
    inner = magpy.magnet.Cylinder(polarization=(0, 0, b_r), dimension=(2 * r_in, length))
    ref = outer.getB(obs)[:, 2] - inner.getB(obs)[:, 2]
    exact = ring_magnet_bz(z, r_in, r_out, length, b_r)
    np.testing.assert_allclose(exact, ref, rtol=0.0, atol=1e-12 * np.max(np.abs(ref)))


def test_long_solenoid_centre_field_is_mu0_n_i():
    assert thin_solenoid_bz(0.0, 0.01, 100.0, 1000.0, 2.0) == pytest.approx(
        MU0 * 1000 * 2.0, rel=1e-7)


def test_mutual_inductance_far_field_is_dipolar():
    a, b, d = 0.01, 0.02, 1.0
    dipole = MU0 * np.pi * a**2 * b**2 / (2 * d**3)
    assert loop_mutual_inductance(a, b, d) == pytest.approx(dipole, rel=1e-3)


def test_square_gmd_is_maxwells_0_447():
    assert rectangle_gmd(1.0, 1.0) == pytest.approx(0.44705, rel=1e-4)


def test_filament_sum_converges_at_second_order():
    args = (7.95e-3, 11.58e-3, 7e-3, 1100)
    l8, l16, l32 = (coil_inductance_filaments(*args, n, n) for n in (8, 16, 32))
    order = np.log2((l8 - l16) / (l16 - l32))
    assert 1.6 < order < 2.4


# --- slow studies ---------------------------------------------------------------------------


@pytest.mark.slow
def test_convergence_order_is_two_over_four_refinements():
    h, err, order = verify.convergence_study(levels=5)
    assert np.all(np.diff(err) < 0)
    assert np.all(order[1:] > 1.8), (h, err, order)


@pytest.mark.slow
def test_truncation_error_falls_as_the_box_grows():
    errs = [verify.check_truncation(r)[0].rel_error for r in (0.1, 0.2, 0.4)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-4

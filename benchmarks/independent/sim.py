"""The independent simulator: chain, coil flux, read-out circuit, rig.

Chain (what msens models, implemented here from the physics, not from msens's code):
particles 0..n-1 (0 the striker, n - 1 on the wall) on the x axis pointing down to the wall;
contact k < n - 1 between particles k and k + 1, contact n - 1 between the last and the wall.
Approach d_k = u_k - u_{k+1} (d_{n-1} = u_{n-1}) from the displacements u, negative when open.
While d_k > 0 the contact pushes with F_k = A_k d_k^(3/2) + a dashpot:
"linear-loading" gamma [d'_k]_+ (the dashpot resists compression only), or Hertz-Kuwabara-Kono
gamma d_k^(1/2) d'_k. A_k = (4/3) E* sqrt(R*) from the two bodies' E, nu and radii (a flat
for the wall). Each particle feels m g, the static forces (the magnets' pull and any added
compression) and a tube drag -c v. The static equilibrium (striker touching particle 1 with
zero force) is solved with :func:`scipy.optimize.root`; the impact with
:func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-10), its dense output read at the DAQ's
sampling instants.

Coil: the flux change Lambda(t) = sum_c [dLambda/dF_c (F_c - F_c0) + dLambda/ddelta_c
(d~_c - d~_c0)], d~ the contact maps' equivalent approaches (linear interpolation of the
tables), so the EMF is -dLambda/dt. Read-out: EMF - R - L into the winding, cable and DAQ
capacitances in parallel with the DAQ's input resistance, written with the state
q = L i + Lambda so that the flux itself is the input (no numerical derivative):

    dq/dt = -R (q - Lambda) / L - v,    C dv/dt = (q - Lambda) / L - v / R_in,

integrated by :func:`scipy.signal.lsim` (first-order hold of the input); optional extra
stages (a first-order DAQ low-pass, a sensor resonance) are states of the same system.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from benchmarks.independent.field import DELTA_GRID, CoilTables, FieldTables
from scipy import optimize, signal
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator

G = 9.80665


def hertz_prefactor(e1: float, nu1: float, r1: float, e2: float, nu2: float,
                    r2: float | None) -> float:
    """A of F = A d^(3/2) between two elastic spheres (r2 None: a flat), N/m^1.5."""
    e_star = 1.0 / ((1 - nu1**2) / e1 + (1 - nu2**2) / e2)
    r_star = r1 if r2 is None else r1 * r2 / (r1 + r2)
    return 4.0 / 3.0 * e_star * np.sqrt(r_star)


@dataclass(frozen=True)
class Chain:
    """The chain the simulator integrates (SI units).

    Attributes
    ----------
    mass : ndarray, shape (n,)
    stiffness : ndarray, shape (n,)
        Hertz prefactors A_k of the contacts (last: the wall).
    damping : ndarray, shape (n,)
        Dashpot coefficient of each contact (kg/s linear-loading, kg/(s m^0.5) HKK).
    law : {"linear-loading", "hkk"}
    static : ndarray, shape (n,)
        Static forces on the particles besides gravity, N, + toward the wall.
    drag : ndarray, shape (n,)
        Tube drag coefficient, N s/m.
    gap : ndarray, shape (n,)
        Initial gap of each contact, m (0: closed under its static load; > 0: open by that
        much, e.g. a second striker above the first).
    velocity : ndarray, shape (n,)
        Initial velocities, m/s (the striker's impact speed).
    """

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    law: str
    static: np.ndarray
    drag: np.ndarray
    gap: np.ndarray
    velocity: np.ndarray

    @property
    def n(self) -> int:
        return int(self.mass.size)


def contact_forces(chain: Chain, u: np.ndarray, v: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(approaches d, their rates, total contact forces F), each shape (..., n)."""
    d = np.empty_like(u)
    dd = np.empty_like(v)
    d[..., :-1] = u[..., :-1] - u[..., 1:]
    d[..., -1] = u[..., -1]
    dd[..., :-1] = v[..., :-1] - v[..., 1:]
    dd[..., -1] = v[..., -1]
    closed = d > 0
    dp = np.where(closed, d, 0.0)
    f = chain.stiffness * dp**1.5
    if chain.law == "linear-loading":
        f = f + np.where(closed, chain.damping * np.maximum(dd, 0.0), 0.0)
    elif chain.law == "hkk":
        f = f + np.where(closed, chain.damping * np.sqrt(dp) * dd, 0.0)
    else:
        raise ValueError(f"unknown damping law {chain.law!r}")
    return d, dd, f


def equilibrium(chain: Chain) -> np.ndarray:
    """Static displacements u0 (m): particles 1..n-1 at rest on the wall under gravity and
    the static forces, the striker touching (or ``gap`` above) its neighbour, found by
    :func:`scipy.optimize.root` on the force balance in the approaches."""
    n = chain.n
    load = chain.mass * G + chain.static
    scale = 1e-8  # m: the static approaches are of this order

    def residual(x: np.ndarray) -> np.ndarray:
        d = x * scale
        f = chain.stiffness[1:] * np.sign(d) * np.abs(d) ** 1.5
        above = np.concatenate([[0.0], f[:-1]])
        return above - f + load[1:]

    guess = np.full(n - 1, 1.0)
    sol = optimize.root(residual, guess, method="hybr", tol=1e-14)
    if not sol.success or np.max(np.abs(residual(sol.x))) > 1e-10:
        sol = optimize.root(residual, sol.x, method="lm", tol=1e-15)
    d = sol.x * scale
    if np.max(np.abs(residual(sol.x))) > 1e-9 or np.any(d <= 0):
        raise RuntimeError(f"no static equilibrium: {sol.message}")
    d_all = np.concatenate([[-chain.gap[0]], d])
    return np.cumsum(d_all[::-1])[::-1]


@dataclass(frozen=True)
class History:
    """Chain history at the requested times: approaches and total forces, shape (nt, n);
    velocities (nt, n); the static state (u0, F0, d0)."""

    t: np.ndarray
    approach: np.ndarray
    force: np.ndarray
    velocity: np.ndarray
    d0: np.ndarray
    f0: np.ndarray


def simulate(chain: Chain, t: np.ndarray, rtol: float = 1e-10) -> History:
    """The impact at t = 0 (striker at ``chain.velocity``), read at times ``t`` (s; t < 0:
    the chain at rest)."""
    n = chain.n
    u0 = equilibrium(chain)
    load = chain.mass * G + chain.static

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        u, v = y[:n], y[n:]
        _, _, f = contact_forces(chain, u, v)
        above = np.concatenate([[0.0], f[:-1]])
        return np.concatenate([v, (above - f + load - chain.drag * v) / chain.mass])

    y0 = np.concatenate([u0, chain.velocity])
    t_end = float(np.max(t))
    atol = np.concatenate([np.full(n, 1e-16), np.full(n, 1e-11)])
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=atol,
                    dense_output=True, max_step=0.5e-6)
    if not sol.success:
        raise RuntimeError(sol.message)
    after = t >= 0
    y = np.repeat(y0[None, :], t.size, axis=0)
    y[:, n:] = 0.0  # before the impact: at rest (striker still above)
    y[after] = sol.sol(t[after]).T
    d, _, f = contact_forces(chain, y[:, :n], y[:, n:])
    d0, _, f0 = contact_forces(chain, u0, np.zeros(n))
    return History(t=t, approach=d, force=f, velocity=y[:, n:], d0=d0, f0=f0)


# ------------------------------------------------------------------ coil and read-out

@dataclass(frozen=True)
class CoilState:
    """One coil as the simulator reads it: sensitivities over the chain's contacts (zero for
    contacts the tables do not hold), its contact maps, its circuit."""

    villari: np.ndarray
    approach: np.ndarray
    mapped: np.ndarray  # 0-based chain contact index of each map
    delta_eq: np.ndarray
    resistance: float
    inductance: float
    winding_capacitance: float


def coil_state(c: CoilTables, *, offset: float = 0.0, remanence: float = 1.0,
               shift: int = 0, n_contacts: int = 30) -> CoilState:
    """The coil's sensitivities moved by ``offset`` (m) or at magnet ``remanence`` (PCHIP
    in the tables), on a chain whose contact c (1-based in the tables) is chain contact
    c - 1 + ``shift`` (0-based)."""
    vil, app = np.array(c.villari), np.array(c.approach)
    if offset != 0.0:
        vil = vil + PchipInterpolator(c.offsets, c.villari_by_offset, axis=0)(offset) \
            - PchipInterpolator(c.offsets, c.villari_by_offset, axis=0)(0.0)
        app = app + PchipInterpolator(c.offsets, c.approach_by_offset, axis=0)(offset) \
            - PchipInterpolator(c.offsets, c.approach_by_offset, axis=0)(0.0)
    if remanence != 1.0:
        vil = PchipInterpolator(c.remanence, c.villari_by_remanence, axis=0)(remanence)
        app = PchipInterpolator(c.remanence, c.approach_by_remanence, axis=0)(remanence)
    v_full = np.zeros(n_contacts)
    a_full = np.zeros(n_contacts)
    v_full[shift:shift + vil.size] = vil
    a_full[shift:shift + app.size] = app
    return CoilState(villari=v_full, approach=a_full, mapped=c.mapped - 1 + shift,
                     delta_eq=c.delta_eq, resistance=c.resistance, inductance=c.inductance,
                     winding_capacitance=c.winding_capacitance)


def equivalent(coil: CoilState, d: np.ndarray) -> np.ndarray:
    """Approaches (nt, n) read through the coil's contact maps (linear interpolation of the
    tables, linear extrapolation beyond them)."""
    out = np.array(d, dtype=float)
    x = DELTA_GRID
    for k, table in zip(coil.mapped, coil.delta_eq, strict=True):
        col = d[:, k]
        y = np.interp(col, x, table)
        lo, hi = col < x[0], col > x[-1]
        s_lo = (table[1] - table[0]) / (x[1] - x[0])
        s_hi = (table[-1] - table[-2]) / (x[-1] - x[-2])
        y = np.where(lo, table[0] + s_lo * (col - x[0]), y)
        out[:, k] = np.where(hi, table[-1] + s_hi * (col - x[-1]), y)
    return out


def flux(coil: CoilState, h: History) -> np.ndarray:
    """Change of the coil's flux linkage from the static state, Wb, shape (nt,)."""
    eq = equivalent(coil, h.approach)
    eq0 = equivalent(coil, h.d0[None, :])[0]
    return (h.force - h.f0) @ coil.villari + (eq - eq0) @ coil.approach


@dataclass(frozen=True)
class Electronics:
    """Cable and DAQ (F, Ohm), and extra linear stages after the circuit."""

    cable_capacitance: float = 100e-12
    input_resistance: float = 1e6
    input_capacitance: float = 20e-12
    lowpass_tau: float = 0.0  # s, first-order DAQ low-pass (0: none)
    resonance_hz: float = 0.0  # a sensor/amplifier resonance (0: none)
    resonance_q: float = 5.0


def circuit(coil: CoilState, e: Electronics) -> signal.StateSpace:
    """The read-out as a state space with the flux (Wb) as input and the DAQ voltage (V) as
    output (see the module docstring); extra stages in series."""
    r, l_ = coil.resistance, coil.inductance
    c = coil.winding_capacitance + e.cable_capacitance + e.input_capacitance
    a = [[-r / l_, -1.0], [1.0 / (l_ * c), -1.0 / (e.input_resistance * c)]]
    b = [[r / l_], [-1.0 / (l_ * c)]]
    sys = (np.array(a), np.array(b), np.array([[0.0, 1.0]]), np.zeros((1, 1)))
    if e.lowpass_tau > 0:
        sys = _series(sys, (np.array([[-1.0 / e.lowpass_tau]]),
                            np.array([[1.0 / e.lowpass_tau]]), np.array([[1.0]]),
                            np.zeros((1, 1))))
    if e.resonance_hz > 0:
        w = 2 * np.pi * e.resonance_hz
        # x1' = x2, x2' = -w^2 x1 - (w/Q) x2 + w^2 u: unit DC gain, a peak of ~Q at w
        sys = _series(sys, (np.array([[0.0, 1.0], [-w * w, -w / e.resonance_q]]),
                            np.array([[0.0], [w * w]]), np.array([[1.0, 0.0]]),
                            np.zeros((1, 1))))
    return signal.StateSpace(*sys)


def _series(s1, s2):
    """State space of s2 after s1 (single input and output)."""
    a1, b1, c1, d1 = s1
    a2, b2, c2, d2 = s2
    n1, n2 = a1.shape[0], a2.shape[0]
    a = np.block([[a1, np.zeros((n1, n2))], [b2 @ c1, a2]])
    b = np.vstack([b1, b2 @ d1])
    c = np.hstack([d2 @ c1, c2])
    return a, b, c, d2 @ d1


def daq_voltage(coil: CoilState, e: Electronics, h: History) -> np.ndarray:
    """The DAQ voltage at the history's (uniform) times, V: the circuit driven by the
    flux from rest before the impact."""
    lam = flux(coil, h)
    _, y, _ = signal.lsim(circuit(coil, e), lam, h.t - h.t[0], interp=True)
    return np.asarray(y)


# ------------------------------------------------------------------ the study's chain

@dataclass(frozen=True)
class World:
    """Everything one shot of the simulated rig depends on (the undisturbed main study by
    default: :func:`nominal`).

    Attributes
    ----------
    chain : Chain
    offsets : tuple of float
        Axial offset of each coil, m.
    remanence : float
        Magnets' remanence factor.
    electronics : Electronics
    shift : int
        Chain contact index of table contact 1 (1 when a particle is added above the
        striker).
    saturation : float
        Amplifier saturation level as a fraction of each shot's peak (0: linear): v ->
        level tanh(v / level).
    """

    chain: Chain
    offsets: tuple[float, ...] = (0.0, 0.0)
    remanence: float = 1.0
    electronics: Electronics = field(default_factory=Electronics)
    shift: int = 0
    saturation: float = 0.0


@dataclass(frozen=True)
class StudyNumbers:
    """The numbers of the main study the simulator is built from (read from the study file
    by :func:`msens.config.study.load_study`)."""

    n: int
    mass: float
    radius: float
    youngs: float
    poisson: float
    wall_youngs: float
    wall_poisson: float
    gamma_c: float
    gamma_w: float
    drop_height: float
    sample_rate: float
    t_end: float
    cable: float
    input_resistance: float
    input_capacitance: float
    particles: tuple[int, ...]

    @property
    def velocity(self) -> float:
        return float(np.sqrt(2 * G * self.drop_height))


def study_numbers(study) -> StudyNumbers:
    """The study's chain, striker, sampling and electronics numbers."""
    c = study.chain
    e = study.electronics
    return StudyNumbers(n=c.n_particles, mass=c.bead_mass_kg, radius=0.5 * c.bead_diameter_m,
                        youngs=c.youngs_modulus_pa, poisson=c.poisson_ratio,
                        wall_youngs=c.wall.youngs_modulus_pa,
                        wall_poisson=c.wall.poisson_ratio, gamma_c=c.gamma_contact,
                        gamma_w=c.gamma_wall, drop_height=study.striker.drop_height_m,
                        sample_rate=study.simulation.sample_rate_hz,
                        t_end=study.simulation.t_end_s, cable=e.cable_capacitance_f,
                        input_resistance=e.input_resistance_ohm,
                        input_capacitance=e.input_capacitance_f,
                        particles=tuple(s.particle for s in study.setups[0].sensors))


def nominal(s: StudyNumbers, tables: FieldTables) -> World:
    """The undisturbed main study."""
    n = s.n
    stiff = np.full(n, hertz_prefactor(s.youngs, s.poisson, s.radius, s.youngs, s.poisson,
                                       s.radius))
    stiff[-1] = hertz_prefactor(s.youngs, s.poisson, s.radius, s.wall_youngs, s.wall_poisson,
                                None)
    damping = np.full(n, s.gamma_c)
    damping[-1] = s.gamma_w
    vel = np.zeros(n)
    vel[0] = s.velocity
    chain = Chain(mass=np.full(n, s.mass), stiffness=stiff, damping=damping,
                  law="linear-loading", static=np.array(tables.pull), drag=np.zeros(n),
                  gap=np.zeros(n), velocity=vel)
    return World(chain=chain, electronics=Electronics(cable_capacitance=s.cable,
                                                      input_resistance=s.input_resistance,
                                                      input_capacitance=s.input_capacitance))


def with_remanence(world: World, tables: FieldTables, factor: float) -> World:
    """All magnets' remanence times ``factor``: their pull and the coils' sensitivities."""
    pull = PchipInterpolator(tables.remanence, tables.pull_by_remanence, axis=0)(factor)
    static = world.chain.static - tables.pull + pull
    return replace(world, chain=replace(world.chain, static=static), remanence=factor)


def coil_voltages(world: World, tables: FieldTables, t: np.ndarray,
                  h: History | None = None) -> tuple[np.ndarray, History]:
    """DAQ voltage of each coil at times ``t`` (V, shape (n_coils, nt)) and the history."""
    h = simulate(world.chain, t) if h is None else h
    out = []
    for k, c in enumerate(tables.coils):
        cs = coil_state(c, offset=world.offsets[k], remanence=world.remanence,
                        shift=world.shift, n_contacts=world.chain.n)
        out.append(daq_voltage(cs, world.electronics, h))
    v = np.array(out)
    if world.saturation > 0:
        level = world.saturation * np.max(np.abs(v), axis=1, keepdims=True)
        v = level * np.tanh(v / level)
    return v, h


# ------------------------------------------------------------------ the rig

@dataclass(frozen=True)
class Rig:
    """The acquisition around the simulated sensors (written for this simulator; ranges
    like a lab rig's): amplifier gain log-uniform in ``gain`` (one per channel for all
    shots), DC offset uniform in +- ``offset`` of the channel's peak, trigger delay uniform
    in ``delay`` (s) plus a per-shot jitter uniform in +- ``jitter``, white noise of std
    ``noise`` x the channel's peak, ``pretrigger`` s recorded before the trigger, each shot's
    striker speed nominal x (1 + ``speed_spread`` e), e standard normal."""

    shots: int = 1
    noise: float = 0.01
    gain: tuple[float, float] = (0.5, 2.0)
    offset: float = 0.02
    delay: tuple[float, float] = (20e-6, 60e-6)
    jitter: float = 0.5e-6
    pretrigger: float = 20e-6
    speed_spread: float = 0.01


def record(world: World, tables: FieldTables, s: StudyNumbers, rig: Rig, seed: int):
    """A measured file's content: (time axis s, data (nt, channels), channel names,
    truth dict). Channels ``mss@<particle>[#k]``."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / s.sample_rate
    n_model = round(s.t_end * s.sample_rate) + 1
    n_pre = round(rig.pretrigger / dt)
    delay = float(rng.uniform(*rig.delay))
    n_rec = n_model - int(np.ceil((delay + rig.jitter) / dt)) + n_pre - 1
    tau = (np.arange(n_rec) - n_pre) * dt
    gains = np.exp(rng.uniform(np.log(rig.gain[0]), np.log(rig.gain[1]),
                               len(tables.coils)))
    v_striker = world.chain.velocity[world.shift]
    speeds = (v_striker * (1.0 + rig.speed_spread * rng.standard_normal(rig.shots))
              if rig.shots > 1 else np.array([v_striker]))
    columns, names = [], []
    delays = []
    for k in range(rig.shots):
        shot_delay = delay + float(rng.uniform(-rig.jitter, rig.jitter))
        delays.append(shot_delay)
        vel = np.array(world.chain.velocity)
        vel[:world.shift + 1] = speeds[k]  # the striker (and anything falling with it)
        shot = replace(world, chain=replace(world.chain, velocity=vel))
        # the circuit starts from rest at the impact: simulate from t = 0 and read the
        # record's instants (before the impact: 0). Starting the read-out at the first
        # recorded instant instead (after the impact, with the flux already changing)
        # rang the coil's resonance through the whole record.
        t_sim = np.arange(int(np.ceil((tau[-1] + shot_delay) / dt)) + 2) * dt
        v_sim, _ = coil_voltages(shot, tables, t_sim)
        v = np.array([np.interp(tau + shot_delay, t_sim, x, left=0.0) for x in v_sim])
        for j, c in enumerate(tables.coils):
            sig = gains[j] * v[j]
            peak = float(np.max(np.abs(sig)))
            columns.append(sig + rng.uniform(-rig.offset, rig.offset) * peak
                           + rng.normal(0.0, rig.noise * peak, tau.size))
            names.append(f"mss@{c.particle}" + (f"#{k + 1}" if rig.shots > 1 else ""))
    truth = {"gains": gains.tolist(), "trigger_delays_s": delays,
             "striker_speeds_m_per_s": speeds.tolist()}
    return tau, np.column_stack(columns), names, truth

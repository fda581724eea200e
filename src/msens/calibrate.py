"""Calibration of the chain model against measurements (paper §4.1, §5.1, §5.2).

- :func:`fit_dissipation`: the contact and wall dissipation coefficients gamma_c, gamma_w
  that reproduce measured amplitude ratios at two sensors (paper Eq. 10).
- :func:`voltage_to_force_factor`: sensor sensitivity K = F_num / V_exp over shots (Eq. 11).
- :func:`precompression_from_speed`: the static precompression that makes the
  long-wavelength solitary-wave speed equal a measured speed (paper §4.1, the MsS's 1.8 N).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq, minimize

from msens.errors import require
from msens.mechanics.longwave import soliton_speed_precompressed, soliton_speed_uncompressed
from msens.readout.sensors import SensorKind, observe, read_contacts
from msens.signals.features import pulse_features


@dataclass(frozen=True)
class DissipationFit:
    """Result of :func:`fit_dissipation`.

    Attributes
    ----------
    gamma_c, gamma_w : float
        Fitted contact and wall dissipation coefficients (units of the chain's damping law;
        kg/s for the linear law).
    objective : float
        Eq. 10 at the optimum, dimensionless (norm of the two relative AR errors).
    ar_top_model, ar_bottom_model : float
        Model amplitude ratios at the top and bottom sensors at the optimum.
    tof_top_model, tof_bottom_model : float
        Model times of flight at the optimum, s.
    n_simulations : int
        Chain simulations used (grid + refinement).
    """

    gamma_c: float
    gamma_w: float
    objective: float
    ar_top_model: float
    ar_bottom_model: float
    tof_top_model: float
    tof_bottom_model: float
    n_simulations: int


#: Default start grids for gamma_c and gamma_w, kg/s (paper's gamma_c = 4.8 inside).
GAMMA_C_GRID = tuple(np.linspace(0.0, 12.0, 13))
GAMMA_W_GRID = tuple(np.linspace(0.0, 12.0, 7))


def _default_simulator():
    from msens.chain.integrate import simulate_batch  # lazy: calibrate sits above the chain

    return simulate_batch


def dissipation_objective(ar_top_model: ArrayLike, ar_bottom_model: ArrayLike, ar_top: float,
                          ar_bottom: float) -> np.ndarray:
    """Paper Eq. 10: || [(AR_top,num - AR_top)/AR_top, (AR_bot,num - AR_bot)/AR_bot] ||_2.

    NaN model ratios (no reflection found) give +inf.
    """
    e1 = (np.asarray(ar_top_model, dtype=float) - ar_top) / ar_top
    e2 = (np.asarray(ar_bottom_model, dtype=float) - ar_bottom) / ar_bottom
    y = np.hypot(e1, e2)
    return np.where(np.isfinite(y), y, np.inf)


def fit_dissipation(make_chain: Callable[[float, float], object], sensors: tuple[int, int],
                    ar_top: float, ar_bottom: float, velocity: float, t_out: ArrayLike, *,
                    kind: SensorKind | str = SensorKind.BEAD,
                    gamma_c_grid: ArrayLike = GAMMA_C_GRID,
                    gamma_w_grid: ArrayLike = GAMMA_W_GRID,
                    min_delay: tuple[float, float] = (0.0, 0.0),
                    refine: bool = True, xatol: float = 1e-3, fatol: float = 1e-6,
                    simulator: Callable | None = None) -> DissipationFit:
    """Fit gamma_c, gamma_w >= 0 to measured amplitude ratios (paper Eq. 10).

    A batched grid search (one ``simulate_batch`` call over all grid points) picks the
    start; a bounded Nelder-Mead (``scipy.optimize.minimize``, bounds [0, inf)) refines it.
    Nelder-Mead rather than L-BFGS-B because the AR of a sampled record is only piecewise
    smooth in gamma (the peak sample can jump), which spoils finite-difference gradients.

    Parameters
    ----------
    make_chain : callable (gamma_c, gamma_w) -> Chain
        Builds the chain for given dissipation coefficients.
    sensors : (int, int)
        1-based particle numbers of the top and bottom sensors (paper: 13, 18).
    ar_top, ar_bottom : float
        Measured amplitude ratios (> 0).
    velocity : float
        Striker velocity, m/s.
    t_out : array_like, shape (nt,)
        Uniform output times from impact, s; must contain both reflections.
    kind : SensorKind or str
        Sensor observation operator ("bead", "rod", "mss"); the AR is of the dynamic force.
    gamma_c_grid, gamma_w_grid : array_like
        Grid of the start search (>= 0).
    min_delay : (float, float)
        Earliest reflection after the incident peak at top and bottom sensors, s
        (see :func:`msens.signals.features.pulse_features`).
    refine : bool
        Run the local refinement after the grid.
    xatol, fatol : float
        Nelder-Mead tolerances on gamma (chain units) and on the objective.
    simulator : callable, optional
        ``simulate_batch``-compatible function (chains, velocities, t_out, contacts=...) ->
        result with ``force`` (runs, nt, len(contacts)), the forces of those contacts;
        default :func:`msens.chain.integrate.simulate_batch`. Only the sensors' contacts are
        requested.

    Returns
    -------
    DissipationFit
    """
    require(ar_top > 0 and ar_bottom > 0,
            f"measured amplitude ratios must be > 0, got {ar_top}, {ar_bottom}")
    gc_grid = np.asarray(gamma_c_grid, dtype=float).ravel()
    gw_grid = np.asarray(gamma_w_grid, dtype=float).ravel()
    require(gc_grid.size >= 1 and gw_grid.size >= 1 and gc_grid.min() >= 0
            and gw_grid.min() >= 0, "gamma grids must be non-empty and >= 0")
    t_out = np.asarray(t_out, dtype=float)
    top, bottom = sensors
    kind = SensorKind(kind)
    simulate_batch = simulator or _default_simulator()
    count = [0]
    # Only the sensors' contacts are sampled (less memory and work for big grids).
    n = make_chain(float(gc_grid[0]), float(gw_grid[0])).n_particles
    sel = read_contacts([(kind, top), (kind, bottom)], n)

    def model(gammas: np.ndarray) -> tuple[np.ndarray, ...]:
        """(runs, 2) gammas -> ar_top, ar_bottom, tof_top, tof_bottom, each (runs,)."""
        chains = [make_chain(float(gc), float(gw)) for gc, gw in gammas]
        res = simulate_batch(chains, np.full(len(chains), velocity), t_out, contacts=sel)
        count[0] += len(chains)
        out = []
        for p, delay in zip((top, bottom), min_delay, strict=True):
            sensor = observe(kind, res.force, p, contacts=sel)
            out.append(pulse_features(sensor, t_out, min_delay=delay))
        return out[0].ar, out[1].ar, out[0].tof, out[1].tof

    gc, gw = np.meshgrid(gc_grid, gw_grid, indexing="ij")
    grid = np.column_stack([gc.ravel(), gw.ravel()])
    ar_t, ar_b, _, _ = model(grid)
    y = dissipation_objective(ar_t, ar_b, ar_top, ar_bottom)
    require(bool(np.isfinite(y).any()),
            "no grid point gave a reflected pulse at both sensors: lengthen t_out or "
            "check min_delay")
    best = grid[int(np.argmin(y))]

    if refine:
        def f(x: np.ndarray) -> float:
            x = np.clip(x, 0.0, None)  # Nelder-Mead may step outside before clipping
            a_t, a_b, _, _ = model(x[None, :])
            return float(dissipation_objective(a_t, a_b, ar_top, ar_bottom)[0])

        step = np.array([_spacing(gc_grid), _spacing(gw_grid)])
        simplex = best + np.array([[0.0, 0.0], [step[0], 0.0], [0.0, step[1]]])
        opt = minimize(f, best, method="Nelder-Mead", bounds=[(0.0, None), (0.0, None)],
                       options={"initial_simplex": simplex, "xatol": xatol, "fatol": fatol,
                                "maxfev": 200})
        best = np.clip(opt.x, 0.0, None) if opt.fun <= y.min() else best

    a_t, a_b, tof_t, tof_b = model(best[None, :])
    obj = float(dissipation_objective(a_t, a_b, ar_top, ar_bottom)[0])
    return DissipationFit(gamma_c=float(best[0]), gamma_w=float(best[1]), objective=obj,
                          ar_top_model=float(a_t[0]), ar_bottom_model=float(a_b[0]),
                          tof_top_model=float(tof_t[0]), tof_bottom_model=float(tof_b[0]),
                          n_simulations=count[0])


def _spacing(grid: np.ndarray) -> float:
    """Initial Nelder-Mead step from a grid: its spacing, or 1 for a single point."""
    return float(np.min(np.diff(np.unique(grid)))) if np.unique(grid).size > 1 else 1.0


def voltage_to_force_factor(force_peak_model: float | ArrayLike,
                            voltage_peaks: ArrayLike) -> tuple[float, float]:
    """Sensor conversion factor K_i = F_num / V_i,exp over shots (paper Eq. 11).

    Parameters
    ----------
    force_peak_model : float or array_like, shape (shots,)
        Peak dynamic force of the model at the sensor, N.
    voltage_peaks : array_like, shape (shots,)
        Measured peak of each shot: volts for bead and rod; for the MsS the peak of the
        time-integrated coil voltage, V s (then K is in N/(V s)).

    Returns
    -------
    mean, std : float
        Mean of K_i and its sample standard deviation (ddof = 1; 0 for a single shot), in
        N/V (bead, rod) or N/(V s) (MsS).
    """
    v = np.asarray(voltage_peaks, dtype=float).ravel()
    require(v.size >= 1, "voltage_peaks must hold at least one shot")
    require(bool(np.all(np.isfinite(v)) and np.all(v != 0)),
            "voltage_peaks must be finite and non-zero")
    k = np.asarray(force_peak_model, dtype=float) / v
    return float(k.mean()), float(k.std(ddof=1)) if k.size > 1 else 0.0


def precompression_from_speed(speed: float, F_m: float, diameter: float, E: float, nu: float,
                              rho: float, *,
                              amplitude: Literal["dynamic", "total"] = "dynamic") -> float:
    """Static precompression F0 at which the long-wavelength solitary-wave speed equals
    ``speed`` (inverse of :func:`msens.mechanics.longwave.soliton_speed_precompressed`, by brentq).

    Parameters
    ----------
    speed : float
        Measured solitary-wave speed, m/s.
    F_m : float
        Pulse amplitude, N: the dynamic amplitude an AC-coupled sensor sees
        (``amplitude="dynamic"``, the total peak is then F0 + F_m), or the total peak force
        (``amplitude="total"``, then F0 < F_m).
    diameter, E, nu, rho : float
        Bead diameter (m), Young's modulus (Pa), Poisson's ratio, density (kg/m^3).
    amplitude : {"dynamic", "total"}

    Returns
    -------
    float
        F0, N.

    Raises
    ------
    InputError
        If ``speed`` is outside the speeds reachable with F0 >= 0 (below the uncompressed
        solitary-wave speed, or, for a total amplitude, above the sound speed at F0 = F_m).
    """
    require(F_m > 0 and speed > 0, f"speed and F_m must be > 0, got {speed}, {F_m}")
    require(amplitude in ("dynamic", "total"),
            f"amplitude must be 'dynamic' or 'total', got {amplitude!r}")
    v_min = float(soliton_speed_uncompressed(F_m, diameter, E, nu, rho))
    require(speed > v_min,
            f"speed {speed:.6g} m/s is not above the uncompressed solitary-wave speed "
            f"{v_min:.6g} m/s for F_m = {F_m:.6g} N: no precompression >= 0 fits")

    def v_of(F0: float) -> float:
        total = F_m + F0 if amplitude == "dynamic" else F_m
        return float(soliton_speed_precompressed(total, F0, diameter, E, nu, rho))

    lo = 1e-12 * F_m
    if amplitude == "total":
        hi = F_m
        require(speed <= v_of(hi), f"speed {speed:.6g} m/s exceeds the sound speed "
                f"{v_of(hi):.6g} m/s at F0 = F_m = {F_m:.6g} N")
    else:
        hi = F_m
        while v_of(hi) < speed:  # V grows like F0^(1/6) without bound
            hi *= 4.0
    return float(brentq(lambda F0: v_of(F0) - speed, lo, hi, xtol=1e-14 * hi, rtol=1e-13))


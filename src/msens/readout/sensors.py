"""Observation operators: what a sensor reads from the chain's contact-force histories.

Contact numbering follows the paper (its Eq. 9 and Fig. 3): contact c_i (1-based) is between
particles i and i+1, c_n is between the last particle and the wall; in arrays contact c_i has
index i-1. Particle 1 is the striker. A sensor at particle p therefore touches contacts
c_{p-1} (above) and c_p (below).

Sensors (paper §3 and §4.2):

- bead sensor at p: mean of c_{p-1} and c_p (a piezo plate at the bead's centre reads the
  average of the forces at its two ends; Daraio et al. 2005, the paper's ref. [6]);
- piezo rod at p: the same two contacts (its two end faces);
- four-contact MsS centred at p: mean of c_{p-2} .. c_{p+1} (the paper's c11..c14 for
  p = 13), and its time derivative, the paper's hypothesis V ∝ dF/dt (Eq. 5).

Dynamic, not total, force: all three sensors are AC-coupled (a piezoelectric crystal does
not hold a static charge; a coil sees only changes of flux), so by default they report the
contact force minus its static value. The static value is taken from the first sample
(t = 0, the instant of impact, when the chain below the striker is at rest in static
equilibrium) unless it is given explicitly. ``dynamic=False`` returns the total force.

All functions take ``force`` of shape (..., nt, n) (time, contact) so that they work on
one run (nt, n) and on a batch (runs, nt, n) alike, and return (..., nt).
"""

from __future__ import annotations

import enum
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike

from msens.errors import require


class SensorKind(enum.Enum):
    """Kind of sensor whose reading is a mean of contact forces."""

    BEAD = "bead"
    ROD = "rod"
    MSS = "mss"  # four-contact MsS model


def sensor_contacts(kind: SensorKind, particle: int, n_contacts: int) -> np.ndarray:
    """0-based indices of the contacts a sensor averages.

    Parameters
    ----------
    kind : SensorKind
    particle : int
        1-based particle number the sensor sits on (bead, rod) or is centred on (MsS);
        the striker is particle 1.
    n_contacts : int
        Number of contacts of the chain (= number of particles, the last one is the wall).

    Returns
    -------
    ndarray of int, shape (2,) for bead and rod, (4,) for the MsS

    Raises
    ------
    InputError
        If the sensor's contacts are not all in the chain.
    """
    kind = SensorKind(kind)
    if kind is SensorKind.MSS:
        first, last = particle - 2, particle + 1  # c_{p-2} .. c_{p+1}, 1-based
        allowed = f"3..{n_contacts - 1}"
    else:
        first, last = particle - 1, particle  # c_{p-1}, c_p
        allowed = f"2..{n_contacts}"
    require(isinstance(particle, int | np.integer) and first >= 1 and last <= n_contacts,
            f"sensor particle {particle!r} for kind '{kind.value}' is outside the chain: "
            f"allowed particles are {allowed} for a chain of {n_contacts} particles")
    return np.arange(first - 1, last)


def dynamic_force(force: ArrayLike, static: ArrayLike | None = None) -> np.ndarray:
    """Contact force minus its static value.

    Parameters
    ----------
    force : array_like, shape (..., nt, n)
        Total contact forces, N.
    static : array_like, shape (..., n) or (n,), optional
        Static contact forces, N. Default: the first sample, ``force[..., 0, :]``.

    Returns
    -------
    ndarray, shape (..., nt, n)
        Dynamic contact forces, N.
    """
    force = np.asarray(force, dtype=float)
    require(force.ndim >= 2, f"force must have shape (..., nt, n), got {force.shape}")
    base = force[..., 0, :] if static is None else np.asarray(static, dtype=float)
    return force - base[..., None, :]


def contact_mean(force: ArrayLike, contacts: ArrayLike, *, dynamic: bool = True,
                 static: ArrayLike | None = None) -> np.ndarray:
    """Mean of some contact forces over time.

    Parameters
    ----------
    force : array_like, shape (..., nt, n)
        Total contact forces, N.
    contacts : array_like of int
        0-based contact indices to average.
    dynamic : bool
        Subtract the static force (default, AC-coupled sensors) or not.
    static : array_like, shape (..., n) or (n,), optional
        Static contact forces, N; default the first sample (see :func:`dynamic_force`).

    Returns
    -------
    ndarray, shape (..., nt)
        Averaged force, N.
    """
    force = np.asarray(force, dtype=float)
    require(force.ndim >= 2, f"force must have shape (..., nt, n), got {force.shape}")
    idx = np.asarray(contacts, dtype=int)
    f = dynamic_force(force, static) if dynamic else force
    return f[..., idx].mean(axis=-1)


def observe(kind: SensorKind | str, force: ArrayLike, particle: int, *, dynamic: bool = True,
            static: ArrayLike | None = None, contacts: ArrayLike | None = None) -> np.ndarray:
    """Force a sensor reads: mean of its contacts (see module docstring).

    Parameters
    ----------
    kind : SensorKind or {"bead", "rod", "mss"}
    force : array_like, shape (..., nt, n) or (..., nt, c)
        Total contact forces, N: of all contacts, or of ``contacts``.
    particle : int
        1-based particle number of the sensor (centre, for the MsS).
    dynamic, static
        As in :func:`contact_mean` (``static`` per column of ``force``).
    contacts : array_like of int, shape (c,), optional
        The 0-based contact of each column of ``force`` when it holds some contacts only
        (e.g. ``simulate_batch(..., contacts=read_contacts(...))``); they must include those
        the sensor reads. Default: all contacts, in order.

    Returns
    -------
    ndarray, shape (..., nt)
        Sensor force, N.
    """
    force = np.asarray(force, dtype=float)
    require(force.ndim >= 2, f"force must have shape (..., nt, n), got {force.shape}")
    if contacts is None:
        return contact_mean(force, sensor_contacts(SensorKind(kind), particle, force.shape[-1]),
                            dynamic=dynamic, static=static)
    contacts = np.asarray(contacts, dtype=int)
    # (The chain's length is not known here: whether its contacts are there is checked below.)
    read = sensor_contacts(SensorKind(kind), particle,
                           max(int(contacts.max()) + 1, particle + 2))
    columns = [np.flatnonzero(contacts == c) for c in read]
    require(contacts.shape == force.shape[-1:] and all(col.size for col in columns),
            f"force holds contacts {contacts.tolist()}, which must include the contacts "
            f"{read.tolist()} that the '{SensorKind(kind).value}' sensor at particle "
            f"{particle} reads, one per column")
    return contact_mean(force, [col[0] for col in columns], dynamic=dynamic, static=static)


def read_contacts(sensors: Iterable[tuple[SensorKind | str, int]], n_contacts: int,
                  ) -> np.ndarray:
    """Sorted 0-based contacts that some sensors of one chain read together.

    Parameters
    ----------
    sensors : iterable of (kind, particle)
    n_contacts : int
        Number of contacts of the chain.

    Returns
    -------
    ndarray of int, shape (c,)
        The union of their :func:`sensor_contacts`: what a simulation needs to output for
        :func:`observe` (``contacts=``) to read them all.
    """
    return np.unique(np.concatenate([sensor_contacts(SensorKind(kind), p, n_contacts)
                                     for kind, p in sensors]))


def bead_sensor(force: ArrayLike, particle: int, **kw) -> np.ndarray:
    """Sensor bead at ``particle``: mean of c_{p-1}, c_p, shape (..., nt), N."""
    return observe(SensorKind.BEAD, force, particle, **kw)


def rod_sensor(force: ArrayLike, particle: int, **kw) -> np.ndarray:
    """Piezo rod at ``particle``: mean of its two end contacts, shape (..., nt), N."""
    return observe(SensorKind.ROD, force, particle, **kw)


def mss_four_contact(force: ArrayLike, particle: int, **kw) -> np.ndarray:
    """Four-contact MsS centred at ``particle``: mean of c_{p-2}..c_{p+1}, (..., nt), N."""
    return observe(SensorKind.MSS, force, particle, **kw)


def time_derivative(signal: ArrayLike, t: ArrayLike) -> np.ndarray:
    """Time derivative along the last axis (second-order finite differences).

    Used for the four-contact MsS voltage, V ∝ dF/dt (paper Eq. 5).

    Parameters
    ----------
    signal : array_like, shape (..., nt)
    t : array_like, shape (nt,)
        Sample times, s, strictly increasing (nt >= 3).

    Returns
    -------
    ndarray, shape (..., nt)
        d(signal)/dt, in signal units per second.
    """
    t = np.asarray(t, dtype=float)
    signal = np.asarray(signal, dtype=float)
    require(t.ndim == 1 and t.size >= 3 and signal.shape[-1] == t.size,
            f"time_derivative needs t of shape (nt>=3,) matching signal, got {t.shape} "
            f"and {signal.shape}")
    require(bool(np.all(np.diff(t) > 0)), "sample times t must be strictly increasing")
    return np.gradient(signal, t, axis=-1, edge_order=2)


def time_integral(signal: ArrayLike, t: ArrayLike) -> np.ndarray:
    """Cumulative trapezoidal integral along the last axis, zero at t[0].

    Recovers a force-like signal from an MsS voltage (paper §5.3: integrate, then scale by K).

    Parameters
    ----------
    signal : array_like, shape (..., nt)
    t : array_like, shape (nt,)
        Sample times, s, strictly increasing.

    Returns
    -------
    ndarray, shape (..., nt)
        Integral, in signal units times seconds.
    """
    t = np.asarray(t, dtype=float)
    signal = np.asarray(signal, dtype=float)
    require(t.ndim == 1 and t.size >= 2 and signal.shape[-1] == t.size,
            f"time_integral needs t of shape (nt>=2,) matching signal, got {t.shape} "
            f"and {signal.shape}")
    require(bool(np.all(np.diff(t) > 0)), "sample times t must be strictly increasing")
    steps = 0.5 * (signal[..., 1:] + signal[..., :-1]) * np.diff(t)
    out = np.zeros_like(signal)
    out[..., 1:] = np.cumsum(steps, axis=-1)
    return out


def mss_four_contact_rate(force: ArrayLike, t: ArrayLike, particle: int, **kw) -> np.ndarray:
    """d/dt of the four-contact MsS force: the paper's model of the coil voltage up to a
    constant (Eq. 5), shape (..., nt), N/s."""
    return time_derivative(mss_four_contact(force, particle, **kw), t)

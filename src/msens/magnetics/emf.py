"""The EMF of a physics MsS from the chain's contact states (sign conventions: see
:mod:`msens.magnetics.transducer`).

The chain gives contact forces; :func:`contact_rates` turns them into the rates of both
mechanisms' states (force for Villari, Hertz approach for the contact approach), and
:func:`emf` weights them with the sensitivities of a
:class:`~msens.magnetics.transducer.Transducer`: V = -dΛ/dt. Rigid translation of the chain
and open contacts have their own terms (:func:`rigid_translation_emf`,
:func:`open_contact_emf`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from msens.errors import require
from msens.magnetics.transducer import Mechanism, Transducer, _check_mechanism
from msens.mechanics.hertz import hertz_approach


@dataclass(frozen=True)
class ContactRates:
    """Rates of the contacts a transducer reads, for one chain history.

    Attributes
    ----------
    t : ndarray, shape (nt,)
        s.
    force : ndarray, shape (nt, n_c)
        dF_c/dt, N/s (zero for contacts beyond the chain's columns).
    approach : ndarray, shape (nt, n_c)
        dδ_c/dt of the Hertz approach δ_c = ([F_c]_+/A)^{2/3}, m/s.
    """

    t: np.ndarray
    force: np.ndarray
    approach: np.ndarray


def contact_forces_of(force: np.ndarray, contacts: np.ndarray,
                      columns: np.ndarray | None = None) -> np.ndarray:
    """The columns of ``contacts`` from a chain's contact forces, zeros where absent.

    Parameters
    ----------
    force : ndarray, shape (nt, m)
        Contact forces, N.
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers wanted.
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force`` (sorted); default column k is contact
        k + 1 (as in :mod:`msens.chain`).

    Returns
    -------
    ndarray, shape (nt, n_c)
    """
    f = np.asarray(force, dtype=float)
    contacts = np.asarray(contacts, dtype=int)
    if columns is None:
        columns = np.arange(1, f.shape[1] + 1)
    columns = np.asarray(columns, dtype=int)
    k = np.clip(np.searchsorted(columns, contacts), 0, max(columns.size - 1, 0))
    use = (columns.size > 0) & (columns[k] == contacts)
    out = np.zeros((f.shape[0], contacts.size))
    out[:, use] = f[:, k[use]]
    return out


def contact_rates(t: np.ndarray, force: np.ndarray, contacts: np.ndarray,
                  stiffness: float, columns: np.ndarray | None = None,
                  approach: np.ndarray | None = None,
                  equivalent: Callable[[np.ndarray], np.ndarray] | None = None
                  ) -> ContactRates:
    """Force and approach rates of ``contacts`` from a chain's contact states.

    Parameters
    ----------
    t : ndarray, shape (nt,)
        Strictly increasing times, s.
    force : ndarray, shape (nt, m)
        Contact forces, N.
    contacts : ndarray of int, shape (n_c,)
        1-based contact numbers.
    stiffness : float
        Hertz prefactor A, N/m^1.5.
    columns : ndarray of int, shape (m,), optional
        Contact number of each column of ``force`` (see :func:`contact_forces_of`).
    approach : ndarray, shape (nt, m), optional
        The chain's contact approaches δ_c(t), m (negative: open), same columns as
        ``force``. Without it δ_c = ([F_c]_+/A)^{2/3}, whose slope in F is infinite at
        F = 0: a contact that unloads or opens between two samples then gives a spike.
    equivalent : callable, optional
        Maps the approaches (nt, n_c) of ``contacts`` to those the linear sources read:
        :meth:`Transducer.equivalent_approach` (the nonlinear contact maps). Every reading of
        a chain history passes its transducer's here.

    Notes
    -----
    Rates are :func:`numpy.gradient` (second order, also on non-uniform times).
    """
    t = np.asarray(t, dtype=float)
    require(t.ndim == 1 and t.size >= 2, "t must be 1-D with at least 2 samples")
    require(bool(np.all(np.diff(t) > 0)), "t must be strictly increasing")
    require(np.ndim(force) == 2 and np.shape(force)[0] == t.size,
            f"force must have shape (nt={t.size}, n_contacts), got "
            f"{np.shape(force)}")
    fc = contact_forces_of(force, contacts, columns)
    delta = hertz_approach(fc, stiffness) if approach is None else \
        contact_forces_of(approach, contacts, columns)
    if equivalent is not None:
        delta = equivalent(delta)
    return ContactRates(t=t, force=np.gradient(fc, t, axis=0),
                        approach=np.gradient(delta, t, axis=0))


def emf_from_rates(rates: ContactRates, sensitivity_villari: np.ndarray,
                   dlambda_dapproach: np.ndarray, mechanism: Mechanism = "both"
                   ) -> np.ndarray:
    """Open-circuit EMF V = -Σ_c [(∂Λ/∂F_c) dF_c/dt + (∂Λ/∂δ_c) dδ_c/dt], V.

    Parameters
    ----------
    rates : ContactRates
    sensitivity_villari, dlambda_dapproach : ndarray, shape (..., n_c)
        Wb/N and Wb/m; leading axes (e.g. coil designs) broadcast.
    mechanism : {"villari", "approach", "both"}

    Returns
    -------
    ndarray, shape (..., nt)
    """
    _check_mechanism(mechanism)
    out = 0.0
    if mechanism in ("villari", "both"):
        out = out - np.asarray(sensitivity_villari) @ rates.force.T
    if mechanism in ("approach", "both"):
        out = out - np.asarray(dlambda_dapproach) @ rates.approach.T
    return out


def rigid_translation_emf(transducer: Transducer, rates: ContactRates) -> np.ndarray:
    """The part of the contact-approach EMF that is the beads' rigid translation, V.

    Each approach source moves every modelled bead above its contact rigidly, so summed over
    contacts the sources move bead p by u_p = Σ_{c ≥ p} δ_c (the wall does not move): the
    beads' translation in the coil's and magnet's field gradients is contained in the
    contact-approach EMF. Its size is the sensitivity to translating all modelled beads
    together, T = ∂Λ/∂δ of the lowest modelled contact (no contact changes then), times the
    speed of the coil's bead: -T du_p/dt. Beads near the coil move together to within a few
    contact approaches, so this estimates the translation part of the signal.

    Parameters
    ----------
    transducer : Transducer
    rates : ContactRates
        Rates of ``transducer.contacts`` (:func:`contact_rates`).

    Returns
    -------
    ndarray, shape (nt,)
    """
    contacts = np.asarray(transducer.contacts)
    below = contacts >= transducer.particle
    speed = np.sum(rates.approach[:, below], axis=1)
    return -float(transducer.dlambda_dapproach[-1]) * speed


def open_contact_emf(transducer: Transducer, rates: ContactRates,
                     approach: np.ndarray) -> np.ndarray:
    """The part of the contact-approach EMF from contacts while they are open (δ_c < 0), V.

    The approach sources are linearised about the static load; for an open gap they are
    extrapolated linearly (a gap changes the field mesh's topology). This is how much of the
    signal rests on that extrapolation.

    Parameters
    ----------
    transducer : Transducer
    rates : ContactRates
        Rates of ``transducer.contacts``.
    approach : ndarray, shape (nt, n_c)
        δ_c(t) of the same contacts, m.

    Returns
    -------
    ndarray, shape (nt,)
    """
    parts = -rates.approach * np.asarray(transducer.dlambda_dapproach)[None, :]
    return np.where(np.asarray(approach) < 0.0, parts, 0.0).sum(axis=1)


def emf(transducer: Transducer, t: np.ndarray, force: np.ndarray,
        mechanism: Mechanism = "both", approach: np.ndarray | None = None) -> np.ndarray:
    """Open-circuit coil EMF of one transducer for a chain's contact forces, V.

    Parameters
    ----------
    transducer : Transducer
    t : ndarray, shape (nt,)
        s.
    force : ndarray, shape (nt, m)
        Contact forces, N (column k is contact k + 1).
    mechanism : {"villari", "approach", "both"}
    approach : ndarray, shape (nt, m), optional
        The chain's contact approaches, m (see :func:`contact_rates`).

    Returns
    -------
    ndarray, shape (nt,)
    """
    rates = contact_rates(t, force, transducer.contacts, transducer.contact_stiffness,
                          approach=approach, equivalent=transducer.equivalent_approach)
    return emf_from_rates(rates, transducer.sensitivity_villari, transducer.dlambda_dapproach,
                          mechanism)


__all__ = [
    "ContactRates",
    "contact_forces_of",
    "contact_rates",
    "emf",
    "emf_from_rates",
    "open_contact_emf",
    "rigid_translation_emf",
]

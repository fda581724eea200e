"""The EMF of a physics MsS from the chain's contact states (sign conventions: see
:mod:`msens.magnetics.transducer`).

The chain gives contact forces; :func:`msens.readout.mss.contact_rates` turns them into the
rates of both mechanisms' states (force for Villari, Hertz approach for the contact
approach), and :func:`emf` weights them with the sensitivities of a
:class:`~msens.magnetics.transducer.Transducer`: V = -dΛ/dt (the physics MsS's whole
read-out, EMF to DAQ record, is :func:`msens.readout.mss.mss_signals`). Rigid translation of
the chain and open contacts have their own terms (:func:`rigid_translation_emf`,
:func:`open_contact_emf`).
"""

from __future__ import annotations

import numpy as np

from msens.magnetics.transducer import Mechanism, Transducer
from msens.readout.mss import ContactRates, contact_columns, contact_rates, emf_from_rates


def rigid_translation_rates(transducer: Transducer, rates: ContactRates) -> ContactRates:
    """The beads' rigid translation as contact rates: the lowest modelled contact's approach
    rate carries the speed of the coil's bead, every other rate is zero.

    Each approach source moves every modelled bead above its contact rigidly, so summed over
    contacts the sources move bead p by u_p = Σ_{c ≥ p} δ_c (the wall does not move): the
    beads' translation in the coil's and magnet's field gradients is contained in the
    contact-approach EMF. Its size is the sensitivity to translating all modelled beads
    together, T = ∂Λ/∂δ of the lowest modelled contact (no contact changes then), times the
    speed of the coil's bead, du_p/dt. Beads near the coil move together to within a few
    contact approaches, so this estimates the translation part of the signal. Read through a
    transducer's sensitivities (:func:`rigid_translation_emf`) or an eddy-current frequency
    response (:func:`msens.magnetics.eddy_readout.mechanism_emfs`, its ``"approach"`` part).

    Parameters
    ----------
    transducer : Transducer
    rates : ContactRates
        Rates of ``transducer.contacts`` (:func:`contact_rates`).

    Returns
    -------
    ContactRates
    """
    contacts = np.asarray(transducer.contacts)
    below = contacts >= transducer.particle
    approach = np.zeros_like(rates.approach)
    approach[:, -1] = np.sum(rates.approach[:, below], axis=1)
    return ContactRates(rates.t, np.zeros_like(rates.force), approach)


def rigid_translation_emf(transducer: Transducer, rates: ContactRates) -> np.ndarray:
    """The part of the contact-approach EMF that is the beads' rigid translation, V, shape
    (nt,): -T du_p/dt, with the arguments and T of :func:`rigid_translation_rates`."""
    return emf_from_rates(rigid_translation_rates(transducer, rates),
                          transducer.sensitivity_villari, transducer.dlambda_dapproach,
                          "approach")


def open_contact_rates(rates: ContactRates, approach: np.ndarray) -> ContactRates:
    """The contact-approach rates of contacts while they are open (δ_c < 0); every other
    rate is zero.

    The approach sources are linearised about the static load; for an open gap they are
    extrapolated linearly (a gap changes the field mesh's topology). The EMF of these rates
    (:func:`open_contact_emf`, or through an eddy-current frequency response) is how much
    of the signal rests on that extrapolation.

    Parameters
    ----------
    rates : ContactRates
    approach : ndarray, shape (nt, n_c)
        δ_c(t) of the same contacts, m.

    Returns
    -------
    ContactRates
    """
    return ContactRates(rates.t, np.zeros_like(rates.force),
                        np.where(np.asarray(approach) < 0.0, rates.approach, 0.0))


def open_contact_emf(transducer: Transducer, rates: ContactRates,
                     approach: np.ndarray) -> np.ndarray:
    """The part of the contact-approach EMF from contacts while they are open (δ_c < 0), V
    (:func:`open_contact_rates`).

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
    return emf_from_rates(open_contact_rates(rates, approach), transducer.sensitivity_villari,
                          transducer.dlambda_dapproach, "approach")


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
    "contact_columns",
    "contact_rates",
    "emf",
    "emf_from_rates",
    "open_contact_emf",
    "open_contact_rates",
    "rigid_translation_emf",
    "rigid_translation_rates",
]  # the first four from msens.readout.mss, where they live

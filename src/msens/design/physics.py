"""The study's wave as a design sees it: the same chain ``msens run`` simulates.

:func:`study_wave` simulates the study's MsS setup exactly as :func:`msens.pipeline.run_study`
does (its damping, or its Eq. 10 fit; the magnets' pull on the beads from the design's
transducers as static precompression) and reduces it to what a design needs: the contact
rates the transducer reads and the magnetic precompression figures at the sensor.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from msens.chain.equilibrium import static_contact_forces
from msens.config.assemble import build_chain
from msens.config.fieldsetup import mss_setup
from msens.config.study import Study
from msens.design.metrics import Wave
from msens.magnetics.emf import contact_rates
from msens.magnetics.transducer import Transducer, magnetic_precompression
from msens.mechanics.longwave import soliton_speed_precompressed
from msens.pipeline import calibrate_dissipation, output_times, simulate_setup


def study_wave(study: Study, transducers: Mapping[int, Transducer], particle: int) -> Wave:
    """The wave of the study's MsS setup with the transducers' magnets, seen at ``particle``.

    Parameters
    ----------
    study : Study
    transducers : mapping of int -> Transducer
        All transducers of one field model (their magnets set the precompression).
    particle : int
        The swept sensor's coil particle.
    """
    setup = mss_setup(study)
    t = output_times(study)
    fit = calibrate_dissipation(study, t)
    gc = fit.gamma_c if fit is not None else study.chain.gamma_contact
    gw = fit.gamma_w if fit is not None else study.chain.gamma_wall
    chain, history = simulate_setup(study, setup, t, gamma_contact=gc, gamma_wall=gw,
                                    transducers=dict(transducers))
    tr = transducers[particle]
    rates = contact_rates(t, history.force, tr.contacts, tr.contact_stiffness,
                          approach=history.approach, equivalent=tr.equivalent_approach)
    comp = np.cumsum(magnetic_precompression(transducers))  # contact c at index c - 1
    own = slice(max(particle - 3, 0), particle + 1)  # c_{p-2} .. c_{p+1}
    static = static_contact_forces(chain)
    grav = static_contact_forces(build_chain(study, replace(setup, precompression=())))
    peak_dyn = float(np.max(history.force[:, particle - 1] - static[particle - 1]))
    change = float(wave_speed_change(study, peak_dyn, grav[particle - 1], comp[particle - 1]))
    return Wave(contacts=np.asarray(tr.contacts), rates=rates,
                precompression_N=float(np.mean(comp[own])),
                precompression_max_N=float(np.max(np.abs(comp[own]))),
                wave_speed_change=change)


def wave_speed_change(study: Study, peak_dynamic: float, f_gravity: float,
                      f_magnet: np.ndarray) -> np.ndarray:
    """V(F_m + F_mag, F0 + F_mag) / V(F_m, F0) − 1 with F_m = F0 + peak dynamic force.

    Parameters
    ----------
    study : Study
    peak_dynamic : float
        Peak dynamic contact force at the sensor, N.
    f_gravity : float
        Static contact force from gravity alone, N.
    f_magnet : float or ndarray
        Magnetic static compression, N.
    """
    c = study.chain
    rho = c.bead_mass_kg / (np.pi * c.bead_diameter_m**3 / 6)
    args = (c.bead_diameter_m, c.youngs_modulus_pa, c.poisson_ratio, rho)
    f0 = f_gravity
    base = soliton_speed_precompressed(f0 + peak_dynamic, f0, *args)
    mag = np.asarray(f_magnet, dtype=float)
    return soliton_speed_precompressed(f0 + mag + peak_dynamic, f0 + mag, *args) / base - 1.0


__all__ = ["study_wave", "wave_speed_change"]

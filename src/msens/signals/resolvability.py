"""Can a record resolve the pulse, and does it hold the reflected one?

A solitary wave in a chain of spheres lasts a few tens of microseconds and crosses a bead
in a few microseconds; a record sampled at 1 kHz, or one that ends before the wave has come
back from the wall, cannot give its time of flight (TOF) or amplitude ratio (AR), however
confidently a peak finder reports numbers. This module bounds the pulse's scales from the
chain's parameters alone, before any simulation, so the study can be refused naming the
key, and checks the features found in a record against the same bounds afterwards.

The bounds lean towards accepting:

- the wave's peak contact force is bounded by the Hertz impact of the striker on the first
  bead (the wave that forms carries less: about 4.6 N against the 17 N bound for the paper's
  7.2 mm drop), plus the largest static contact force;
- the pulse travels no faster than :data:`SPEED_MARGIN` times the long-wavelength sound
  speed at that force (:func:`msens.mechanics.longwave.sound_speed`), so arrivals are no
  earlier than the distance over that speed (rods count as zero length: sound in a rod is
  faster); for the paper's chain the bound is 1136 m/s against a modelled 647 m/s;
- the pulse spans :data:`PULSE_LENGTH_DIAMETERS` bead diameters, so it lasts at least that
  length over the speed bound (21 µs for the paper's beads, whose modelled pulse has a FWHM
  of 31 µs).

All functions are pure: numbers in, numbers out (SI units).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from msens.mechanics.hertz import hertz_sphere_sphere
from msens.mechanics.longwave import sound_speed

#: Spatial length of a solitary wave in bead diameters (Nesterenko: about five).
PULSE_LENGTH_DIAMETERS = 5.0
#: Factor on the speed bound. The paper's modelled chain (7.2 mm drop) runs at 647 m/s,
#: 0.85 of the sound speed at the impact force (757 m/s); the margin covers what the bound
#: leaves out (the static forces of magnets not yet computed, a stiffer wall, round-off of
#: the Hertz impact), so a record is only refused when it is clearly too short or too coarse.
SPEED_MARGIN = 1.5
#: Fewest samples a record must take within the shortest plausible pulse for its peak and
#: width to be located (a parabola through three samples needs the peak's neighbours on the
#: pulse, not on the baseline).
MIN_SAMPLES_PER_PULSE = 4

__all__ = [
    "MIN_SAMPLES_PER_PULSE",
    "PULSE_LENGTH_DIAMETERS",
    "ROUND_TRIP_WINDOW",
    "SPEED_MARGIN",
    "PulseScales",
    "arrival_bounds",
    "impact",
    "pulse_scales",
    "reflection_note",
    "round_trip",
]


@dataclass(frozen=True)
class PulseScales:
    """Bounds of a chain's pulse, from its parameters alone.

    Attributes
    ----------
    peak_force_n : float
        Upper bound of the wave's peak contact force, N (striker impact + static force).
    speed_m_per_s : float
        Upper bound of the pulse's speed, m/s.
    duration_s : float
        Lower bound of the pulse's duration, s.
    impact_pressure_pa : float
        Peak Hertz pressure of the striker's impact on the first bead, Pa.
    """

    peak_force_n: float
    speed_m_per_s: float
    duration_s: float
    impact_pressure_pa: float

    def min_sample_rate_hz(self) -> float:
        """Lowest sample rate that takes :data:`MIN_SAMPLES_PER_PULSE` samples within
        :attr:`duration_s`, Hz."""
        return MIN_SAMPLES_PER_PULSE / self.duration_s


def impact(mass_kg: float, diameter_m: float, youngs_modulus_pa: float, poisson_ratio: float,
           velocity_m_per_s: float) -> tuple[float, float]:
    """Peak force (N) and peak Hertz pressure (Pa) of a bead striking an identical bead at
    rest (reduced mass m/2, Hertz law F = A delta^1.5 with A of two spheres).

    Returns
    -------
    (float, float)
        Force, N; pressure p0 = 3 F / (2 pi a^2) with a the contact radius, Pa.
    """
    r = 0.5 * diameter_m
    a_hertz = float(hertz_sphere_sphere(youngs_modulus_pa, poisson_ratio, r,
                                        youngs_modulus_pa, poisson_ratio, r))
    reduced = 0.5 * mass_kg
    delta = (5.0 * reduced * velocity_m_per_s**2 / (4.0 * a_hertz)) ** 0.4
    force = a_hertz * delta**1.5
    # contact radius of two spheres of radius r: a^2 = R_eff delta with R_eff = r / 2
    contact_radius_sq = 0.5 * r * delta
    pressure = 3.0 * force / (2.0 * math.pi * contact_radius_sq)
    return force, pressure


def pulse_scales(*, mass_kg: float, diameter_m: float, youngs_modulus_pa: float,
                 poisson_ratio: float, velocity_m_per_s: float,
                 static_force_n: float = 0.0) -> PulseScales:
    """The :class:`PulseScales` bounds of a chain of identical beads struck by one of them.

    Parameters
    ----------
    mass_kg, diameter_m : float
        Bead mass (kg) and diameter (m).
    youngs_modulus_pa, poisson_ratio : float
        Bead material.
    velocity_m_per_s : float
        Striker speed at impact, m/s.
    static_force_n : float
        Largest static contact force of the chain, N (precompression, weight, magnets).
    """
    force, pressure = impact(mass_kg, diameter_m, youngs_modulus_pa, poisson_ratio,
                             velocity_m_per_s)
    peak = force + max(static_force_n, 0.0)
    rho = mass_kg / (math.pi / 6.0 * diameter_m**3)
    speed = SPEED_MARGIN * float(sound_speed(peak, diameter_m, youngs_modulus_pa,
                                             poisson_ratio, rho))
    return PulseScales(peak_force_n=peak, speed_m_per_s=speed,
                       duration_s=PULSE_LENGTH_DIAMETERS * diameter_m / speed,
                       impact_pressure_pa=pressure)


def arrival_bounds(length: ArrayLike, particle: int, speed_m_per_s: float
                   ) -> tuple[float, float]:
    """Earliest times the incident and the wall-reflected pulse reach a particle's centre.

    Time zero is the striker's impact on particle 2 (the striker is particle 1).

    Parameters
    ----------
    length : array_like, shape (n,)
        Axial length of each particle, m; 0 for a particle the pulse crosses at once (a rod,
        for a lower bound).
    particle : int
        1-based particle number (2..n).
    speed_m_per_s : float
        Upper bound of the pulse speed, m/s.

    Returns
    -------
    (float, float)
        Incident and reflected arrival, s.
    """
    lengths = np.asarray(length, dtype=float)
    k = particle - 1  # 0-based
    to_centre = float(np.sum(lengths[1:k]) + 0.5 * lengths[k])
    to_wall = float(np.sum(lengths[1:]))
    back = float(np.sum(lengths[k + 1:]) + 0.5 * lengths[k])
    return to_centre / speed_m_per_s, (to_wall + back) / speed_m_per_s


#: Window of a reflection's time of flight around the round trip expected at the modelled
#: speed (twice the sensor-wall distance over the incident pulse's speed): a reflected pulse
#: is slower (it is smaller: V ~ F^(1/6)) and crosses rods faster; a peak outside is not
#: the wall's reflection. On the paper's setups the TOFs lie within 0.9-1.2 of the centre.
ROUND_TRIP_WINDOW = (0.6, 1.6)


def round_trip(length: ArrayLike, particle: int, speed_m_per_s: float) -> float:
    """Time for a pulse to go from a particle's centre to the wall and back at
    ``speed_m_per_s``, s (``length`` as in :func:`arrival_bounds`)."""
    lengths = np.asarray(length, dtype=float)
    k = particle - 1
    return 2.0 * float(np.sum(lengths[k + 1:]) + 0.5 * lengths[k]) / speed_m_per_s


def reflection_note(t_incident: float, t_reflected: float, t_end: float,
                    window: tuple[float, float]) -> str | None:
    """Why a record's reflected peak is not the wall's reflection, or None if it can be.

    Parameters
    ----------
    t_incident, t_reflected : float
        Times of the incident and the reflected peak the features found, s (NaN: none).
    t_end : float
        End of the record, s.
    window : (float, float)
        Shortest and longest plausible time of flight, s (:data:`ROUND_TRIP_WINDOW` times
        :func:`round_trip`).
    """
    lo, hi = window
    if not math.isfinite(t_incident):
        return "no incident pulse found in the record: no TOF or AR"
    if t_end < t_incident + lo:
        return (f"the record ends at {t_end * 1e6:.4g} us, before the wall's reflection can "
                f"arrive (not before {(t_incident + lo) * 1e6:.4g} us): no TOF or AR")
    if not math.isfinite(t_reflected):
        why = ("the record may end before it (expected up to "
               f"{(t_incident + hi) * 1e6:.4g} us)" if t_end < t_incident + hi
               else "the chain's damping absorbs it")
        return f"no reflected pulse found in the record ({why}): no TOF or AR"
    tof = t_reflected - t_incident
    if not lo <= tof <= hi:
        return (f"the peak taken for the reflection ({t_reflected * 1e6:.4g} us, TOF "
                f"{tof * 1e6:.4g} us) is not the wall's reflection, expected with a TOF of "
                f"{lo * 1e6:.4g}-{hi * 1e6:.4g} us at the modelled speed"
                + (" (the record ends before that)" if t_end < t_incident + hi else "")
                + ": no TOF or AR")
    return None

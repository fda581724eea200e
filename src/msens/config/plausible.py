"""Physical plausibility limits of the numbers a study gives, each with its reason.

The study schema (:mod:`msens.config.study`) refuses a value outside these ranges up front, naming
the key, so that nonsense (a bead of 1e-300 m, a modulus of 1e308 Pa) never reaches the chain
integrator or the field model, where it would hang, exhaust memory or give confident
nonsense. The ranges are generous: every granular chain and magnetostrictive sensor a
laboratory builds lies well inside them.
"""

from __future__ import annotations

# ----------------------------------------------------------------- chain and beads

#: Beads below the striker. Laboratory chains have tens to a few hundred beads; beyond a
#: thousand the tube (metres long) is not a granular-chain sensor any more.
BEADS = (2, 1000)
#: Bead diameter, m: Hertz contact of spheres from 0.1 mm (below, adhesion and surface
#: roughness dominate the contact) to 0.1 m (cannon balls).
BEAD_DIAMETER_M = (1e-4, 0.1)
#: Bead density implied by mass and diameter, kg/m^3: from foamed polymers (~100) to the
#: densest metals (osmium, 22,600), with margin. A mass that does not fit the diameter is a
#: typo in one of them.
BEAD_DENSITY_KG_PER_M3 = (100.0, 30e3)
#: Young's modulus of beads, wall and inserts, Pa: from soft elastomers (~1 MPa) to diamond
#: (1.2 TPa), with margin.
YOUNGS_MODULUS_PA = (1e6, 1.5e12)
#: Shortest dashpot time m/(2 gamma) of a contact, s. The linear law's gamma (kg/s) is a
#: dashpot; one that stops a bead in under 0.1 us damps faster than any Hertz contact of a
#: granular chain vibrates (contact times are microseconds or longer): the chain would not
#: carry a wave, and the integrator's step would shrink to nothing. The paper's fits
#: (gamma ~ 5 kg/s, 0.45 g beads) give ~45 us.
MIN_DASHPOT_TIME_S = 1e-7
#: Reference approach of a contact, m, that turns the Hertz-Kuwabara-Kono coefficient
#: (kg/(s m^0.5)) into a dashpot (gamma = gamma_HKK sqrt(delta)) for the same bound:
#: 1 um is a typical approach of mm-size steel beads under newton forces.
HKK_REFERENCE_APPROACH_M = 1e-6
#: Gravity along the chain, m/s^2: 0 (horizontal chain) up to a centrifuge's 1000 g.
GRAVITY_M_PER_S2 = (0.0, 1e4)
#: Peak Hertz pressure a static load may put on a bead contact, Pa. Above ~10 GPa every
#: steel (and most ceramics) yields: the contact is plastic and Hertz's law, which the chain
#: and field models use, no longer holds.
MAX_CONTACT_PRESSURE_PA = 10e9

# ----------------------------------------------------------------- striker and sensors

#: Striker drop height, m: a drop of 10 m hits at 14 m/s, far into plastic impact for steel.
DROP_HEIGHT_M = (1e-6, 10.0)
#: Striker speed, m/s: same reason (impact yield of steel beads starts near 1 m/s, the
#: chain model stays meaningful a little beyond).
STRIKER_VELOCITY_M_PER_S = (1e-4, 20.0)
#: Axial offset of a coil or magnet from its particle, in bead diameters: beyond half a
#: diameter its centre is nearer the neighbouring particle, which the sensor should name.
MAX_AXIAL_OFFSET_BEADS = 0.5
#: Coil and magnet dimensions, m: a coil wound around a tube of millimetre to centimetre
#: beads; the field model's air box is sized for parts below 0.1 m.
SENSOR_SIZE_M = (1e-5, 0.1)

# ----------------------------------------------------------------- simulation and electronics

#: Fixed integration step, s: below 0.1 ns no granular-chain contact needs resolving (the
#: default step of mm steel beads is ~10 ns) and the step count explodes.
DT_S = (1e-10, 1e-5)
#: Sample rates, Hz: 1 kHz to 1 GHz (the fastest digitisers used on such sensors sample at a
#: few hundred MHz).
SAMPLE_RATE_HZ = (1e3, 1e9)
#: DAQ input resistance, Ohm: 1 Ohm (a current shunt) to 1 POhm (an electrometer).
INPUT_RESISTANCE_OHM = (1.0, 1e15)
#: Cable and input capacitances, F: 0 to 1 uF (10 km of coaxial cable).
CAPACITANCE_F = (0.0, 1e-6)
#: ADC full-scale range, V: 1 mV to 1 kV.
ADC_RANGE_V = (1e-3, 1e3)
#: Random seeds: numpy's generators take non-negative integers below 2^63.
SEED = (0, 2**63 - 1)

# ----------------------------------------------------------------- budget

#: Largest memory the chain records of one run may take, bytes (the machine must hold the
#: force and approach histories of every particle, and of a calibration batch at once).
MEMORY_BUDGET_BYTES = 2 * 2**30
#: Most Runge-Kutta steps times particles of one chain run (about a minute of integration at
#: ~1e8 particle-steps per second, more for a calibration).
STEP_BUDGET = 5e9

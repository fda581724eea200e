"""Physical constants (SI)."""

from __future__ import annotations

import math

#: Vacuum permeability, H/m (CODATA 2018: 1.25663706212e-6).
MU0 = 1.25663706212e-6
#: Standard gravity, m/s^2.
G0 = 9.80665
#: Boltzmann constant, J/K (exact, SI 2019).
K_B = 1.380649e-23
#: Resistivity of annealed copper at 20 °C, Ohm m (IEC 60028).
RHO_COPPER = 1.7241e-8
#: Temperature coefficient of copper resistivity at 20 °C, 1/K (IEC 60028).
ALPHA_COPPER = 0.00393

TWO_PI = 2.0 * math.pi

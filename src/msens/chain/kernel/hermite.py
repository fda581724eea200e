"""Hermite interpolants of the kernel's dense output and event location (scalar helpers).

Interpolation in the step's own time variable: in t for regular steps (quintic through
value, rate, acceleration; septic with the jerks too), and in x = sqrt((t - t_ref) / hs) for
steps taken next to a contact switch (see :mod:`msens.chain.dop853_codegen`); the cubic
Hermite polynomial of a gap or rate locates the state switches. All take and return
scalars, so that the loops that call them vectorise.
"""

from __future__ import annotations

import numba as nb


@nb.njit(cache=True, inline="always")
def hermite_coefficients(septic, p0, d0, e0, f0, dp, d1, e1, f1):
    """Monomial coefficients c1..c7 in s of the Hermite interpolant on s in [0, 1].

    End data: values p0 and p0 + dp, first, second and third derivatives in s (d, e, f =
    the time derivatives times h, h^2, h^3). Septic (error O(h^8)) with the third
    derivatives, else quintic (O(h^6); f ignored, c6 = c7 = 0). c0 = p0.
    """
    if septic:
        c4 = (35.0 * dp - 20.0 * d0 - 15.0 * d1 - 5.0 * e0 + 2.5 * e1
              - (2.0 / 3.0) * f0 - f1 / 6.0)
        c5 = -84.0 * dp + 45.0 * d0 + 39.0 * d1 + 10.0 * e0 - 7.0 * e1 + f0 + 0.5 * f1
        c6 = (70.0 * dp - 36.0 * d0 - 34.0 * d1 - 7.5 * e0 + 6.5 * e1
              - (2.0 / 3.0) * f0 - 0.5 * f1)
        c7 = -20.0 * dp + 10.0 * d0 + 10.0 * d1 + 2.0 * e0 - 2.0 * e1 + (f0 + f1) / 6.0
        return d0, 0.5 * e0, f0 / 6.0, c4, c5, c6, c7
    c3 = 10.0 * dp - 6.0 * d0 - 1.5 * e0 - 4.0 * d1 + 0.5 * e1
    c4 = -15.0 * dp + 8.0 * d0 + 1.5 * e0 + 7.0 * d1 - e1
    c5 = 6.0 * dp - 3.0 * d0 - 0.5 * e0 - 3.0 * d1 + 0.5 * e1
    return d0, 0.5 * e0, c3, c4, c5, 0.0, 0.0


@nb.njit(cache=True, inline="always")
def hermite_weights(septic, x, h):
    """Weights of the end data in the Hermite interpolant at s = x of a step of size h.

    Returns (w_dp, w_r0, w_r1, w_q0, w_q1, w_s0, w_s1) for the value, where value = p0
    + w_dp dp + w_r0 r0 + ... (dp = increment, r rates, q accelerations, s jerks at the two
    ends), then the same seven weights for its time derivative (rate = v_dp dp + v_r0 r0
    + ...). Septic or quintic as in :func:`hermite_coefficients` (jerk weights 0).
    """
    x2 = x * x
    x3 = x2 * x
    x4 = x3 * x
    hh = h * h
    inv_h = 1.0 / h
    if septic:
        return (x4 * (35.0 + x * (-84.0 + x * (70.0 - 20.0 * x))),
                h * x * (1.0 + x3 * (-20.0 + x * (45.0 + x * (-36.0 + 10.0 * x)))),
                h * x4 * (-15.0 + x * (39.0 + x * (-34.0 + 10.0 * x))),
                hh * x2 * (0.5 + x2 * (-5.0 + x * (10.0 + x * (-7.5 + 2.0 * x)))),
                hh * x4 * (2.5 + x * (-7.0 + x * (6.5 - 2.0 * x))),
                hh * h * x3 * (1.0 / 6.0 + x * (-2.0 / 3.0 + x * (1.0 + x * (-2.0 / 3.0
                                                                    + x / 6.0)))),
                hh * h * x4 * (-1.0 / 6.0 + x * (0.5 + x * (-0.5 + x / 6.0))),
                inv_h * x3 * (140.0 + x * (-420.0 + x * (420.0 - 140.0 * x))),
                1.0 + x3 * (-80.0 + x * (225.0 + x * (-216.0 + 70.0 * x))),
                x3 * (-60.0 + x * (195.0 + x * (-204.0 + 70.0 * x))),
                h * x * (1.0 + x2 * (-20.0 + x * (50.0 + x * (-45.0 + 14.0 * x)))),
                h * x3 * (10.0 + x * (-35.0 + x * (39.0 - 14.0 * x))),
                hh * x2 * (0.5 + x * (-8.0 / 3.0 + x * (5.0 + x * (-4.0 + 7.0 * x / 6.0)))),
                hh * x3 * (-2.0 / 3.0 + x * (2.5 + x * (-3.0 + 7.0 * x / 6.0))))
    return (x3 * (10.0 + x * (-15.0 + 6.0 * x)),
            h * x * (1.0 + x2 * (-6.0 + x * (8.0 - 3.0 * x))),
            h * x3 * (-4.0 + x * (7.0 - 3.0 * x)),
            hh * x2 * (0.5 + x * (-1.5 + x * (1.5 - 0.5 * x))),
            hh * x3 * (0.5 + x * (-1.0 + 0.5 * x)),
            0.0, 0.0,
            inv_h * x2 * (30.0 + x * (-60.0 + 30.0 * x)),
            1.0 + x2 * (-18.0 + x * (32.0 - 15.0 * x)),
            x2 * (-12.0 + x * (28.0 - 15.0 * x)),
            h * x * (1.0 + x * (-4.5 + x * (6.0 - 2.5 * x))),
            h * x2 * (1.5 + x * (-4.0 + 2.5 * x)),
            0.0, 0.0)


@nb.njit(cache=True, inline="always")
def hermite3_slope(p0, d0, p1, d1, t):
    # d/dt of hermite3
    t2 = t * t
    return ((6.0 * t2 - 6.0 * t) * (p0 - p1) + (3.0 * t2 - 4.0 * t + 1.0) * d0
            + (3.0 * t2 - 2.0 * t) * d1)


@nb.njit(cache=True, inline="always")
def hermite3(p0, d0, p1, d1, t):
    t2 = t * t
    t3 = t2 * t
    return ((2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * d0
            + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * d1)


@nb.njit(cache=True, inline="always")
def sqrt_coefficients(septic, hs, p0, r0, q0, s0, dp, r1, q1, s1):
    """Monomial coefficients c0..c10 of the interpolant of a step taken in x = sqrt((t -
    t_ref) / hs), t_ref its singular end (x = 0), hs = +-h.

    In x the solution is P(t_ref + hs x^2) + (singular terms): the even coefficients are the
    Taylor coefficients of the regular part P at t_ref (value p0, rate r0, acceleration q0,
    jerk s0: c2 = hs r0, c4 = hs^2 q0 / 2, c6 = hs^3 s0 / 6), c1 = 0, and the highest ones
    match the value p0 + dp, rate r1, acceleration q1 (and jerk s1) at x = 1.

    - ``septic`` (linear-dashpot laws, jerks known): the singular terms start at x^7, the
      Hertz (t - t_ref)^{7/2}; c7..c10 from the four end data. Exact for the regular part
      to (t - t_ref)^5 and the singular terms (t - t_ref)^{7/2}, (t - t_ref)^{9/2}.
    - else (Kuwabara-Kono: its jerk is unbounded at t_ref and the singular terms start at
      x^5): c5..c7 from value, rate and acceleration at x = 1.
    """
    hh = hs * hs
    c2 = hs * r0
    c4 = 0.5 * hh * q0
    # Value and first (three) x-derivatives at x = 1 left for the highest coefficients;
    # their inverse systems in exact rationals.
    if septic:
        c6 = hh * hs * s0 / 6.0
        e0 = dp - c2 - c4 - c6
        e1 = 2.0 * hs * r1 - 2.0 * c2 - 4.0 * c4 - 6.0 * c6
        e2 = 2.0 * hs * r1 + 4.0 * hh * q1 - 2.0 * c2 - 12.0 * c4 - 30.0 * c6
        e3 = 12.0 * hh * q1 + 8.0 * hh * hs * s1 - 24.0 * c4 - 120.0 * c6
        return (p0, c2, 0.0, c4, 0.0, c6,
                120.0 * e0 - 36.0 * e1 + 4.0 * e2 - e3 / 6.0,
                -315.0 * e0 + 99.0 * e1 - 11.5 * e2 + 0.5 * e3,
                280.0 * e0 - 91.0 * e1 + 11.0 * e2 - 0.5 * e3,
                -84.0 * e0 + 28.0 * e1 - 3.5 * e2 + e3 / 6.0)
    e0 = dp - c2 - c4
    e1 = 2.0 * hs * r1 - 2.0 * c2 - 4.0 * c4
    e2 = 2.0 * hs * r1 + 4.0 * hh * q1 - 2.0 * c2 - 12.0 * c4
    return (p0, c2, 0.0, c4, 21.0 * e0 - 6.0 * e1 + 0.5 * e2, -35.0 * e0 + 11.0 * e1 - e2,
            15.0 * e0 - 5.0 * e1 + 0.5 * e2, 0.0, 0.0, 0.0)

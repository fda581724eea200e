"""Compiled (numba) integrator of the chain: fixed-step 8th-order Runge-Kutta with contact
events.

Scheme
------
The right-hand side of Eq. 6 is smooth only while the set of closed contacts is fixed: a
linear dashpot switches on with a jump at contact (gamma d(delta)/dt != 0 at delta = 0) and
the Hertz force A delta^{3/2} is only C^1 at delta = 0. A fixed-step Runge-Kutta method
stepping across such points loses its order (to O(h) for the jump). We therefore integrate
a *hybrid* system: each contact carries an open/closed state that is frozen during a step,
and a step whose end violates a state (a closed contact with delta < 0 or an open one with
delta > 0) is cut back to the crossing. The crossing time is located on the cubic Hermite
interpolant of the gap (values and rates at both ends), then refined by Newton steps that
re-run the RK step to the new end until the residual gap is below ``1e-7 h |d(gap)/dt|``
where the force jumps at the switch (a dashpot acting), ``1e-4 h |d(gap)/dt|`` where it is
continuous (an error e in the time then moves the impulse by ~ A rate^{3/2} e^{5/2}); the
contact is toggled there and the step sequence resumes with the nominal step. If another
contact is found in a violated state at the end of the cut step (it switched and switched
back within the uncut step, invisible at its end), the step is redone to there so that the
earlier switch is found. A state that switched at a step's start within the tolerance of
its time is not a violation while it leaves the wrong sign (no chatter).

Even with exact switch times, F ~ (t - t_0)^{3/2} near a switch is not smooth: the solution
has a (t - t_0)^{7/2} term ((t - t_0)^{5/2} for Kuwabara-Kono) that caps the order of a step
starting or ending at t_0. The steps next to a switch are therefore taken in s = sqrt(|t -
t_0|), in which the solution's expansion (powers of (t - t_0)^{1/2}) is smooth
(:mod:`msens.chain.dop853_codegen`): the step after a closing in s = sqrt(t - t_0)
(``STEP_SQRT_START``, length dt 2^-K, then steps dt 2^-(K-1), ..., dt/2, each at most twice
the time since the closing; K = ``grade_levels``, deeper for a grazing closing whose rate
changes within the first step), and the step to an opening in s = sqrt(t_0 - t)
(``STEP_SQRT_END``). An opening is foreseen from the gap's Taylor polynomial to second order;
the contact is approached in halving steps to within dt/4 and the last step, in s, ends at
the estimate, its length refined by Newton until the gap at its end is below the tolerance
above. Dense output inside such a step is a polynomial in s
(:func:`msens.chain.kernel.sampling.sample_sqrt`).

With the loading-only dashpot (``LAW_LINEAR_LOADING``) the dashpot of a closed contact is a
second state, switched where the approach rate changes sign (a kink of the force), located
on the cubic Hermite interpolant of the rate (values and relative accelerations) without
Newton refinement: an O(h^4) error in the time of a kink is harmless. Rates below
``rate_tol`` do not switch it, so the resting part of the chain does not chatter. Most of
these switches are *predicted* instead: the quintic Hermite polynomial through the rate and
its first two derivatives at this and the previous step's start, extrapolated, gives the
rate's next zero, and the step is shortened (or stretched by at most 1 %) to end there; the
switch is taken at the step's end when the zero lies within 1e-3 steps of it, else the step
is cut back as above. Where a contact nearby switched at this step's start, the derivatives'
left limits there enter the fit and their jumps are added to the extrapolation. Contacts
without a dashpot (gamma = 0, e.g. the paper's wall) track no dashpot switches.

The Runge-Kutta method is the 12-stage 8th-order formula of Dormand & Prince (DOP853,
Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., Springer 1993, §II.5), run at a fixed
step. Its step is generated code (:mod:`msens.chain.kernel.dop853_step`, written by
:mod:`msens.chain.dop853_codegen` from SciPy's coefficients,
``scipy.integrate._ivp.dop853_coefficients``) so that the coefficients are neither retyped
nor looped over.

Dense output (arbitrary output times) is the septic Hermite interpolant through the
displacement, velocity, acceleration and jerk at the two ends of the step that contains the
time (error O(h^8) in u, O(h^7) in v); the jerk follows from differentiating Eq. 6 along the
motion (:func:`jerks`) and is only formed for steps that hold output samples. The contact
forces are evaluated from the interpolated state with the step's contact states
(:mod:`msens.chain.kernel.sampling`). With the quintic interpolant the interpolation, not
the integration, set the error; the septic one allows the longer default step.

Layout for speed: the particle arrays, contact states and output rows are padded with zeros
to a multiple of 8 entries past the wall (:mod:`msens.chain.kernel.forces`), so the loops
vectorise without scalar remainders and the per-step event passes are branch-free counts;
the passes over the particle arrays are compiled with their array arguments declared free of
overlap (:mod:`msens.chain.kernel.noalias`); the scratch arrays start on 64-byte boundaries
(:func:`msens.chain.kernel.forces.zeros64`). Measurements behind these choices:
docs/chain-performance.md.

Modules: :mod:`.forces` (padded layout, forces, accelerations, jerks), :mod:`.dop853_step`
(the generated Runge-Kutta step), :mod:`.hermite` (interpolating polynomials),
:mod:`.sampling` (dense output), :mod:`.events` (contact state switches), :mod:`.phases`
(the phases of one step), :mod:`.stepper` (the step loop), :mod:`.noalias` (the no-overlap
compiler), :mod:`.cache_guard` (numba's on-disk cache, invalidated by an edit to any of these
files). All compiled functions are cached on disk (the first use compiles them, up to a
minute; later processes load them).
"""

# The cache guard first: numba stamps each function's cache when it is decorated.
from msens.chain.kernel import cache_guard
from msens.chain.kernel.forces import (
    LAW_HKK,
    LAW_LINEAR,
    LAW_LINEAR_LOADING,
    accelerations,
    contact_forces,
    jerks,
    padded_length,
)
from msens.chain.kernel.stepper import integrate, integrate_batch

__all__ = [
    "LAW_HKK",
    "LAW_LINEAR",
    "LAW_LINEAR_LOADING",
    "accelerations",
    "cache_guard",
    "contact_forces",
    "integrate",
    "integrate_batch",
    "jerks",
    "padded_length",
]

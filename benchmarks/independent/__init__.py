"""An independent simulator of the main study's physics MsS (issue 35, item 5).

A second implementation of the physics behind ``msens run`` on ``studies/paper-mss.toml``
with ``[field] eddy_currents = false`` (its magnetostatic variant, :func:`field.main_study`),
written apart from msens's code path, to make hidden-effect data that msens did not make:

- :mod:`benchmarks.independent.field`: the field model's *tabulated outputs* read once from
  msens (per coil and contact dLambda/ddelta and dLambda/dF, the contact maps' shapes, the
  offset and remanence tables, the magnets' pull, R, L, winding capacitance) and perturbed
  by a seeded ~1 % (the accuracy of the field model: two independent solvers differ by
  about that much);
- :mod:`benchmarks.independent.sim`: the chain (Hertz contacts from E, nu and the radii,
  gravity, the magnets' pull, the linear-loading dashpot), integrated by
  :func:`scipy.integrate.solve_ivp` (DOP853) from a static equilibrium found by
  :func:`scipy.optimize.root`; contact approaches from the beads' positions; the coil flux
  and a read-out circuit derived here (flux-driven state space, :func:`scipy.signal.lsim`);
  the rig (gain, offset, trigger delay and jitter, noise, shots with a speed spread);
- :mod:`benchmarks.independent.cases`: the hidden-effect, null and outside-the-library cases.

Nothing here is imported by ``src/msens``.
"""

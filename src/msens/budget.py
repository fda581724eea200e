"""Work and memory a study's chain runs will need, checked before any work starts.

A study whose values are each plausible can still ask for too much together: a long
``t_end_s`` at a high ``sample_rate_hz`` (the force history of every contact at every
sample), or stiff, light beads whose stable step makes the integration take hours. The
estimate here uses the integrator's own step (:func:`msens.chain.integrate.stable_step`) and
its output layout, and refuses the study naming the keys, with the numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from msens.config import plausible as P
from msens.config.study import Study
from msens.errors import InputError

#: Bytes per output sample and particle of one chain run: the force and approach histories
#: (float64) that :func:`msens.chain.integrate.simulate` returns.
_BYTES_PER_SAMPLE = 2 * 8
#: Contacts each run of the Eq. 10 calibration batch samples (two sensors' contacts).
_CALIBRATION_CONTACTS = 8
#: Largest count of mesh elements the eddy-current model's skin refinement may add
#: (``[field] skin_size_m``). Measured on the one-coil tiny study (9 beads refined):
#: 40 µm gives 38,600 elements in 3.6 s of meshing, 20 µm 71,500 in 7 s, 10 µm 139,000 in
#: 17 s (the finest size of the convergence study, benchmarks/dynamic_mesh_convergence.py);
#: 1 µm would be about 1.3 million, meshed for minutes and solved at every frequency.
MAX_SKIN_ELEMENTS = 150_000

#: Records of nt float64 samples each sensor adds (force, features' work arrays, and for a
#: physics MsS its flux, EMF, voltage and circuit states), a generous count.
_ARRAYS_PER_SENSOR = 16


@dataclass(frozen=True)
class Budget:
    """Estimated cost of a study's largest chain run.

    Attributes
    ----------
    samples : int
        Output samples per record.
    steps : float
        Runge-Kutta steps of one chain run (t_end / step).
    particle_steps : float
        ``steps`` times the particles of the largest setup.
    memory_bytes : float
        Memory of the chain records held at once (one run, or the calibration batch), bytes.
    dt_s : float
        The step used, s.
    """

    samples: int
    steps: float
    particle_steps: float
    memory_bytes: float
    dt_s: float


def estimate(study: Study) -> Budget:
    """The :class:`Budget` of ``study`` (cheap: builds each setup's chain, runs nothing).

    Parameters
    ----------
    study : Study

    Returns
    -------
    Budget
    """
    from msens.calibrate import GAMMA_C_GRID, GAMMA_W_GRID
    from msens.chain.integrate import stable_step
    from msens.chain.kernel import padded_length
    from msens.config.assemble import build_chain

    sim = study.simulation
    samples = round(sim.t_end_s * sim.sample_rate_hz) + 1
    dt = float("inf")
    width = sensors = 0
    for setup in study.setups:
        sensors = max(sensors, len(setup.sensors))
        chain = build_chain(study, setup)
        step = sim.dt_s if sim.dt_s is not None else stable_step(chain,
                                                                 study.striker.velocity_m_per_s)
        dt = min(dt, step)
        width = max(width, chain.n_particles)
    steps = sim.t_end_s / dt if dt > 0.0 else float("inf")
    memory = samples * (padded_length(width) * _BYTES_PER_SAMPLE
                        + sensors * _ARRAYS_PER_SENSOR * 8)
    if study.dissipation_fit is not None:
        runs = len(GAMMA_C_GRID) * len(GAMMA_W_GRID)
        memory = max(memory, runs * samples * _CALIBRATION_CONTACTS * _BYTES_PER_SAMPLE)
    return Budget(samples=samples, steps=steps, particle_steps=steps * width,
                  memory_bytes=float(memory), dt_s=dt)


def skin_elements(study: Study) -> tuple[float, float]:
    """Mesh elements the eddy-current model's skin refinement adds, and the ``skin_size_m``
    that would add :data:`MAX_SKIN_ELEMENTS` (0, 0 without eddy currents or an MsS).

    The refinement (:class:`msens.field.build.MeshOptions`) grades triangles of size
    ``s + g d`` at distance ``d`` on both sides of each refined bead's surface (a half circle
    of length pi R in the axisymmetric section), until a coarser size takes over, so a bead
    adds about ``2 pi R / ((sqrt(3)/4) g s)`` triangles; within 10 % of the measured
    counts (see :data:`MAX_SKIN_ELEMENTS`).

    Returns
    -------
    (float, float)
        Estimated elements (the setup that refines most beads) and the smallest allowed
        skin size, m.
    """
    from msens.config.fieldsetup import eddy_settings, geometry_from_study
    from msens.config.schema import MssModel

    if not study.field.eddy_currents:
        return 0.0, 0.0
    options = eddy_settings(study).options
    per_bead_times_size = 2.0 * math.pi * 0.5 * study.chain.bead_diameter_m / (
        math.sqrt(3.0) / 4.0 * options.skin_growth)
    most = 0
    for setup in study.setups:
        if not any(s.model is MssModel.PHYSICS for s in setup.sensors):
            continue
        geometry = geometry_from_study(study, setup)
        coils = [u.coil.particle for u in geometry.sensors]
        reach = max(options.near_contacts, 1)  # the beads msens.field.build refines
        refined = [p for p in geometry.beads.particles
                   if min(abs(p - q) for q in coils) <= reach]
        most = max(most, len(refined))
    scale = most * per_bead_times_size
    smallest = scale / MAX_SKIN_ELEMENTS
    if smallest > 0.0:  # rounded up to two significant digits, so the value quoted passes
        step = 10.0 ** (math.floor(math.log10(smallest)) - 1)
        smallest = math.ceil(smallest / step) * step
    return scale / options.skin_size, smallest


def check(study: Study) -> Budget:
    """Refuse ``study`` (InputError naming the keys) if its chain runs exceed the memory or
    step budget of :mod:`msens.config.plausible`, or its eddy-current mesh the element
    bound :data:`MAX_SKIN_ELEMENTS`, or if its records cannot resolve the pulse
    (:func:`msens.resolvability.check_study`); returns the chain estimate otherwise."""
    elements, smallest = skin_elements(study)
    if elements > MAX_SKIN_ELEMENTS:
        raise InputError(
            f"{study.source}: 'field.skin_size_m' = {study.field.skin_size_m!r} m refines the "
            f"bead surfaces near the coils into about {elements:,.0f} mesh elements; the bound "
            f"is {MAX_SKIN_ELEMENTS:,} (minutes of meshing and of solving at every frequency "
            f"beyond it): the smallest skin_size_m for this study is {smallest:.2g} m "
            "(default 4e-05 m)")
    b = estimate(study)
    sim = study.simulation
    if b.memory_bytes > P.MEMORY_BUDGET_BYTES:
        calib = (" (the [calibration] batch of Eq. 10 holds many runs at once)"
                 if study.dissipation_fit is not None else "")
        raise InputError(
            f"{study.source}: 'simulation.t_end_s' = {sim.t_end_s:g} s at 'sample_rate_hz' = "
            f"{sim.sample_rate_hz:g} Hz gives {b.samples:,} samples per record, whose chain "
            f"histories need about {b.memory_bytes / 2**30:.3g} GiB{calib}; the budget is "
            f"{P.MEMORY_BUDGET_BYTES / 2**30:g} GiB: shorten t_end_s or lower sample_rate_hz")
    if b.particle_steps > P.STEP_BUDGET:
        cause = ("'simulation.dt_s'" if sim.dt_s is not None else
                 "the chain's stable step (set by 'chain.youngs_modulus_pa', "
                 "'bead_mass_kg', the damping and the striker speed)")
        raise InputError(
            f"{study.source}: 'simulation.t_end_s' = {sim.t_end_s:g} s in steps of "
            f"{b.dt_s:.3g} s from {cause} is {b.steps:.3g} steps of the chain, "
            f"{b.particle_steps:.3g} particle-steps; the budget is {P.STEP_BUDGET:.3g} (about "
            "a minute): shorten t_end_s, or check those values")
    return b

"""Work and memory a study's chain runs will need, checked before any work starts.

A study whose values are each plausible can still ask for too much together: a long
``t_end_s`` at a high ``sample_rate_hz`` (the force history of every contact at every
sample), or stiff, light beads whose stable step makes the integration take hours. The
estimate here uses the integrator's own step (:func:`msens.chain.integrate.stable_step`) and
its output layout, and refuses the study naming the keys, with the numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

from msens.config import plausible as P
from msens.config.study import Study
from msens.errors import InputError

#: Bytes per output sample and particle of one chain run: the force and approach histories
#: (float64) that :func:`msens.chain.integrate.simulate` returns.
_BYTES_PER_SAMPLE = 2 * 8
#: Contacts each run of the Eq. 10 calibration batch samples (two sensors' contacts).
_CALIBRATION_CONTACTS = 8
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


def check(study: Study) -> Budget:
    """Refuse ``study`` (InputError naming the keys) if its chain runs exceed the memory or
    step budget of :mod:`msens.config.plausible`; returns the estimate otherwise."""
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

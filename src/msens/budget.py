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
#: (``[field] skin_size_m``). Measured with the bead surfaces graded only, on the one-coil
#: tiny study (9 beads refined): 40 µm gives 38,600 elements in 3.6 s of meshing, 20 µm
#: 71,500 in 7 s, 10 µm 139,000 in 17 s; 1 µm would be about 1.3 million, meshed for minutes
#: and solved at every frequency. Grading the pole pieces too adds ~33,000 per
#: bridge magnet at 40 µm: the one-coil model has 71,600 elements (7 s of meshing), the main
#: study (two coils) 132,000 against 66,400; at the default 30 µm (1 % of a finer reference
#: at 100 kHz) the main study has ~175,000 (estimated 150,000 added), hence the bound.
MAX_SKIN_ELEMENTS = 200_000

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
    ``s + g d`` at distance ``d`` on both sides of every conducting surface (each refined
    bead's half circle of length pi R in the axisymmetric section, each pole piece's and
    magnet's rectangle outline, :func:`msens.field.build.skin_part_sizes`), until a coarser
    size takes over, so a length ``l`` of surface adds about ``2 l / ((sqrt(3)/4) g s)``
    triangles; within 10 % of the measured counts (see :data:`MAX_SKIN_ELEMENTS`).

    Returns
    -------
    (float, float)
        Estimated elements (the setup that refines most) and the smallest allowed
        skin size, m.
    """
    from msens.config.fieldsetup import eddy_settings, geometry_from_study
    from msens.config.schema import MssModel
    from msens.field.build import skin_beads, skin_part_sizes

    if not study.field.eddy_currents:
        return 0.0, 0.0
    options = eddy_settings(study).options
    per_length_times_size = 2.0 / (math.sqrt(3.0) / 4.0 * options.skin_growth)
    scale = fixed = 0.0  # elements x skin size (surfaces at skin_size), elements (others)
    for setup in study.setups:
        if not any(s.model is MssModel.PHYSICS for s in setup.sensors):
            continue
        geometry = geometry_from_study(study, setup)
        beads = len(skin_beads(geometry, options)) * math.pi * geometry.beads.radius
        parts = fixed_parts = 0.0
        for q, size in skin_part_sizes(geometry, options):
            outline = 2.0 * ((q.r1 - q.r0) + (q.z1 - q.z0))
            if q.name.startswith("pole_"):  # graded to skin_size (the steel's δ/2 is less)
                parts += outline
            else:  # a magnet, graded to its own skin depth: does not scale with skin_size
                fixed_parts += outline * per_length_times_size / size
        here = (beads + parts) * per_length_times_size
        if here / options.skin_size + fixed_parts > scale / options.skin_size + fixed:
            scale, fixed = here, fixed_parts
    smallest = scale / max(MAX_SKIN_ELEMENTS - fixed, 1.0)
    if smallest > 0.0:  # rounded up to two significant digits, so the value quoted passes
        step = 10.0 ** (math.floor(math.log10(smallest)) - 1)
        smallest = math.ceil(smallest / step) * step
    return scale / options.skin_size + fixed, smallest


def check(study: Study) -> Budget:
    """Refuse ``study`` (InputError naming the keys) if its chain runs exceed the memory or
    step budget of :mod:`msens.config.plausible`, or its eddy-current mesh the element
    bound :data:`MAX_SKIN_ELEMENTS`, or if its records cannot resolve the pulse
    (:func:`msens.resolvability.check_study`); returns the chain estimate otherwise."""
    from msens.field.eddy import SKIN_SIZE

    elements, smallest = skin_elements(study)
    if elements > MAX_SKIN_ELEMENTS:
        raise InputError(
            f"{study.source}: 'field.skin_size_m' = {study.field.skin_size_m!r} m refines the "
            f"bead surfaces near the coils into about {elements:,.0f} mesh elements; the bound "
            f"is {MAX_SKIN_ELEMENTS:,} (minutes of meshing and of solving at every frequency "
            f"beyond it): the smallest skin_size_m for this study is {smallest:.2g} m "
            f"(default {SKIN_SIZE:g} m)")
    check_resolvable(study)
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


# ----------------------------------------------------------------- resolvability

def _striker_key(study: Study) -> str:
    return ("'striker.drop_height_m'" if study.striker.drop_height_m is not None
            else "'striker.velocity_m_per_s'")


def setup_scales(study: Study, setup, chain=None):
    """Pulse bounds of one setup (:func:`msens.signals.resolvability.pulse_scales`) and the
    particle lengths the pulse crosses (rods as 0: sound crosses them faster than the
    pulse crosses beads).

    Parameters
    ----------
    study : Study
    setup : SetupSpec
    chain : Chain, optional
        The setup's chain as simulated (with its magnets' static forces); default: built
        from the study (declared precompression only).

    Returns
    -------
    (PulseScales, ndarray)
    """
    import numpy as np

    from msens.chain.equilibrium import static_contact_forces
    from msens.config.assemble import build_chain
    from msens.signals.resolvability import pulse_scales

    chain = build_chain(study, setup) if chain is None else chain
    c = study.chain
    scales = pulse_scales(mass_kg=c.bead_mass_kg, diameter_m=c.bead_diameter_m,
                          youngs_modulus_pa=c.youngs_modulus_pa,
                          poisson_ratio=c.poisson_ratio,
                          velocity_m_per_s=study.striker.velocity_m_per_s,
                          static_force_n=float(np.max(static_contact_forces(chain))))
    length = np.array(chain.length, dtype=float)
    for ins in setup.inserts:
        length[ins.particle - 1] = 0.0
    return scales, length


def check_resolvable(study: Study) -> None:
    """Refuse (InputError naming the key) a study whose records cannot resolve the pulse or
    cannot hold its reflection from the wall, or whose impact yields the beads.

    - ``simulation.sample_rate_hz`` (the chain's output) and, with a physics MsS,
      ``electronics.sample_rate_hz`` (the DAQ's) must take
      :data:`~msens.signals.resolvability.MIN_SAMPLES_PER_PULSE` samples within the shortest
      plausible pulse;
    - ``simulation.t_end_s`` must reach the earliest time the wall's reflection can arrive
      at every sensor (TOF and AR need it);
    - the striker's Hertz impact pressure must stay below
      :data:`msens.config.plausible.MAX_CONTACT_PRESSURE_PA`, where steels yield.

    The bounds lean towards accepting (:mod:`msens.signals.resolvability`); a record that
    passes but still holds no reflection gets its features flagged after the run
    (:func:`flag_unresolved`).
    """
    from msens.config.schema import MssModel
    from msens.signals.resolvability import MIN_SAMPLES_PER_PULSE, arrival_bounds

    sim = study.simulation
    for setup in study.setups:
        scales, length = setup_scales(study, setup)
        if not scales.impact_pressure_pa <= P.MAX_CONTACT_PRESSURE_PA:
            ratio = P.MAX_CONTACT_PRESSURE_PA / scales.impact_pressure_pa
            v_max = study.striker.velocity_m_per_s * ratio**2.5  # p0 grows as v^(2/5)
            limit = (f"a drop of at most {v_max**2 / (2.0 * 9.80665):.3g} m"
                     if study.striker.drop_height_m is not None
                     else f"at most {v_max:.3g} m/s")
            raise InputError(
                f"{study.source}: {_striker_key(study)}: the striker hits at "
                f"{study.striker.velocity_m_per_s:.4g} m/s with a peak Hertz pressure of "
                f"{scales.impact_pressure_pa / 1e9:.3g} GPa on the first contact, above the "
                f"{P.MAX_CONTACT_PRESSURE_PA / 1e9:g} GPa where steels yield (the contact is "
                f"plastic; the Hertz law the chain model uses no longer holds): {limit} here")
        rates = [("simulation.sample_rate_hz", sim.sample_rate_hz)]
        if any(s.model is MssModel.PHYSICS for s in setup.sensors):
            rates.append(("electronics.sample_rate_hz", study.electronics.sample_rate_hz))
        need = scales.min_sample_rate_hz()
        for key, rate in rates:
            if rate < need:
                raise InputError(
                    f"{study.source}: '{key}' = {rate!r} Hz cannot resolve the pulse: it "
                    f"lasts at least {scales.duration_s * 1e6:.3g} us (a solitary wave of "
                    f"about five {study.chain.bead_diameter_m:g} m beads), which needs "
                    f"{MIN_SAMPLES_PER_PULSE} samples, so at least {need:.3g} Hz")
        for sensor in setup.sensors:
            _, earliest = arrival_bounds(length, sensor.particle, scales.speed_m_per_s)
            if sim.t_end_s < earliest:
                raise InputError(
                    f"{study.source}: 'simulation.t_end_s' = {sim.t_end_s!r} s holds no "
                    f"reflected pulse at the {sensor.kind.value}@{sensor.particle} sensor of "
                    f"setup {setup.name!r}: the wave reaches the wall and comes back there "
                    f"at the earliest at {earliest * 1e6:.4g} us (TOF and AR need that "
                    f"reflection); lengthen t_end_s beyond {earliest:.3g} s (the modelled "
                    "wave is usually about 1.7 times slower than this bound)")


def flag_unresolved(study: Study, result):
    """``result`` (a :class:`msens.results.SetupResult`) with the reflected features of
    every sensor whose record holds no wall reflection set to NaN (null in JSON) and the
    reason in the sensor's ``note``; each reason is also logged as a warning.

    The reflection is expected one round trip (sensor to wall and back) after the incident
    peak at the modelled incident speed (between the setup's sensors, else from the impact
    to the sensor), within :data:`~msens.signals.resolvability.ROUND_TRIP_WINDOW`; a peak
    outside that window, or a record that ends before it, gives no TOF or AR.
    """
    import dataclasses
    import logging

    import numpy as np

    from msens.signals.resolvability import ROUND_TRIP_WINDOW, reflection_note, round_trip

    _, zeroed = setup_scales(study, result.setup, result.chain)
    full = np.asarray(result.chain.length, dtype=float)
    t_end = float(result.history.t[-1])
    sensors = []
    for r in result.sensors:
        t_inc = float(r.features.t_incident)
        speed = result.speed_incident
        if not (math.isfinite(speed) and speed > 0.0):  # one sensor: impact to sensor
            k = r.sensor.particle - 1
            speed = (float(np.sum(full[1:k]) + 0.5 * full[k]) / t_inc
                     if math.isfinite(t_inc) and t_inc > 0.0 else math.nan)
        if math.isfinite(speed) and speed > 0.0:
            window = (ROUND_TRIP_WINDOW[0] * round_trip(zeroed, r.sensor.particle, speed),
                      ROUND_TRIP_WINDOW[1] * round_trip(full, r.sensor.particle, speed))
            note = reflection_note(t_inc, float(r.features.t_reflected), t_end, window)
        else:
            note = "no incident pulse found in the record: no TOF or AR"
        if note is None:
            sensors.append(r)
            continue
        nan = np.full_like(np.asarray(r.features.t_reflected, dtype=float), np.nan)
        features = dataclasses.replace(r.features, t_reflected=nan, f_reflected=nan.copy())
        note = f"{r.sensor.kind.value}@{r.sensor.particle}: {note}"
        logging.getLogger("msens.budget").warning("setup %s: %s", result.setup.name, note)
        sensors.append(dataclasses.replace(r, features=features, note=note))
    if not any(s.note for s in sensors):
        return result
    return dataclasses.replace(result, sensors=tuple(sensors), speed_reflected=math.nan)


def check_record_rate(study: Study, waveform, source: str) -> None:
    """Refuse (InputError naming ``source``) a measured record sampled too coarsely to
    resolve the study's pulse: the same bound as ``simulation.sample_rate_hz``
    (:func:`check_resolvable`), against the record's own sample interval."""
    from msens.signals.resolvability import MIN_SAMPLES_PER_PULSE

    t = waveform.time
    if t.size < 2:
        return  # the readers refuse such records
    dt = float(t[-1] - t[0]) / (t.size - 1)
    # the most lenient setup: the record's sensors choose one of them later
    scales = max((setup_scales(study, setup)[0] for setup in study.setups),
                 key=lambda s: s.duration_s)
    if not dt * MIN_SAMPLES_PER_PULSE <= scales.duration_s:
        raise InputError(
            f"{source}: sampled every {dt * 1e6:.4g} us ({1.0 / dt:.4g} Hz), too coarse for "
            f"the pulse of {study.source}, which lasts at least {scales.duration_s * 1e6:.3g} "
            f"us and needs {MIN_SAMPLES_PER_PULSE} samples, so at least "
            f"{scales.min_sample_rate_hz():.3g} Hz (or the time axis looks scaled: time_s "
            "must be in seconds)")

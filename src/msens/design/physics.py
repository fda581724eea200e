"""Physics shared by coil and magnet sweeps: bias state, magnetic precompression, the wave.

- :func:`bias_state`: mesh (cached by content hash), nonlinear bias solve, Villari sources of
  the beads within :data:`SENSITIVE_BEADS` of the sensor and their incremental potentials
  (:mod:`msens.design.reciprocity`).
- :func:`magnetic_compression`: the static compression each modelled contact carries from the
  magnets (eggshell Maxwell stress, :func:`msens.field.sensor_model.contact_forces`) and the
  equivalent static particle forces for the chain (x down: f_p = C_p − C_{p−1}; the magnets'
  compression is taken to end at the modelled column's ends).
- :func:`study_wave`: the chain of the study's MsS setup with those forces in place of the
  setup's declared [[precompression]] (the physics replaces the paper's 1.8 N guess), with the
  study's damping (no Eq. 10 calibration in a sweep).
- :func:`wave_speed_change`: relative change of the long-wave solitary-wave speed at the
  sensor's contact caused by the magnetic precompression (paper Eq. 3-5, msens.longwave).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from msens.assemble import build_chain
from msens.chain.equilibrium import static_contact_forces
from msens.chain.integrate import simulate
from msens.design.reciprocity import source_potentials, villari_sources
from msens.field.geometry import SensorGeometry
from msens.field.sensor_model import bias_problem, contact_forces, load_mesh
from msens.field.solve import FieldSolution, solve
from msens.longwave import soliton_speed_precompressed
from msens.pipeline import output_times
from msens.study import Study

#: Beads on either side of the sensor bead whose Villari sources are solved; at 4 the outer
#: beads' S_i are below 30 % of the central ones and change sign (tests/design).
SENSITIVE_BEADS = 4
#: Newton iterations allowed for a design's bias solve (strongly saturated contacts converge
#: slowly; see progress-fieldcore.md).
MAX_NEWTON = 40


@dataclass(frozen=True)
class BiasState:
    """One bias solve and the incremental potentials of its Villari sources.

    Attributes
    ----------
    solution : FieldSolution
    particles : tuple of int
        Beads with a source, top to bottom (consecutive).
    potentials : ndarray, shape (n_beads, n_dofs)
        A_φ per newton of a two-pole load on each bead, T m/N.
    """

    solution: FieldSolution
    particles: tuple[int, ...]
    potentials: np.ndarray

    @property
    def contacts(self) -> tuple[int, ...]:
        """Contacts c (between beads c and c+1) covered by the sensitivities."""
        return self.particles[:-1]


def bias_state(geometry: SensorGeometry, particle: int,
               mesh_dir: str | Path | None = None) -> BiasState:
    """Mesh, bias solve and Villari potentials around the sensor at ``particle``."""
    axi, _ = load_mesh(geometry, mesh_dir=mesh_dir)
    sol = solve(bias_problem(geometry, axi), max_iter=MAX_NEWTON)
    b = geometry.beads
    parts = tuple(p for p in range(particle - SENSITIVE_BEADS, particle + SENSITIVE_BEADS + 1)
                  if b.first <= p <= b.last)
    pot = source_potentials(sol, villari_sources(sol, geometry, parts))
    return BiasState(sol, parts, pot)


def magnetic_compression(sol: FieldSolution, geometry: SensorGeometry, n_particles: int
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Magnetic static compression per chain contact and the equivalent particle forces.

    Returns
    -------
    compression : ndarray, shape (n_particles,)
        N, contact c_i (particles i, i+1) at index i − 1; zero where not modelled.
    particle_force : ndarray, shape (n_particles,)
        Static force on each particle along +x (toward the wall), N.
    """
    comp = np.zeros(n_particles)
    for cf in contact_forces(sol, geometry):
        comp[cf.upper - 1] = cf.magnetic_force_N
    above = np.concatenate([[0.0], comp[:-1]])
    return comp, comp - above


def study_wave(study: Study, setup, particle_force: np.ndarray | None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contact forces of the study's wave with magnetic static forces.

    Returns
    -------
    t : ndarray, shape (nt,)
        s.
    force : ndarray, shape (nt, n)
        Total contact forces, N.
    static : ndarray, shape (n,)
        Static contact forces at rest (gravity + magnets), N.
    """
    clean = replace(setup, precompression=())
    chain = build_chain(study, clean, static_force=particle_force)
    t = output_times(study)
    history = simulate(chain, study.striker.velocity_m_per_s, t, dt=study.simulation.dt_s)
    return t, history.force, static_contact_forces(chain)


def gravity_static(study: Study, setup) -> np.ndarray:
    """Static contact forces without magnets, N, shape (n,)."""
    return static_contact_forces(build_chain(study, replace(setup, precompression=())))


def wave_speed_change(study: Study, peak_dynamic: float, f_gravity: float,
                      f_magnet: np.ndarray) -> np.ndarray:
    """V(F_m + F_mag, F0 + F_mag) / V(F_m, F0) − 1 with F_m = F0 + peak dynamic force."""
    c = study.chain
    rho = c.bead_mass_kg / (np.pi * c.bead_diameter_m**3 / 6)
    args = (c.bead_diameter_m, c.youngs_modulus_pa, c.poisson_ratio, rho)
    f0 = f_gravity
    base = soliton_speed_precompressed(f0 + peak_dynamic, f0, *args)
    mag = np.asarray(f_magnet, dtype=float)
    return soliton_speed_precompressed(f0 + mag + peak_dynamic, f0 + mag, *args) / base - 1.0


__all__ = ["MAX_NEWTON", "SENSITIVE_BEADS", "BiasState", "bias_state", "gravity_static",
           "magnetic_compression", "study_wave", "wave_speed_change"]

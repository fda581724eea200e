"""Contact mechanics of the beads, below both the chain and the field model.

- :mod:`.hertz` — Hertz contact of elastic spheres (paper Eq. 1, 2, 7).
- :mod:`.longwave` — long-wavelength speeds of sound and solitary waves in the chain.
- :mod:`.beadmesh`, :mod:`.elasticity`, :mod:`.beadstress`, :mod:`.stress_sampling` — the
  stress inside a bead squeezed by its neighbours (axisymmetric linear elasticity) and its
  sampling at points, along lines and over the bead.

The names below load with their module on first use: importing :mod:`.hertz` does not load
the finite-element code of :mod:`.elasticity`.
"""

from msens._lazy import attribute, names

_HOMES = {
    "hertz": ("effective_modulus", "hertz_approach", "hertz_contact_radius", "hertz_energy",
              "hertz_sphere_flat", "hertz_sphere_sphere", "identical_spheres_modulus"),
    "longwave": ("soliton_speed_precompressed", "soliton_speed_uncompressed", "sound_speed"),
    "beadmesh": ("BeadMeshSpec", "bead_section_mesh"),
    "elasticity": ("axisymmetric_stress", "lame_parameters", "solve_traction"),
    "beadstress": ("BeadStress", "hertz_axis_stress", "hertz_contact", "hertz_resultant",
                   "solve_bead_stress"),
    "stress_sampling": ("mean_stress", "mean_stress_exact", "stress_along", "stress_at"),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)

"""The discrete particle chain of the paper (Eq. 6-9): masses, contact laws, loads.

Conventions (shared with the rest of msens)
-------------------------------------------
* ``n`` particles, 0-based arrays: index ``k`` is the paper's particle ``k + 1``; index 0 is
  the striker. The x axis points down toward the wall, gravity acts along +x.
* ``n`` contacts: index ``k < n - 1`` is the contact between particles ``k`` and ``k + 1``
  (the paper's c_{k+1}); index ``n - 1`` is the last particle on the wall (c_n).
* Displacements ``u`` (m) are measured along +x from the "just touching" configuration;
  the approach is delta_k = [u_k - u_{k+1}]_+ and delta_{n-1} = [u_{n-1}]_+.

Each particle k may also feel a viscous drag -c_k v_k (``Chain.drag``, N s/m) from the tube
it slides in, relative to the fixed tube; zero by default.

Contact force (compressive positive), only while delta > 0:

* ``LINEAR`` (paper Eq. 6): F = A delta^{3/2} + gamma d(delta)/dt, gamma in kg/s.
* ``HERTZ_KUWABARA_KONO``: F = A delta^{3/2} + gamma delta^{1/2} d(delta)/dt,
  gamma in kg/(s m^{1/2}) (Kuwabara & Kono, Jpn. J. Appl. Phys. 26 (1987) 1230).
* ``LINEAR_LOADING``: F = A delta^{3/2} + gamma [d(delta)/dt]_+, gamma in kg/s: the dashpot
  acts only while the contact is compressed further. This reading of Eq. 6 (the paper's
  [.]_+ applied to the rate as well) reproduces the paper's Table 2 with gamma_c = 4.8 kg/s:
  TOF 319.6 / 228.0 us and AR 0.57 / 0.68 at beads 13 / 18 against the published
  318.7 / 227.5 us and 0.57 / 0.68, whereas ``LINEAR`` gives 335.6 / 239.4 us and 0.42 / 0.56
  (it needs gamma_c ~ 2.2 kg/s to match).

The total force is **not clipped** at zero: as in the paper's Eq. 6 the dashpot term can make
a contact pull briefly just before it opens (at most gamma times the opening speed). We keep
Eq. 6 as printed; clipping would add a switch where the force crosses zero. The elastic part
is never tensile since delta is clipped, and ``LINEAR_LOADING`` is never tensile at all.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from msens.params.units import G0


class DampingLaw(enum.Enum):
    """Dissipative part of the contact force."""

    LINEAR = "linear"
    HERTZ_KUWABARA_KONO = "hertz-kuwabara-kono"
    #: Linear dashpot acting only while the contact is being compressed (d(delta)/dt > 0),
    #: i.e. Eq. 6 with the rate also taken as [d(delta)/dt]_+. With the paper's gamma_c =
    #: 4.8 kg/s this reproduces its Table 2 (TOF and AR at beads 13 and 18), which LINEAR
    #: does not (see tests/verification/test_chain_table2.py).
    LINEAR_LOADING = "linear-loading"


def _vector(name: str, value, n: int | None) -> np.ndarray:
    arr = np.array(value, dtype=float)  # copy: the frozen chain owns its arrays
    if arr.ndim != 1:
        raise ValueError(f"Chain.{name} must be a 1-D array, got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"Chain.{name} must have length {n} (one per particle/contact), "
                         f"got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"Chain.{name} must be finite")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class Chain:
    """A chain of ``n`` particles (striker first) on a wall.

    Attributes
    ----------
    mass : ndarray, shape (n,)
        Particle masses, kg (> 0).
    stiffness : ndarray, shape (n,)
        Hertz prefactor A of each contact, N/m^1.5 (> 0); the last is the wall contact.
    damping : ndarray, shape (n,)
        Dissipation coefficient gamma of each contact (>= 0); kg/s for ``LINEAR``,
        kg/(s m^{1/2}) for ``HERTZ_KUWABARA_KONO``.
    static_force : ndarray, shape (n,)
        Constant external force on each particle, N, along +x (down), without gravity.
    gravity : float
        Acceleration of gravity along +x, m/s^2.
    damping_law : DampingLaw
        Form of the dissipative contact force.
    length : ndarray, shape (n,) or None
        Extent of each particle along the axis, m (2R for a sphere); used only to turn
        displacements into positions.
    drag : ndarray, shape (n,) or None
        Viscous drag coefficient c of each particle on the tube, N s/m (>= 0): force -c v
        on the particle, v its velocity relative to the fixed tube. None (default): zero.
    """

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    static_force: np.ndarray
    gravity: float = G0
    damping_law: DampingLaw = DampingLaw.LINEAR
    length: np.ndarray | None = None
    drag: np.ndarray | None = None

    def __post_init__(self) -> None:
        mass = _vector("mass", self.mass, None)
        n = mass.shape[0]
        if n < 1:
            raise ValueError("a chain needs at least one particle (the striker)")
        fields = {"mass": mass}
        for name in ("stiffness", "damping", "static_force"):
            fields[name] = _vector(name, getattr(self, name), n)
        fields["drag"] = _vector("drag", np.zeros(n) if self.drag is None else self.drag, n)
        if np.any(fields["drag"] < 0):
            raise ValueError("Chain.drag must be >= 0")
        if self.length is not None:
            fields["length"] = _vector("length", self.length, n)
            if np.any(fields["length"] <= 0):
                raise ValueError("Chain.length must be > 0")
        if np.any(mass <= 0):
            raise ValueError("Chain.mass must be > 0")
        if np.any(fields["stiffness"] <= 0):
            raise ValueError("Chain.stiffness must be > 0")
        if np.any(fields["damping"] < 0):
            raise ValueError("Chain.damping must be >= 0")
        if not np.isfinite(self.gravity):
            raise ValueError("Chain.gravity must be finite")
        if not isinstance(self.damping_law, DampingLaw):
            raise ValueError(f"Chain.damping_law must be a DampingLaw, got {self.damping_law!r}")
        for name, arr in fields.items():
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "gravity", float(self.gravity))

    @property
    def n_particles(self) -> int:
        """Number of particles including the striker."""
        return int(self.mass.shape[0])

    @property
    def n_contacts(self) -> int:
        """Number of contacts (= particles; the last is on the wall)."""
        return int(self.mass.shape[0])

    def load(self) -> np.ndarray:
        """Constant force on each particle, gravity included: m g + static_force, N, (n,)."""
        return self.mass * self.gravity + self.static_force


def uniform_chain(n_particles: int, mass: float, stiffness_contact: float,
                  stiffness_wall: float, gamma_contact: float = 0.0, gamma_wall: float = 0.0,
                  *, gravity: float = G0, static_force: np.ndarray | None = None,
                  damping_law: DampingLaw = DampingLaw.LINEAR,
                  length: float | None = None) -> Chain:
    """Chain of identical particles (paper Eq. 7-8).

    Parameters
    ----------
    n_particles : int
        Particles including the striker.
    mass : float
        Particle mass, kg.
    stiffness_contact, stiffness_wall : float
        Hertz prefactors A_c and A_w, N/m^1.5.
    gamma_contact, gamma_wall : float
        Dissipation coefficients gamma_c and gamma_w (units per ``damping_law``).
    gravity : float
        m/s^2 along +x.
    static_force : ndarray, shape (n,), optional
        External static forces, N, +x; zero by default.
    damping_law : DampingLaw
    length : float, optional
        Particle length along the axis (bead diameter), m.

    Returns
    -------
    Chain
    """
    n = int(n_particles)
    stiffness = np.full(n, float(stiffness_contact))
    stiffness[-1] = stiffness_wall
    damping = np.full(n, float(gamma_contact))
    damping[-1] = gamma_wall
    return Chain(mass=np.full(n, float(mass)), stiffness=stiffness, damping=damping,
                 static_force=np.zeros(n) if static_force is None else static_force,
                 gravity=gravity, damping_law=damping_law,
                 length=None if length is None else np.full(n, float(length)))

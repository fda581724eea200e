"""The reference paper's bead constants: one home for every module that needs them.

"A Comparative Study on Three Different Transducers for the Measurement of Nonlinear
Solitary Waves" (shared/reference/hnsw-transducers-paper.txt): low-carbon steel beads of
4.76 mm diameter and 0.45 g (§2; McMaster-Carr 96455K51), and the paper's estimate of the
magnet's static force per sensor contact (§4.1).
"""

from __future__ import annotations

#: Bead radius, m (4.76 mm diameter, paper §2).
BEAD_RADIUS = 2.38e-3
#: Bead mass, kg (paper §2).
BEAD_MASS = 0.45e-3
#: Magnetic static force per sensor contact estimated in the paper (§4.1), N.
PAPER_MAGNETIC_FORCE = 1.8

__all__ = ["BEAD_MASS", "BEAD_RADIUS", "PAPER_MAGNETIC_FORCE"]

"""Published parameter sets and material records, each cited, and physical constants.

- :mod:`.units` — physical constants (SI).
- :mod:`.paper` — the reference paper's bead constants.
- :mod:`.materials` — elastic materials, B–H curves, magnet grades, with their sources.
- :mod:`.magnetostriction_data` — parameter sets of the Jiles–Atherton–Sablik law.
"""

from msens._lazy import attribute, names

_HOMES = {
    "units": ("ALPHA_COPPER", "G0", "K_B", "MU0", "RHO_COPPER", "TWO_PI"),
    "paper": ("BEAD_MASS", "BEAD_RADIUS", "PAPER_MAGNETIC_FORCE"),
    "materials": ("BEAD_STEEL", "BHCurve", "ElasticMaterial", "MAGNET_GRADES", "MagnetGrade",
                  "PIEZO_ROD", "PIEZO_ROD_LENGTH", "PIEZO_ROD_MASS", "STEEL_1018_BH",
                  "STEEL_REVERSIBILITY"),
    "magnetostriction_data": ("JA_DEFAULTS_STEEL", "STEEL_1018_FIT", "JilesAthertonSablik"),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)

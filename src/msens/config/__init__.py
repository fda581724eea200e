"""Study files: schema, parsing, plausibility limits, and the mapping of a study to models.

- :mod:`.study` — a study file read once into a :class:`Study`; changes by dotted keys.
- :mod:`.schema` — the frozen dataclasses of a validated study (schema ``msens.study/1``).
- :mod:`.read_chain`, :mod:`.read_setups`, :mod:`.read_options` — the readers of its tables.
- :mod:`.plausible` — the physical limits of the numbers a study gives, with their reasons.
- :mod:`.assemble` — the discrete chain of one setup.
- :mod:`.fieldsetup` — the field model's geometry and eddy-current settings.
"""

from msens._lazy import attribute, names

_HOMES = {
    "study": ("Study", "builtin_study_path", "default_study_path", "load_study", "parse_study",
              "replace_study"),
    "schema": ("DEFAULT_STUDY", "PAPER_TABLE2", "SCHEMA", "ChainSpec", "CoilSpec",
               "DissipationFitSpec", "FieldSpec", "InsertSpec", "MagnetSpec", "MssModel",
               "PrecompressionSpec", "ReferenceRow", "SensorSpec", "SetupSpec",
               "SimulationSpec", "StrikerSpec", "WallSpec"),
    "assemble": ("build_chain", "precompression_forces"),
    "fieldsetup": ("EddySettings", "eddy_settings", "geometry_from_study"),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)

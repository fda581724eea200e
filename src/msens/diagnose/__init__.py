"""Discrepancy workflow: find where model and measurement disagree, name the missing
effect from a library (:mod:`msens.diagnose.effects`), add it, and show the gap shrink."""

from msens.diagnose.effects import NAMES as EFFECT_NAMES
from msens.diagnose.effects import registry
from msens.diagnose.workflow import (
    THRESHOLD,
    Candidate,
    Diagnosis,
    diagnose,
    diagnose_passes,
    diagnose_reference,
)

__all__ = ["EFFECT_NAMES", "THRESHOLD", "Candidate", "Diagnosis", "diagnose", "diagnose_passes",
           "diagnose_reference", "registry"]

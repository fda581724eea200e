"""Predictions with error bars: uncertain inputs as data, forward propagation, Sobol indices.

- :mod:`.inputs` — the uncertain inputs of a study (``msens.uncertainty/1`` files), checked
  once against it; each input's route to the model (chain and read-out, field-model tables,
  or held at its nominal value with the reason).
- :mod:`.model` — one model evaluation per row of input values through ``msens run``'s own
  observation (:func:`msens.pipeline.observe_setup`).
- :mod:`.propagate` — Saltelli samples (SALib), bands and Sobol indices with confidence
  intervals.
- :mod:`.report` — ``uq.json``, the text table and the figures.
- :mod:`.workflow` — ``msens uq``: checks, then the work, then the files.

The inverse, ``msens calibrate``:

- :mod:`.posterior` — prior (the uncertainty file's distributions) and likelihood (the one
  ``msens diagnose`` uses) of chosen inputs, in standardised coordinates.
- :mod:`.mcmc` — start point, emcee's ensemble sampler, split R-hat and autocorrelation.
- :mod:`.calibration` — ``msens calibrate``: checks, sampling, posterior predictive, files.
- :mod:`.calibration_report` — ``calibration.json``, the text table and the figures.
"""

from msens.uq.calibration import CalibrateResult, Calibration, run_calibrate
from msens.uq.inputs import InputSet, UncertainInput, load_inputs
from msens.uq.propagate import Propagation
from msens.uq.workflow import UqResult, run_uq

# propagate() stays in msens.uq.propagate: a package attribute cannot be both the function
# and the submodule of the same name (``import msens.uq.propagate as m`` would bind the function)
__all__ = ["CalibrateResult", "Calibration", "InputSet", "Propagation", "UncertainInput",
           "UqResult", "load_inputs", "run_calibrate", "run_uq"]

"""
Compare with my scope export
============================

A two-channel oscilloscope wrote ``examples/data/scope-mss.csv``: a few lines of settings,
the header ``Time,CH1,CH2``, a units row, then the time in ms and the voltages in mV. (It was
made by ``msens synth studies/paper-mss.toml --seed 0``: an unknown gain, trigger delay and
1 % noise on the model's coil voltages.) A column map says which column is the time and which
coil each channel recorded, with the scale to SI units; ``msens compare`` then aligns the
record on the model, calibrates its gain and compares the pulse features.

The same on the command line::

    msens compare studies/paper-mss.toml examples/data/scope-mss.csv \\
        --columns examples/data/scope-columns.toml --out out/scope
"""

import tempfile
from pathlib import Path

import matplotlib.image as mpimg
import matplotlib.pyplot as plt

import msens
from msens.io.mapped import mapped

root = Path.cwd()
while not (root / "examples" / "data").is_dir():  # the repository, from docs/ or elsewhere
    root = root.parent
scope = root / "examples" / "data" / "scope-mss.csv"
columns = root / "examples" / "data" / "scope-columns.toml"
print(columns.read_text())

# %%
# Read the export through the map: time in seconds, channels in volts.

waveform = msens.read_waveform(scope, columns=columns)
print(f"{waveform.time.size} samples, {waveform.time[0] * 1e6:.0f} to "
      f"{waveform.time[-1] * 1e6:.0f} us after the trigger; channels: "
      + ", ".join(f"{c.kind}@{c.particle}" for c in waveform.channels))

# %%
# Compare it with the main study. ``compare`` writes ``compare.json`` and ``overlay.png``
# into the output folder and returns a :class:`msens.CompareResult`: ``result.to_json()`` is
# the content of ``compare.json``, ``result.table()`` the text ``msens compare`` prints.

out = Path(tempfile.mkdtemp(prefix="msens-compare-"))
result = msens.compare(msens.load_default(), mapped(scope, columns), out)
print(result.table())  # the table msens compare prints

# %%
# The overlay: the measured record after alignment and calibration against the model's,
# and the residual below each. Where the incident pulses arrive together the TOFs agree;
# where the reflected pulse has the same height relative to the incident one the ARs agree.
# A residual that is only noise says the model explains that channel; a residual with a
# shape (a pulse of its own) says where model and measurement part, which is what
# ``msens diagnose`` then tries to name. A residual of the integrated voltage that drifts
# steadily is a small offset of the voltage record, integrated.

image = mpimg.imread(out / "overlay.png")
fig, ax = plt.subplots(figsize=(8, 8 * image.shape[0] / image.shape[1]), layout="constrained")
ax.imshow(image)
ax.set_axis_off()

"""
Find what the model misses
==========================

The paper's own model of its bead sensors misses the measured time of flight by about 3 %
(its Table 2). What physical effect would close that gap? ``msens diagnose`` fits every
effect of its library — a stiffer or more dissipative wall, a faster striker, another contact
damping law, a static precompression somewhere along the chain, heavier sensor beads, drag on
the tube, ... — each within its physical range, and names the best one only if it is decisive,
plausible and larger than what a rig can hold; then it says whether the data are *explained*
(the residual at the level of the measurement's scatter).

Here the "measurement" is the paper's Table 2 bead rows (TOF and AR with their standard
deviations: the study's ``[[reference.row]]`` tables), as on the command line::

    msens diagnose --reference bead --out out/diagnose-bead
"""

import tempfile
from pathlib import Path

import matplotlib.image as mpimg
import matplotlib.pyplot as plt

import msens

out = Path(tempfile.mkdtemp(prefix="msens-diagnose-"))
result = msens.diagnose(msens.load_paper_table2(), None, out, reference="bead")

print(result.table())  # the table msens diagnose prints; result.to_json(): diagnosis.json

# %%
# Read the table from the top (score: ΔBIC against the baseline; misfit: in units of the
# measurement's standard deviation): the best-scoring candidates can be implausible (a striker
# faster than free fall from its drop height) and are then not named. The named effect's
# parameters say where and how large it is; ``explained`` says whether the model with it
# reproduces the data within their scatter. The figure ``msens diagnose`` writes shows, per
# feature, the model's miss in units of the measurement's standard deviation, for the
# baseline model and with the named effect: bars within about ±1 are within the scatter.

image = mpimg.imread(out / "diagnosis.png")
fig, ax = plt.subplots(figsize=(8, 8 * image.shape[0] / image.shape[1]), layout="constrained")
ax.imshow(image)
ax.set_axis_off()

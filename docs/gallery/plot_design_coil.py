"""
Design a coil
=============

Which coil gives the most signal for the sensor at particle 13? A sweep file lists the coil
keys to vary; ``msens design`` evaluates every design with the same physics as ``msens
run`` — both mechanisms, the chain, each design's own winding resistance, inductance and
read-out circuit — and recommends the one with the best signal-to-noise ratio that keeps a
bandwidth of at least 50 kHz.

The coil is air, so one field model serves every design: the mechanisms' source potentials
are tabulated once (the slow part, tens of seconds) and each design then costs
milliseconds. This example sweeps 12 designs; ``studies/sweep-coil.toml`` sweeps 400 the
same way::

    msens design studies/paper-mss.toml --sweep studies/sweep-coil.toml --out out/sweep-coil
"""

import csv
import tempfile
from pathlib import Path

import matplotlib.image as mpimg
import matplotlib.pyplot as plt

import msens

sweep = """\
schema = "msens.sweep/1"
name = "coil-13-small"
sensor = 13                       # the MsS at particle 13

[coil]
turns = [600, 850, 1100]
length_m = [7e-3, 10e-3]
wire = ["AWG36", "AWG38"]

[recommend]
objective = "snr"
min_bandwidth_Hz = 50e3
"""
work = Path(tempfile.mkdtemp(prefix="msens-design-"))
(work / "sweep.toml").write_text(sweep)

# %%
# Run the sweep (one local worker: the docs build shares its machine).

result = msens.design(msens.load_default(), work / "sweep.toml", work / "out", workers=1,
                      progress=False)
print(result.table())  # what msens design prints: the recommendation and why

# %%
# ``designs.csv`` has one row per design. The paper's coil (1100 turns, 7 mm, AWG36) is one of
# them: its peak DAQ voltage is the one ``msens run`` predicts.

with open(work / "out" / "designs.csv", newline="") as f:
    rows = list(csv.DictReader(f))
keys = [k for k in ("coil_turns", "coil_length_m", "coil_wire", "peak_voltage_V", "snr",
                    "bandwidth_Hz")
        if k in rows[0]]
print(", ".join(keys))
for row in rows:
    print(", ".join(row[k] for k in keys))

# %%
# The Pareto plot ``msens design`` writes: each design by its signal against its
# bandwidth. More turns give more volts, but more inductance and winding capacitance pull the
# read-out's resonance down toward the signal band; the recommended design is marked.

image = mpimg.imread(work / "out" / "pareto.png")
fig, ax = plt.subplots(figsize=(8, 8 * image.shape[0] / image.shape[1]), layout="constrained")
ax.imshow(image)
ax.set_axis_off()

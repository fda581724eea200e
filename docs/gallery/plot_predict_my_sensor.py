"""
Predict my sensor
=================

What voltage will *my* sensor give? Start from the built-in study of the paper's chain and
magnetostrictive sensors, change what differs in your rig — here the striker dropped from
5 mm instead of 7.2 mm, and 3 m of cable between coil and DAQ instead of 1 m — and compare
the predicted DAQ voltage of the coil at particle 13 with the paper's sensor.

``Study.replace`` takes the keys as they are written in the study file (``sensor[1]`` is the
first ``[[sensor]]`` table) and validates the changed study exactly like a file: a typo or a
value out of range raises :class:`msens.InputError` naming the key. Every key, with its unit,
default and range, is in the :ref:`study-reference`.

These changes leave the field model alone, so both runs read the committed field model of
the main study and take seconds. A new coil or magnet geometry is meshed and solved on first
use (and its contact maps tabulated, minutes), then cached; to compare many coils, sweep them
with ``msens design`` (see the coil-design example).
"""

import matplotlib.pyplot as plt

import msens

paper = msens.load_default()  # studies/paper-mss.toml: coils at particles 13 and 18
mine = paper.replace({
    "striker.drop_height_m": 5e-3,                # a lower drop: a weaker, slower pulse
    "electronics.cable_capacitance_F": 300e-12,   # 3 m of RG-58 (about 100 pF/m)
})

# %%
# Run both and print each coil's headline numbers from ``summary.json``.

runs = {"the paper's rig (7.2 mm drop, 1 m cable)": msens.run(paper),
        "my rig (5 mm drop, 3 m cable)": msens.run(mine)}

for label, result in runs.items():
    coil = msens.summary(result)["coils"][0]
    print(f"{label}: peak DAQ voltage {coil['peak_voltage_V']:.3f} V at "
          f"{coil['peak_voltage_time_us']:.1f} us, L = {coil['inductance_H'] * 1e3:.1f} mH, "
          f"resonance {coil['resonance_Hz'] / 1e3:.0f} kHz")

# %%
# Plot the DAQ voltage of coil 13 against the time since the striker's impact. The first
# bipolar pulse is the incident solitary wave passing the coil. A lower drop gives a weaker
# pulse, which travels more slowly (the speed of a solitary wave grows with its amplitude,
# as F^(1/6)) and so arrives later; the longer cable lowers the read-out's resonance
# (printed above), which reshapes the ringing after the pulse.

fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
for label, result in runs.items():
    record = result.setups[0].sensors[0].mss   # the physics-MsS record of coil 13
    ax.plot(record.t_daq * 1e6, record.voltage * 1e3, label=label)
ax.set_xlim(0, 200)
ax.set_xlabel("time since striker impact (µs)")
ax.set_ylabel("DAQ voltage, coil 13 (mV)")
ax.legend(fontsize=8)
ax.grid(alpha=0.3)

# %%
# Before quoting the number: the steel's small-signal permeability is uncertain. With
# ``[field] small_signal_permeability = "reversible"`` the same prediction is about half as
# large (see :ref:`permeability-choice`): the two bracket what a real rig gives.

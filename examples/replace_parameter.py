"""Change a study parameter without editing its TOML, and see what it does to the TOF.

    python examples/replace_parameter.py

``study.replace`` takes dotted keys, spelled as msens's messages name them
(``"sensor[1].coil.turns"``: arrays of tables count from 1), and validates the changed study
exactly like a file: a typo or a value out of range stops with one InputError naming the key.
A harder impact makes a faster, shorter solitary wave (speed ~ F^(1/6)), so the time of flight
between impact and the reflected pulse shrinks. Needs pandas (pip install "msens[notebook]").
"""

import pandas as pd

import msens.api as ms
from msens.errors import InputError

study = ms.load_default()
frames = []
for height_mm in (3.6, 7.2, 14.4):
    changed = study.replace({"striker.drop_height_m": height_mm * 1e-3})
    frame = ms.run(changed).rows_frame()  # the Table-2 rows as a DataFrame
    frame.insert(0, "drop_height_mm", height_mm)
    frames.append(frame)

table = pd.concat(frames)
print(table.pivot(index="drop_height_mm", columns="position", values="tof_us").round(1)
      .rename(columns=lambda p: f"TOF {p} (us)"))
print(table.groupby("drop_height_mm")["speed_m_per_s"].first().round(1).rename("speed (m/s)"))

try:  # what a typo looks like
    study.replace({"striker.drop_heigth_m": 0.01})
except InputError as exc:
    print(f"\nInputError: {exc}")

"""Synthesize measurements of the main study and compare them with its model.

    python examples/synth_compare.py [OUT_DIR]

The same as ``msens synth studies/paper-mss.toml --out DATA.csv --shots 3`` followed by
``msens compare studies/paper-mss.toml DATA.csv --out DIR``: synthetic coil voltages with an
unknown gain, trigger delay and 1 % noise, then the Eq. 11 factor (K, which undoes the gain),
TOF and AR of the measured records against the model's (in parentheses). Writes
``data.csv``, ``compare.json`` and ``overlay.png`` into OUT_DIR (default: a new temporary
folder).
"""

import sys
import tempfile
from pathlib import Path

import msens.api as ms

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="msens-"))
out.mkdir(parents=True, exist_ok=True)
study = ms.load_default()
data = ms.synth(study, out / "data.csv", shots=3, seed=1)  # a SynthResult: path-like
result = ms.compare(study, data.path, out)
print(result.table())  # the table msens compare prints, and the files it wrote
print(f"(and {data.path}: {data.shots} shots of {', '.join(data.channels)})")

"""Read an oscilloscope's CSV export through a column map and compare it with the model.

    python examples/scope_export.py [OUT_DIR]

``data/scope-mss.csv`` is what a 2-channel scope writes: a few lines of settings, the header
``Time,CH1,CH2``, a units row, then times in ms and voltages in mV. The column map says which
column is the time and which coil each channel recorded, with the scale to SI:
``time=Time:ms,mss@13=CH1:mV,mss@18=CH2:mV`` (or the file ``data/scope-columns.toml``). The
command line takes the same map:

    msens check-waveform examples/data/scope-mss.csv --columns examples/data/scope-columns.toml
    msens compare studies/paper-mss.toml examples/data/scope-mss.csv --out DIR \\
        --columns "time=Time:ms,mss@13=CH1:mV,mss@18=CH2:mV"
"""

import sys
import tempfile
from pathlib import Path

import msens.api as ms
from msens.io.mapped import mapped
from msens.io.read import describe, read_waveform, write_waveform

here = Path(__file__).parent / "data"
scope = here / "scope-mss.csv"
columns = "time=Time:ms,mss@13=CH1:mV,mss@18=CH2:mV"

waveform = read_waveform(scope, columns=columns)  # time in s, channels in V
print(f"{scope.name}: {describe(waveform)}")
print(f"metadata: {dict(waveform.metadata)}")

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="msens-"))
out.mkdir(parents=True, exist_ok=True)
write_waveform(waveform, out / "scope-mss-msens.csv", overwrite=True)  # msens's own format

# msens compare reads the export through the TOML map, as --columns does
result = ms.compare(ms.load_default(), mapped(scope, here / "scope-columns.toml"), out)
print(result.table())  # the table msens compare prints, and the files it wrote
print(f"(and {out / 'scope-mss-msens.csv'})")

"""A changed coil of an eddy-current study read from the solved model against a rebuild
(slow: each rebuild meshes and solves the changed geometry's static and eddy-current models).

The tiny study of tests/magnetics/test_eddy_study.py (coarse 0.3 mm skin): after its default
run, ``msens run`` with the coil changed reads the coil's frequency response from the solved
model's harmonic tables (msens.magnetics.eddy_coil_read); in an empty cache the same study is
rebuilt on its own meshes. The two records differ by the two meshes' discretisation and by
the read's L(ω) (the solved coil's, times the static L ratio). On the main study:
``python benchmarks/coil_read.py --eddy``.
"""

from __future__ import annotations

import numpy as np
import pytest
from tests.magnetics.test_eddy_study import CHANGED, EDDY, TINY

from msens import api

pytestmark = pytest.mark.slow


def _run(tmp_path, text, name):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return api.run(api.load(path))


@pytest.mark.parametrize("change", [
    {"turns = 900": "turns = 900", "length_m = 8e-3": "length_m = 8e-3"},
    {"turns = 900": "inner_radius_m = 8.3e-3", "length_m = 8e-3": "axial_offset_m = 0.7e-3"},
    {"turns = 900": 'wire = "AWG38"', "length_m = 8e-3": "turns = 1300"},
], ids=["turns-length", "radius-offset", "wire-turns"])
def test_a_read_coil_with_eddy_currents_equals_a_rebuild(tmp_path, monkeypatch, caplog,
                                                         change):
    changed = CHANGED
    for old, new in change.items():
        changed = changed.replace(old, new)
    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp_path / "warm"))
    _run(tmp_path, TINY + EDDY, "default")
    with caplog.at_level("INFO"):
        read = _run(tmp_path, changed, "read")
    assert "read from the model of the solved coils" in caplog.text
    monkeypatch.setenv("MSENS_MESH_DIR", str(tmp_path / "cold"))
    caplog.clear()
    with caplog.at_level("INFO"):
        rebuilt = _run(tmp_path, changed, "rebuilt")
    assert "read from the model" not in caplog.text
    a, b = (r.setups[0].sensors[0].mss for r in (read, rebuilt))
    peak = float(np.max(np.abs(b.voltage)))
    assert float(np.max(np.abs(a.voltage))) == pytest.approx(peak, rel=0.01)
    assert float(np.max(np.abs(a.voltage - b.voltage))) < 0.02 * peak
    assert int(np.argmax(np.abs(a.voltage))) == pytest.approx(
        int(np.argmax(np.abs(b.voltage))), abs=2)

"""A changed coil of an eddy-current model read from another coil's model
(msens.magnetics.eddy_coil_read) against the eddy-current model of the changed geometry."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from msens.field.sensor_model import coil_resistance
from msens.magnetics.dynamic import RESPONSE_OFFSET_STEP
from msens.magnetics.dynamic_cache import dynamic_report
from msens.magnetics.eddy_coil_read import free_key, read_response, read_table, tables_key
from msens.magnetics.mechanisms import offset_grid
from msens.magnetics.transducer_cache import transducer_report
from msens.params.materials import SIGMA_1018
from msens.store import Store

from .test_coil_read import with_coil
from .test_transducer import COARSE, one_sensor

#: A coarse eddy-current mesh (0.3 mm skin) and four frequencies: the tests check the read,
#: not the numbers' convergence.
EDDY = replace(COARSE, skin_size=3e-4)
FREQS = (0.0, 1e3, 10e3, 100e3)


def _report(geometry, store, **kw):
    return dynamic_report(geometry, options=EDDY, store=store, frequencies=FREQS,
                          offsets=True, **kw)


def _rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.fixture(scope="module")
def warm(tmp_path_factory):
    """A store that has solved the reference geometry's static transducers and eddy-current
    model (as a run of an eddy-current study does)."""
    store = Store.at(tmp_path_factory.mktemp("warm"))
    transducer_report(one_sensor(), store=store)
    return store, _report(one_sensor(), store)


def _made(store):
    """What the store holds besides the tables a first coil change builds."""
    return sorted(p.name for p in store.directory.iterdir() if "coil-table" not in p.name)


@pytest.mark.slow
@pytest.mark.parametrize(("change", "profiles"), [
    ({"turns": 800, "length": 9e-3}, False),
    ({"inner_radius": 8.4e-3, "axial_offset": 0.8e-3}, True)])
def test_a_changed_coil_is_read_and_matches_its_own_eddy_model(warm, change, profiles,
                                                                  tmp_path, caplog):
    """Its own model (slow: a mesh and solves of the changed geometry): with the offset
    profiles (every source at every frequency) in one case, by reciprocity (one solve per
    frequency) in the other."""
    store, _ = warm
    g = with_coil(one_sensor(), **change)
    before = _made(store)
    with caplog.at_level("INFO", logger="msens.magnetics.eddy_coil_read"):
        read = _report(g, store)
    assert "read from the model of the solved coils" in caplog.text
    assert "coil_read" in read.details
    # no mesh, solve or eddy-current model of the changed geometry was written (its static
    # transducer is read from the static field model, msens.magnetics.coil_read)
    assert [n for n in _made(store) if n not in before and n.startswith(("dynamic", "sensor"))
            ] == []
    got = read.responses[13]
    own = dynamic_report(g, options=EDDY, store=Store.at(tmp_path), frequencies=FREQS,
                         offsets=profiles).responses[13]
    assert got.resistance_ohm == pytest.approx(own.resistance_ohm, rel=1e-12)
    # the changed geometry's own coarse mesh differs from the solved one's by a few per mille
    # to a per cent of the sensitivities (as for the static read); the read adds the table's
    # quadrature of the winding difference
    for f in range(len(FREQS)):
        assert _rel(got.approach[f], own.approach[f]) < 0.02, f
        assert _rel(got.villari[f], own.villari[f]) < 0.03, f
    if profiles:
        assert _rel(got.approach_by_offset, own.approach_by_offset) < 0.03
    # Z(ω): R_dc of the new winding and the solved coil's L(ω) times the static L ratio. The
    # static L agrees to the mesh difference; the eddy part of L(ω) is carried by the ratio
    # (as a coil sweep carries it): 1.4 % of |L| off at 100 kHz for a 2 mm longer coil
    np.testing.assert_allclose(got.static_inductance_H, own.static_inductance_H, rtol=3e-3)
    assert _rel(got.inductance, own.inductance) < 0.02
    assert _rel(got.impedance, own.impedance) < 0.02
    assert got.screening is None


def test_the_solved_coil_is_read_exactly_and_the_same_coil_from_its_model(warm, caplog):
    """The read's path: a changed coil is read, not solved; the solved coil through its own
    table is its model exactly."""
    store, reference = warm
    g = one_sensor()
    # the solved geometry itself: its stored model, no read
    again = _report(g, store)
    assert "coil_read" not in again.details
    np.testing.assert_array_equal(again.responses[13].approach, reference.responses[13].approach)
    # a table (built by a change above, or now) read with the solved coil: the reference
    # exactly (the read adds only the difference of two windings' quadratures)
    before = _made(store)
    with caplog.at_level("INFO", logger="msens.magnetics.eddy_coil_read"):
        changed = _report(with_coil(g, turns=900, length=8e-3), store).responses[13]
    assert "read from the model of the solved coils" in caplog.text
    assert [n for n in _made(store) if n not in before and n.startswith(("dynamic", "sensor"))
            ] == []
    moved = with_coil(g, turns=900, length=8e-3)
    assert changed.resistance_ohm == coil_resistance(moved.sensors[0].coil)
    # L(ω): the solved coil's times the static transducers' ratio (the static coil read)
    ratio = (transducer_report(moved, store=store).transducers[13].inductance_H
             / transducer_report(g, store=store).transducers[13].inductance_H)
    np.testing.assert_allclose(changed.inductance, reference.responses[13].inductance * ratio,
                               rtol=1e-12)
    assert ratio != 1.0 and changed.screening is None
    coils = {13: g.sensors[0].coil}
    key = tables_key(g, coils, EDDY, FREQS, SIGMA_1018, None)  # no offset grid in it
    assert free_key(g, EDDY, FREQS, SIGMA_1018, None, None) != free_key(
        g, EDDY, FREQS, SIGMA_1018, None, offset_grid(RESPONSE_OFFSET_STEP).tolist())
    # tables of a model solved with another coil are other tables (another mesh)
    assert key != tables_key(g, {13: with_coil(g, turns=900).sensors[0].coil}, EDDY, FREQS,
                             SIGMA_1018, None)
    table = read_table(store, key, 13)
    assert table is not None
    coil = g.sensors[0].coil
    same = read_response(table, reference.responses[13], coil, g, coil, g, 1.0)
    np.testing.assert_array_equal(same.villari, reference.responses[13].villari)
    np.testing.assert_array_equal(same.approach_by_offset,
                                  reference.responses[13].approach_by_offset)
    np.testing.assert_allclose(same.impedance, reference.responses[13].impedance, rtol=1e-12)

"""The bias solution kept in the store (msens.field.bias_cache): solved once, then read with
the same bits; keyed on the materials too; a damaged file is solved again."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from msens.field import bias_cache
from msens.field import sensor_model as sm
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.store import Store


def _geometry() -> SensorGeometry:
    return SensorGeometry(beads=BeadChain(first=10, last=16),
                          sensors=(SensorUnit(Coil(13), BiasMagnet(13)),),
                          air=AirBox(0.06, 0.05))


def _refuse(*args, **kwargs):
    raise AssertionError("the bias was solved, not read")


def test_a_solved_bias_is_read_back_bit_for_bit(tmp_path, monkeypatch):
    store = Store.at(tmp_path)
    g = _geometry()
    axi, _ = sm.load_mesh(g, store=store)
    fresh = sm.solve(sm.bias_problem(g, axi))
    first = bias_cache.solve_bias(sm.bias_problem(g, axi), g, None, store)
    assert np.array_equal(first.a, fresh.a)  # the same Newton solve
    name = bias_cache.bias_name(g)
    assert store.find_file(name) is not None
    monkeypatch.setattr(bias_cache, "solve", _refuse)
    read = bias_cache.solve_bias(sm.bias_problem(g, axi), g, None, store)
    assert np.array_equal(read.a, first.a)
    assert read.iterations == first.iterations and read.residuals == first.residuals
    # what is computed from it is too: the run's field report
    a = sm.run_field_model(g, store=store, inductance=False)
    np.testing.assert_array_equal(a.axis_Bz_T, sm.axis_profile(first, g)[1])


def test_the_key_holds_the_materials_and_the_mesh():
    g = _geometry()
    weaker = replace(g, sensors=(replace(g.sensors[0], magnet=replace(
        g.sensors[0].magnet, remanence=0.9 * g.sensors[0].magnet.remanence)),))
    names = {bias_cache.bias_name(g), bias_cache.bias_name(weaker)}
    from msens.field.build import MeshOptions

    names.add(bias_cache.bias_name(g, MeshOptions(bead_size=0.5e-3)))
    assert len(names) == 3


def test_a_damaged_bias_is_solved_again(tmp_path, monkeypatch):
    store = Store.at(tmp_path)
    g = _geometry()
    axi, _ = sm.load_mesh(g, store=store)
    first = bias_cache.solve_bias(sm.bias_problem(g, axi), g, None, store)
    path = store.find_file(bias_cache.bias_name(g))
    data = bytearray(path.read_bytes())
    data[-20] ^= 0xFF
    path.write_bytes(bytes(data))
    calls = []

    def counting(problem, **kwargs):
        calls.append(1)
        return sm.solve(problem, **kwargs)

    monkeypatch.setattr(bias_cache, "solve", counting)
    again = bias_cache.solve_bias(sm.bias_problem(g, axi), g, None, store)
    assert calls == [1]
    assert np.array_equal(again.a, first.a)

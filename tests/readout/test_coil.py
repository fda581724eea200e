"""The coil (msens.readout.coil.Coil): wire table, geometry, resistance, Wheeler L,
self-capacitance estimate."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import special

from msens.errors import InputError
from msens.params.units import ALPHA_COPPER, MU0
from msens.readout.coil import (
    PACKING,
    WIRES,
    Coil,
    Wire,
    awg_diameter,
    coil_from,
    heavy_build_diameter,
    turn_to_turn_capacitance,
    wheeler_inductance,
    winding_capacitance,
    wire_for,
)

PAPER = {"turns": 1100, "length": 7e-3, "inner_radius": 7.95e-3}


def paper_winding(**kw) -> Coil:
    return coil_from(PAPER["turns"], PAPER["length"], PAPER["inner_radius"], **kw)


def test_awg_diameters_match_astm_b258():
    # ASTM B258 nominal diameters: AWG 36 = 0.0050 in, AWG 0 = 0.3249 in, AWG 10 = 0.1019 in.
    assert awg_diameter(36) == pytest.approx(0.127e-3, rel=1e-12)
    assert awg_diameter(0) == pytest.approx(0.3249 * 25.4e-3, rel=2e-4)
    assert awg_diameter(10) == pytest.approx(0.1019 * 25.4e-3, rel=5e-4)
    # every 6 gauges halve the diameter (92^(6/39) = 2.0050)
    assert awg_diameter(30) / awg_diameter(36) == pytest.approx(2.005, rel=1e-3)


def test_awg36_resistance_per_metre_matches_wire_table():
    # Wire tables (NEMA MW 1000): AWG 36 copper, 414.8 Ω per 1000 ft nominal at 20 °C.
    w = paper_winding()
    per_metre = w.resistance() / w.wire_length
    assert per_metre == pytest.approx(414.8 / 304.8, rel=1e-3)


def test_heavy_build_awg36_is_0152_mm():
    assert heavy_build_diameter(36) == pytest.approx(0.152e-3, rel=3e-3)
    assert all(heavy_build_diameter(g) > awg_diameter(g) for g in (30, 32, 34, 36, 38, 40))


def test_paper_coil_geometry_and_layers():
    w = paper_winding()
    d = w.wire.insulated_diameter
    # square packing: the build is N d² / length and equals layers × d up to the last layer
    assert w.thickness == pytest.approx(PAPER["turns"] * d**2 / PAPER["length"], rel=1e-12)
    assert w.turns_per_layer == math.floor(PAPER["length"] / d)
    assert (w.layers - 1) * w.turns_per_layer < PAPER["turns"] <= w.layers * w.turns_per_layer
    assert w.outer_radius == pytest.approx(w.inner_radius + w.thickness)
    assert w.mean_turn_length == pytest.approx(math.pi * (w.inner_radius + w.outer_radius))


def test_orthocyclic_build_is_sqrt3_over_2_of_square():
    square = paper_winding(packing="square")
    ortho = paper_winding(packing="orthocyclic")
    assert ortho.thickness / square.thickness == pytest.approx(math.sqrt(3) / 2, rel=1e-12)
    assert paper_winding(packing=0.7).thickness == pytest.approx(
        square.thickness * PACKING["square"] / 0.7)


def test_resistance_temperature_coefficient():
    w = paper_winding()
    assert w.resistance(273.15 + 70.0) / w.resistance(293.15) == pytest.approx(
        1 + ALPHA_COPPER * 50.0, rel=1e-12)


# ---------------------------------------------------------------- inductance reference

def loop_mutual(a: np.ndarray, b: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Mutual inductance of coaxial circles (Maxwell): μ0 √(ab) [(2/k − k)K − (2/k)E]."""
    k2 = 4 * a * b / ((a + b) ** 2 + d**2)
    k = np.sqrt(k2)
    return MU0 * np.sqrt(a * b) * ((2 / k - k) * special.ellipk(k2)
                                   - 2 / k * special.ellipe(k2))


def filament_inductance(w: Coil, n_r: int, n_z: int) -> float:
    """L of a uniform-current rectangular winding section by filament sums.

    Cell self-terms: a loop of radius r with the geometric mean distance of a rectangle
    (≈ 0.2235 (h_r + h_z), Grover 1946) as its equivalent radius: μ0 r (ln(8r/g) − 2).
    """
    hr, hz = w.thickness / n_r, w.length / n_z
    r = w.inner_radius + hr * (np.arange(n_r) + 0.5)
    z = hz * (np.arange(n_z) + 0.5)
    rr, zz = (x.ravel() for x in np.meshgrid(r, z, indexing="ij"))
    ai, bj = np.meshgrid(rr, rr, indexing="ij")
    di = np.subtract.outer(zz, zz)
    same = (ai == bj) & (di == 0)
    m = np.where(same, 0.0, loop_mutual(ai, bj, np.where(same, 1.0, di)))
    g = 0.2235 * (hr + hz)
    m[same] = MU0 * rr * (np.log(8 * rr / g) - 2)
    return float(m.sum()) * (w.turns / rr.size) ** 2


@pytest.mark.parametrize("length,inner_radius", [(7e-3, 7.95e-3), (14e-3, 7.95e-3),
                                                 (7e-3, 5e-3)])
def test_wheeler_matches_filament_sum(length, inner_radius):
    # Wheeler (1928) claims ~1 % for comparable 6a, 9b, 10c; assert 3 %.
    w = coil_from(1100, length, inner_radius)
    ref = filament_inductance(w, 24, 24)
    assert filament_inductance(w, 16, 16) == pytest.approx(ref, rel=5e-3)  # converged
    assert wheeler_inductance(w) == pytest.approx(ref, rel=0.03)


def test_wheeler_scales_with_turns_squared():
    w1 = paper_winding()
    root2 = math.sqrt(2.0)                            # thinner wire: same build
    thin = Wire("thin", w1.wire.bare_diameter / root2, w1.wire.insulated_diameter / root2)
    w2 = Coil(turns=2 * w1.turns, length=w1.length, inner_radius=w1.inner_radius, wire=thin,
              packing_factor=w1.packing_factor)
    assert w2.thickness == pytest.approx(w1.thickness)
    assert wheeler_inductance(w2) == pytest.approx(4 * wheeler_inductance(w1), rel=1e-12)


# ---------------------------------------------------------------- self-capacitance

def test_layer_energy_method_matches_turn_by_turn_energy():
    # Independent check of C = 4/(3 n_l²) Σ C_ll: back-and-forth layers, equal volts per
    # turn, energy summed over every pair of facing turns in adjacent layers.
    w = coil_from(300, 3e-3, 5e-3)
    n_t, n_l = w.turns_per_layer, w.layers
    w = Coil(turns=n_t * n_l, length=w.length, inner_radius=w.inner_radius, wire=w.wire,
             packing_factor=w.packing_factor)                       # full layers
    v_turn = 1.0 / w.turns
    energy = 0.0
    pitch = w.thickness / n_l
    for i in range(n_l - 1):
        c_tt = turn_to_turn_capacitance(2 * math.pi * (w.inner_radius + (i + 1) * pitch),
                                        w.wire.bare_diameter, w.wire.insulated_diameter)
        for k in range(n_t):
            idx_i = i * n_t + (k if i % 2 == 0 else n_t - 1 - k)
            idx_j = (i + 1) * n_t + (k if (i + 1) % 2 == 0 else n_t - 1 - k)
            energy += 0.5 * c_tt * ((idx_j - idx_i) * v_turn) ** 2
    c_energy = 2 * energy          # ½ C V² with V = 1
    # the layer formula treats voltage as continuous along a layer: O(1/n_t²) difference
    assert winding_capacitance(w) == pytest.approx(c_energy, rel=2.0 / n_t**2 + 1e-12)


def test_turn_to_turn_capacitance_behaviour():
    d_c = awg_diameter(36)
    thin = turn_to_turn_capacitance(1.0, d_c, 1.10 * d_c)
    thick = turn_to_turn_capacitance(1.0, d_c, 1.25 * d_c)
    assert thin > thick > 0                       # thinner enamel, closer copper
    assert turn_to_turn_capacitance(2.0, d_c, 1.2 * d_c) == pytest.approx(
        2 * turn_to_turn_capacitance(1.0, d_c, 1.2 * d_c))
    # paper coil: a few to a few tens of pF (small multilayer coils, estimate)
    assert 1e-12 < winding_capacitance(paper_winding()) < 1e-10


@pytest.mark.parametrize("kwargs,match", [
    ({"turns": 0, "length": 7e-3, "inner_radius": 8e-3}, "turns"),
    ({"turns": 10, "length": -1.0, "inner_radius": 8e-3}, "length"),
    ({"turns": 10, "length": 7e-3, "inner_radius": 8e-3, "wire": "copper"}, "wire"),
    ({"turns": 10, "length": 7e-3, "inner_radius": 8e-3, "wire": "AWG33"}, "AWG 33"),
    ({"turns": 10, "length": 7e-3, "inner_radius": 8e-3, "packing": 0.95}, "packing"),
    ({"turns": 10, "length": 7e-3, "inner_radius": 8e-3, "packing": "wild"}, "packing"),
])
def test_bad_coil_input_raises(kwargs, match):
    with pytest.raises(InputError, match=match):
        coil_from(**kwargs)


def test_untabulated_gauge_with_explicit_insulation():
    w = coil_from(100, 5e-3, 5e-3, wire=33, insulated_diameter=0.21e-3)
    assert w.wire.bare_diameter == pytest.approx(awg_diameter(33))


def test_one_wire_table():
    """The field model's wires are the coil's: tabulated gauges come from WIRES, others from
    ASTM B258 and the heavy-build table (one lookup, wire_for)."""
    assert wire_for("AWG36") is WIRES["AWG36"] is Coil().wire
    assert wire_for(" awg34 ") is WIRES["AWG34"]
    assert wire_for(30) == Wire("AWG30", awg_diameter(30), heavy_build_diameter(30))
    # the tables agree to the rounding of their sources
    for name, w in WIRES.items():
        gauge = int(name.removeprefix("AWG"))
        assert w.bare_diameter == pytest.approx(awg_diameter(gauge), rel=5e-3)
        assert w.insulated_diameter == pytest.approx(heavy_build_diameter(gauge), rel=5e-3)


def test_the_field_model_meshes_the_read_outs_coil():
    from msens.field import parts

    assert parts.Coil is Coil and parts.Wire is Wire and parts.WIRES is WIRES

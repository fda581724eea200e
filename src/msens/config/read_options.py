"""Readers of a study's run options: simulation, electronics, field model (with a user B–H
table), dissipation fit, reference rows, measurement file."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from msens.config import plausible as P
from msens.config.read_chain import _check_static_load
from msens.config.schema import (
    ChainSpec,
    DissipationFitSpec,
    FieldSpec,
    ReferenceRow,
    SetupSpec,
    SimulationSpec,
)
from msens.io.tomlreader import Table
from msens.params.materials import (
    BHCurve,
)
from msens.params.units import MU0
from msens.readout.electronics import ElectronicsSpec


def _simulation(t: Table | None) -> SimulationSpec:
    if t is None:
        return SimulationSpec()
    d = SimulationSpec()
    spec = SimulationSpec(
        # a solitary wave needs ~10 us to cross a mm bead: a shorter run sees nothing
        t_end_s=t.number("t_end_s", d.t_end_s, low=1e-6, high=1.0),
        sample_rate_hz=t.number("sample_rate_hz", d.sample_rate_hz, low=P.SAMPLE_RATE_HZ[0],
                                high=P.SAMPLE_RATE_HZ[1]),
        dt_s=t.number("dt_s", None, low=P.DT_S[0], high=P.DT_S[1], allow_none=True),
    )
    if spec.t_end_s * spec.sample_rate_hz > 5e7:
        raise t.error("t_end_s", "times sample_rate_hz gives more than 5e7 samples")
    if spec.t_end_s * spec.sample_rate_hz < 100:  # no pulse can be resolved in fewer
        raise t.error("t_end_s", f"= {spec.t_end_s:g} s at sample_rate_hz = "
                                 f"{spec.sample_rate_hz:g} Hz gives fewer than 100 samples")
    t.finish()
    return spec


def _electronics(t: Table | None) -> ElectronicsSpec:
    if t is None:
        return ElectronicsSpec()
    d = ElectronicsSpec()
    spec = ElectronicsSpec(
        cable_capacitance_f=t.number("cable_capacitance_F", d.cable_capacitance_f,
                                     low=P.CAPACITANCE_F[0], high=P.CAPACITANCE_F[1]),
        input_resistance_ohm=t.number("input_resistance_ohm", d.input_resistance_ohm,
                                      low=P.INPUT_RESISTANCE_OHM[0],
                                      high=P.INPUT_RESISTANCE_OHM[1]),
        input_capacitance_f=t.number("input_capacitance_F", d.input_capacitance_f,
                                     low=P.CAPACITANCE_F[0], high=P.CAPACITANCE_F[1]),
        sample_rate_hz=t.number("sample_rate_hz", d.sample_rate_hz, low=P.SAMPLE_RATE_HZ[0],
                                high=P.SAMPLE_RATE_HZ[1]),
        johnson_noise=t.boolean("johnson_noise", d.johnson_noise),
        temperature_k=t.number("temperature_K", d.temperature_k, low=0.0, high=1000.0),
        adc_bits=t.integer("adc_bits", 0, low=0, high=32) or None,
        adc_range_v=t.number("adc_range_V", None, low=P.ADC_RANGE_V[0],
                             high=P.ADC_RANGE_V[1], allow_none=True),
        input_noise_v_per_rthz=t.number("input_noise_V_per_rtHz", 0.0, low=0.0, high=1e-3),
        seed=t.integer("seed", 0, low=P.SEED[0], high=P.SEED[1]),
    )
    if (spec.adc_bits is None) != (spec.adc_range_v is None):
        raise t.error("adc_bits", "and 'adc_range_V' must be given together")
    t.finish()
    return spec


def _field(t: Table | None, chain: ChainSpec, source: str) -> FieldSpec:
    if t is None:
        return FieldSpec()
    beads = t.raw("beads")
    n = chain.n_particles
    if beads is not None:
        ok = (isinstance(beads, list) and len(beads) == 2
              and all(isinstance(b, int) and not isinstance(b, bool) for b in beads))
        if not ok or not 2 <= beads[0] <= beads[1] <= n:
            raise t.error("beads", f"must be [first, last] particles with 2 <= first <= "
                                   f"last <= {n}, got {beads!r}")
        beads = (beads[0], beads[1])

    def opt(key: str, high: float) -> float | None:
        return t.number(key, None, low=0.0, high=high, allow_none=True)

    load = opt("contact_load_N", 1e4)
    if load is not None:
        _check_static_load(t, "contact_load_N", load, chain)
    spec = FieldSpec(beads=beads, contact_load_n=load,
                     min_flat_radius_m=opt("min_flat_radius_m", 1e-2),
                     contact_gap_m=opt("contact_gap_m", 1e-3),
                     air_radius_m=opt("air_radius_m", 100.0),
                     air_margin_m=opt("air_margin_m", 100.0),
                     steel_bh=_steel_bh(t, source),
                     eddy_currents=t.boolean("eddy_currents", False),
                     # steels lie between ~1 MS/m (stainless) and ~10 MS/m (pure iron)
                     steel_conductivity_s_per_m=t.number("steel_conductivity_S_per_m", None,
                                                         low=1e5, high=2e7,
                                                         allow_none=True),
                     small_signal_permeability=t.string(
                         "small_signal_permeability", "differential",
                         choices=("differential", "reversible")),
                     # c -> 0 would make the steel non-magnetic for the signal; 1 is the
                     # differential slope ("differential")
                     reversibility=t.number("reversibility", None, low=0.01, high=1.0,
                                            allow_none=True),
                     # below 1 µm the mesh explodes; above 1 mm it is no refinement of a 2.4 mm
                     # bead
                     skin_size_m=t.number("skin_size_m", None, low=1e-6, high=1e-3,
                                          allow_none=True),
                     contact_map=t.boolean("contact_map", False))
    for key, value in (("skin_size_m", spec.skin_size_m),
                       ("steel_conductivity_S_per_m", spec.steel_conductivity_s_per_m)):
        if value is not None and not spec.eddy_currents:  # would be silently unused
            raise t.error(key, "applies only with eddy_currents = true")
    if spec.reversibility is not None and spec.small_signal_permeability != "reversible":
        raise t.error("reversibility", "applies only with small_signal_permeability = "
                                       "\"reversible\"")
    t.finish()
    return spec


#: Largest flux density accepted in a B–H table, T (iron-cobalt alloys saturate near 2.4 T;
#: B = 5 T would need H of order 2e6 A/m, far beyond any sensor's field).
BH_MAX_B = 5.0

#: Smallest slope ΔH/ΔB of a table's last interval, A/(m T): the field model joins the table to
#: the saturation line B = B_n + μ0 (H − H_n) with a monotone cubic, which needs the last secant
#: to be at least 1/(3 μ0) (Fritsch–Carlson bound; see msens.field.bh.monotone_bh).
BH_MIN_LAST_SLOPE = 1.0 / (3.0 * MU0)


def _steel_bh(t: Table, source: str) -> BHCurve | None:
    """``field.steel_bh``: [[B_T, H_A_per_m], ...] from (0, 0), both strictly increasing."""
    raw = t.raw("steel_bh")
    if raw is None:
        return None
    key = "steel_bh"
    if not isinstance(raw, list) or len(raw) < 3:
        got = f"{len(raw)} pair(s)" if isinstance(raw, list) else repr(raw)
        raise t.error(key, f"must be an array of at least 3 pairs [[B_T, H_A_per_m], ...], "
                           f"got {got}")
    rows = []
    for i, pair in enumerate(raw):
        ok = (isinstance(pair, list) and len(pair) == 2
              and all(isinstance(v, int | float) and not isinstance(v, bool) for v in pair)
              and all(math.isfinite(v) for v in pair))
        if not ok:
            raise t.error(f"{key}[{i}]", f"must be a pair of finite numbers [B_T, H_A_per_m], "
                                         f"got {pair!r}")
        rows.append((float(pair[0]), float(pair[1])))
    if rows[0] != (0.0, 0.0):
        raise t.error(f"{key}[0]", f"must be [0, 0] (the curve starts at the origin), got "
                                   f"{list(raw[0])!r}")
    for i in range(1, len(rows)):
        (b0, h0), (b1, h1) = rows[i - 1], rows[i]
        if not b1 > b0:
            raise t.error(f"{key}[{i}]", f"B must be strictly increasing: B = {b1} T follows "
                                         f"{b0} T")
        if not h1 > h0:
            raise t.error(f"{key}[{i}]", f"H must be strictly increasing: H = {h1} A/m follows "
                                         f"{h0} A/m")
        if not b1 < BH_MAX_B:
            raise t.error(f"{key}[{i}]", f"B must be below {BH_MAX_B} T, got {b1} T")
    (b0, h0), (b1, h1) = rows[-2], rows[-1]
    if (h1 - h0) / (b1 - b0) < BH_MIN_LAST_SLOPE:
        raise t.error(f"{key}[{len(rows) - 1}]",
                      f"ends too steeply: the last interval's dH/dB = {(h1 - h0) / (b1 - b0):.4g} "
                      f"A/(m T) must be at least 1/(3 mu0) = {BH_MIN_LAST_SLOPE:.4g} A/(m T) to "
                      f"join the saturation line; extend the table to higher fields")
    b, h = (np.array(c) for c in zip(*rows, strict=True))
    b.flags.writeable = False
    h.flags.writeable = False
    return BHCurve(name="user table", b=b, h=h, source=source)


def _two_sensor_setup(t: Table, key: str, setups: tuple[SetupSpec, ...]) -> str:
    name = t.string(key, required=True)
    names = [s.name for s in setups]
    if name not in names:
        raise t.error(key, f"must name a setup ({', '.join(names)}), got {name!r}")
    return name


def _dissipation_fit(t: Table, setups: tuple[SetupSpec, ...]) -> DissipationFitSpec | None:
    dt = t.table("dissipation")
    t.finish()
    if dt is None:
        return None
    setup = _two_sensor_setup(dt, "setup", setups)
    spec = DissipationFitSpec(
        setup=setup,
        ar_top=dt.number("ar_top", required=True, low=0.0, high=1.0, low_open=True),
        ar_bottom=dt.number("ar_bottom", required=True, low=0.0, high=1.0, low_open=True),
    )
    dt.finish()
    if len(next(s for s in setups if s.name == setup).sensors) < 2:
        raise dt.error("setup", f"{setup!r} needs two sensors (top and bottom) for Eq. 10")
    return spec


def _reference(t: Table | None, setups: tuple[SetupSpec, ...]) -> tuple[ReferenceRow, ...]:
    if t is None:
        return ()
    rows = []
    for rt in t.tables("row"):
        rows.append(ReferenceRow(
            setup=_two_sensor_setup(rt, "setup", setups),
            position=rt.string("position", required=True, choices=["top", "bottom"]),
            # a time of flight and an amplitude ratio are > 0 (errors are relative to them);
            # an AR below 1e-3 is a pulse lost in any instrument's noise, one above 10 a
            # pulse grown tenfold in a dissipative chain; a TOF of 1 s is a 300 m chain
            tof_us=rt.number("tof_us", required=True, low=0.0, high=1e6, low_open=True),
            tof_std_us=rt.number("tof_std_us", 0.0, low=0.0, high=1e6),
            ar=rt.number("ar", required=True, low=1e-3, high=10.0),
            ar_std=rt.number("ar_std", 0.0, low=0.0, high=10.0),
            model_tof_us=rt.number("model_tof_us", None, low=0.0, high=1e6, low_open=True,
                                   allow_none=True),
            model_ar=rt.number("model_ar", None, low=1e-3, high=10.0, allow_none=True),
        ))
        rt.finish()
    t.finish()
    return tuple(rows)


def _measurement(t: Table | None, base_dir: Path | None) -> Path | None:
    if t is None:
        return None
    name = t.string("file", required=True)
    t.finish()
    path = Path(name)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    if not path.is_file():
        raise t.error("file", f"names '{path}', which does not exist")
    return path

"""The physics-MsS part of summary.json on the main study: mechanisms and their shares."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from msens import api
from msens.config.study import default_study_path
from msens.magnetics.eddy_readout import mechanism_emfs
from msens.magnetics.emf import (
    contact_columns,
    contact_rates,
    emf_from_rates,
    open_contact_rates,
    rigid_translation_rates,
)


@pytest.fixture(scope="module")
def result():
    return api.run(api.load(default_study_path()))


@pytest.mark.parametrize("eddy", [True, False], ids=["eddy", "magnetostatic"])
def test_mechanism_shares_add_up_and_the_mechanisms_add_to_the_emf(result, eddy):
    if not eddy:
        result = api.run(api.load_default(eddy_currents=False))
    assert bool(result.setups[0].responses) == eddy
    summary = api.physics_summary(result)
    assert summary["dominant_mechanism"] == "contact approach"
    setup = result.setups[0]
    for coil, sensor in zip(summary["coils"], setup.sensors, strict=True):
        share = coil["mechanism_share"]
        assert share["villari"]["energy_share"] + share["approach"]["energy_share"] == \
            pytest.approx(1.0, rel=1e-12)
        assert share["approach"]["energy_share"] > 0.99
        tr = setup.transducers[sensor.sensor.particle]
        h = setup.history
        rates = contact_rates(h.t, h.force, tr.contacts, tr.contact_stiffness,
                              approach=h.approach, equivalent=tr.equivalent_approach)
        response = setup.responses[sensor.sensor.particle] if setup.responses else None
        if response is None:  # magnetostatic: the EMF is the rates times the sensitivities
            parts = [emf_from_rates(rates, tr.sensitivity_villari, tr.dlambda_dapproach, m)
                     for m in ("villari", "approach")]
        else:  # eddy currents (the main study): each mechanism through S(ω), D(ω)
            parts = list(mechanism_emfs(response, rates).values())
        np.testing.assert_allclose(parts[0] + parts[1], sensor.mss.emf, rtol=0,
                                   atol=1e-12 * np.max(np.abs(sensor.mss.emf)))
        # the pulse's EMF: smooth, no one-sample spike above its neighbours
        e = np.abs(sensor.mss.emf)
        k = int(np.argmax(e))
        assert e[k] - max(e[k - 1], e[k + 1]) < 1e-3 * e[k]


def test_rigid_translation_is_below_one_percent_of_the_approach_signal(result):
    # The beads' rigid translation is part of the contact-approach sources; the issue asks
    # that it be quantified and kept when it exceeds 1 % (it is kept either way).
    summary = api.physics_summary(result)
    setup = result.setups[0]
    for coil, sensor in zip(summary["coils"], setup.sensors, strict=True):
        rigid = coil["mechanism_share"]["approach"]["rigid_translation"]
        tr = setup.transducers[sensor.sensor.particle]
        assert rigid["sensitivity_Wb_per_m"] == tr.dlambda_dapproach[-1]
        # whole-chain translation against the coil's own contact: small but not zero
        assert 0 < abs(rigid["sensitivity_Wb_per_m"]) < 0.01 * np.max(
            np.abs(tr.dlambda_dapproach))
        # 0.2 % of the peak magnetostatic; with eddy currents (the main study) about 1.1 %:
        # the whole chain's translation nearly cancels statically, and the eddy currents
        # delay its parts differently (|D| of the lowest contact 6.6e-3 Wb/m at 0 Hz,
        # 3.5e-2 at 10 kHz)
        assert 0 < rigid["fraction_of_peak"] < 0.02


def test_open_contacts_carry_a_small_part_of_the_signal(result):
    # the open-gap part of the approach signal is a linear extrapolation: say how much it is
    summary = api.physics_summary(result)
    for coil in summary["coils"]:
        opened = coil["mechanism_share"]["approach"]["open_contacts"]
        assert 0 < opened["energy_share"] < 0.05
        assert 0 < opened["peak_emf_V"] < 0.2 * coil["mechanism_share"]["approach"]["peak_emf_V"]


@pytest.mark.parametrize("eddy", [True, False], ids=["eddy", "magnetostatic"])
def test_open_contacts_and_translation_read_through_the_runs_model(result, eddy):
    # with eddy currents the open-contact and rigid-translation parts go through the coil's
    # frequency response, as the EMF does: the open and the closed contacts' parts add up
    # to the contact-approach EMF, and the summary reports those parts
    if not eddy:
        result = api.run(api.load_default(eddy_currents=False))
    summary = api.physics_summary(result)
    setup, h = result.setups[0], result.setups[0].history
    for coil, sensor in zip(summary["coils"], setup.sensors, strict=True):
        tr = setup.transducers[sensor.sensor.particle]
        rates = contact_rates(h.t, h.force, tr.contacts, tr.contact_stiffness,
                              approach=h.approach, equivalent=tr.equivalent_approach)
        delta = contact_columns(h.approach, tr.contacts)
        closed = dataclasses.replace(rates, force=0.0 * rates.force,  # δ_c ≥ 0
                                     approach=np.where(delta >= 0.0, rates.approach, 0.0))
        response = setup.responses[sensor.sensor.particle] if eddy else None

        def approach(r, response=response, tr=tr):
            if response is not None:
                return mechanism_emfs(response, r)["approach"]
            return emf_from_rates(r, tr.sensitivity_villari, tr.dlambda_dapproach, "approach")

        opened = approach(open_contact_rates(rates, delta))
        whole = approach(rates)
        np.testing.assert_allclose(opened + approach(closed), whole, rtol=0,
                                   atol=1e-12 * np.max(np.abs(whole)))
        share = coil["mechanism_share"]["approach"]
        assert share["open_contacts"]["peak_emf_V"] == pytest.approx(
            np.max(np.abs(opened)), rel=1e-12)
        rigid = approach(rigid_translation_rates(tr, rates))
        assert share["rigid_translation"]["peak_emf_V"] == pytest.approx(
            np.max(np.abs(rigid)), rel=1e-12)

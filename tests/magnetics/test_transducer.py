"""Physics MsS transducer: per-contact sensitivities, EMF, magnetic forces, cache."""

from __future__ import annotations

import json

import numpy as np
import pytest

from msens.errors import InputError, InternalError
from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.magnetics.approach import hertz_approach_rate, hertz_stiffness
from msens.magnetics.emf import emf
from msens.magnetics.transducer import Transducer, compute_transducers, magnetic_precompression
from msens.magnetics.transducer_cache import transducer_report, transducers_for
from msens.magnetics.villari import StressSampler, bead_stress, contact_sensitivity
from msens.mechanics.stress_sampling import stress_at
from msens.params.materials import BEAD_STEEL
from msens.store import Store

#: Coarse mesh: enough for consistency and symmetry checks (~4k elements, ~1 s per model).
COARSE = MeshOptions(bead_size=0.6e-3, centre_size=0.3e-3, flat_fraction=0.8, wedge_factor=4.0)


def one_sensor(magnet: bool = True) -> SensorGeometry:
    """Beads 9..17, one MsS centred on particle 13 (mirror-symmetric about bead 13)."""
    return SensorGeometry(beads=BeadChain(first=9, last=17),
                          sensors=(SensorUnit(Coil(particle=13),
                                              BiasMagnet(particle=13) if magnet else None),),
                          air=AirBox(0.06, 0.05))


@pytest.fixture(scope="module")
def mesh_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("meshes")


@pytest.fixture(scope="module")
def report(mesh_dir):
    return compute_transducers(one_sensor(), options=COARSE, store=Store.at(mesh_dir))


def test_contact_rule_averages_neighbour_beads():
    contacts, s = contact_sensitivity(np.array([4, 5, 6]), np.array([1.0, 2.0, 4.0]), 30)
    assert contacts.tolist() == [3, 4, 5, 6]
    assert s.tolist() == [0.5, 1.5, 3.0, 2.0]
    # leading axes (coil designs) are kept
    _, many = contact_sensitivity(np.array([4, 5, 6]), np.array([[1.0, 2.0, 4.0]] * 2), 30)
    assert many.tolist() == [[0.5, 1.5, 3.0, 2.0]] * 2
    with pytest.raises(InternalError, match="consecutive"):  # msens picks the particles
        contact_sensitivity(np.array([4, 6]), np.array([1.0, 2.0]), 30)


def test_stress_sampler_matches_beadstress():
    bs = bead_stress(one_sensor(), 2.0)
    rng = np.random.default_rng(7)
    r = rng.uniform(0.0, bs.radius, 600)
    z = rng.uniform(-bs.radius, bs.radius, 600)
    keep = r**2 + z**2 < bs.radius**2
    fast = StressSampler(bs)(r[keep], z[keep])
    ref = stress_at(bs, r[keep], z[keep]) / bs.force
    assert np.max(np.abs(fast - ref)) <= 1e-10 * np.max(np.abs(ref))


def test_hertz_approach_rate_is_derivative_of_hertz_law():
    radius, f = 2.38e-3, 3.0
    e, nu = BEAD_STEEL.youngs_modulus, BEAD_STEEL.poisson_ratio
    stiff = e * np.sqrt(2 * radius) / (3 * (1 - nu**2))
    assert hertz_stiffness(radius) == pytest.approx(stiff, rel=1e-15)
    delta = lambda force: (force / stiff) ** (2 / 3)  # noqa: E731
    fd = (delta(f * 1.001) - delta(f * 0.999)) / (0.002 * f)
    assert hertz_approach_rate(f, radius) == pytest.approx(fd, rel=1e-6)


def test_transducer_shapes_and_symmetry(report):
    tr = report.transducers[13]
    assert tr.contacts.tolist() == list(range(8, 18))
    assert tr.magnetic_particle_force.shape == (30,)
    s = np.array(report.details["coils"]["13"]["bead_sensitivity_Wb_per_N"])
    # beads 9..17 mirror about bead 13: S and the magnetic forces are (anti)symmetric
    # up to the asymmetry of the unstructured mesh
    assert np.allclose(s, s[::-1], rtol=0.02, atol=0.02 * np.max(np.abs(s)))
    f = tr.magnetic_particle_force[8:17]
    assert np.allclose(f, -f[::-1], atol=0.02 * np.max(np.abs(f)))
    # beads are pulled toward the magnet's centre: down above it, up below it
    assert f[2] > 0 > f[-3]
    # compression of the bead under the coil lowers |M| below the Villari reversal
    assert s[4] > 0
    assert tr.resistance_ohm > 0 and tr.inductance_H > 0


def test_magnet_disabled_gives_no_signal(mesh_dir):
    rep = compute_transducers(one_sensor(magnet=False), options=COARSE,
                              store=Store.at(mesh_dir))
    tr = rep.transducers[13]
    assert np.all(tr.sensitivity_villari == 0.0)
    assert np.all(tr.dlambda_dapproach == 0.0)
    assert np.all(tr.magnetic_particle_force == 0.0)
    t = np.linspace(0, 1e-4, 50)
    force = np.outer(np.sin(3e4 * t), np.ones(20)) * 50.0 + 2.0
    assert np.all(emf(tr, t, force) == 0.0)


def test_emf_is_linear_in_force_rate(report):
    tr = report.transducers[13]
    t = np.linspace(0.0, 2e-4, 401)
    rates = np.linspace(1e4, 3e4, 20)  # N/s, one per chain contact 1..20
    force = 2.0 + np.outer(t, rates)
    v = emf(tr, t, force, mechanism="villari")
    expected = -np.sum(tr.sensitivity_villari * rates[tr.contacts - 1])
    assert np.allclose(v, expected, rtol=1e-12)
    assert np.allclose(emf(tr, t, 2.0 + 3.0 * np.outer(t, rates), mechanism="villari"),
                       3.0 * v, rtol=1e-12)
    # constant forces give nothing, whatever the mechanism
    assert np.allclose(emf(tr, t, np.full((t.size, 20), 5.0)), 0.0)
    # for small pulses about the reference load the approach EMF is the linearised one
    f0 = tr.reference_force
    small = f0 + 1e-3 * np.outer(np.sin(2e4 * t), np.ones(20))
    lin = -np.gradient(small[:, tr.contacts - 1], t, axis=0) @ tr.sensitivity_approach
    exact = emf(tr, t, small, mechanism="approach")
    assert np.allclose(exact, lin, rtol=1e-3, atol=1e-3 * np.max(np.abs(lin)))
    # both mechanisms add
    assert np.allclose(emf(tr, t, small), emf(tr, t, small, mechanism="villari") + exact)


def test_emf_rejects_bad_input(report):
    tr = report.transducers[13]
    t = np.linspace(0, 1, 5)
    with pytest.raises(InputError, match="shape"):
        emf(tr, t, np.zeros((4, 20)))
    with pytest.raises(InputError, match="increasing"):
        emf(tr, t[::-1], np.zeros((5, 20)))
    with pytest.raises(InputError, match="mechanism"):
        emf(tr, t, np.zeros((5, 20)), mechanism="magic")


def _fake(source: str, force: np.ndarray) -> Transducer:
    return Transducer(particle=13, contacts=np.array([12, 13]),
                      sensitivity_villari=np.zeros(2), dlambda_dapproach=np.zeros(2),
                      contact_stiffness=1e10, reference_force=1.0,
                      magnetic_particle_force=force, resistance_ohm=1.0, inductance_H=1e-3,
                      turns=10, source=source)


def test_magnetic_precompression_counts_each_model_once():
    a = np.arange(5.0)
    same = magnetic_precompression({13: _fake("m1", a), 18: _fake("m1", a)})
    assert same.tolist() == a.tolist()
    both = magnetic_precompression([_fake("m1", a), _fake("m2", 2 * a)])
    assert both.tolist() == (3 * a).tolist()
    with pytest.raises(InputError):
        magnetic_precompression([_fake("m1", a), _fake("m2", np.zeros(4))])
    with pytest.raises(InputError):
        magnetic_precompression({})


def test_cache_round_trip(tmp_path, mesh_dir, caplog):
    g = one_sensor()
    store = Store.at(tmp_path, committed=[mesh_dir])  # the mesh is the fixture's
    first = transducer_report(g, options=COARSE, store=store)
    files = list(tmp_path.glob("transducer-*.json"))
    assert len(files) == 1
    again = transducers_for(g, options=COARSE, store=store)
    a, b = first.transducers[13], again[13]
    for name in ("contacts", "sensitivity_villari", "dlambda_dapproach",
                 "magnetic_particle_force"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert (a.inductance_H, a.source, a.contact_stiffness, a.reference_force) == \
        (b.inductance_H, b.source, b.contact_stiffness, b.reference_force)
    # a file that is not what the store wrote is computed again, with a warning
    files[0].write_text(json.dumps({"schema": "other"}))
    with caplog.at_level("WARNING", logger="msens.store"):
        third = transducers_for(g, options=COARSE, store=store)
    assert "no checksum" in caplog.text and files[0].name in caplog.text
    assert third[13].inductance_H == a.inductance_H
    assert json.loads(files[0].read_text())["schema"] == "msens.transducers/3"
    # a different stress force is a different cache entry
    transducers_for(g, options=COARSE, store=store, stress_force=5.0, approach=False)
    assert len(list(tmp_path.glob("transducer-*.json"))) == 2


def test_bad_stress_force(mesh_dir):
    with pytest.raises(InputError, match="stress_force"):
        compute_transducers(one_sensor(), options=COARSE, store=Store.at(mesh_dir),
                            stress_force=-1.0, approach=False)

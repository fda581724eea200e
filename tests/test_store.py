"""The artifact store: lookup order, checksums, rebuilds of bad files, the size bound."""

from __future__ import annotations

import json
import os
import pickle
import shutil
from pathlib import Path

import pytest

from msens import store as store_module
from msens.config.fieldsetup import geometry_from_study
from msens.field import cache as field_cache
from msens.field.build import MeshOptions
from msens.field.geometry import AirBox, BeadChain, SensorGeometry
from msens.field.parts import BiasMagnet, Coil, SensorUnit
from msens.magnetics import transducer_cache
from msens.magnetics.steel_law import law_for_steel
from msens.magnetics.transducer import cache_key
from msens.params.materials import BEAD_STEEL
from msens.store import CHECKSUM, FILE_CHECKSUM, Store, committed_dirs, stamp

LOG = "msens.store"


def _small() -> SensorGeometry:
    """One sensor at particle 13, beads 12..14: meshes in a fraction of a second."""
    return SensorGeometry(beads=BeadChain(first=12, last=14),
                          sensors=(SensorUnit(Coil(13), BiasMagnet(13)),),
                          air=AirBox(0.05, 0.03))


def test_json_round_trip_carries_its_checksum(tmp_path):
    s = Store.at(tmp_path)
    payload = {"a": [0.1, 1e-300, -0.0, 3], "b": {"c": "x"}}
    path = s.write_json("thing-1.json", payload)
    on_disk = json.loads(path.read_text())
    assert set(on_disk) == {"a", "b", CHECKSUM}
    assert s.read_json("thing-1.json") == payload
    assert s.read_json("absent.json") is None


@pytest.mark.parametrize("damage", ["altered", "truncated", "no checksum", "not json",
                                    "not an object"])
def test_a_bad_json_artifact_is_never_used(tmp_path, caplog, damage):
    s = Store.at(tmp_path)
    path = s.write_json("thing-1.json", {"peak_V": 0.70, "n": [1, 2, 3]})
    text = path.read_text()
    if damage == "altered":  # still valid JSON with its old checksum
        path.write_text(text.replace("0.7", "2.44"))
    elif damage == "truncated":
        path.write_text(text[: len(text) // 2])
    elif damage == "no checksum":
        path.write_text(json.dumps({"peak_V": 0.70, "n": [1, 2, 3]}))
    elif damage == "not json":
        path.write_bytes(b"\xff\xfe\x00garbage")
    else:
        path.write_text("[1, 2]")
    with caplog.at_level("WARNING", logger=LOG):
        assert s.read_json("thing-1.json") is None
    assert "thing-1.json" in caplog.text and "not used" in caplog.text


def test_committed_folders_come_first_and_are_never_written(tmp_path, caplog):
    committed, user = tmp_path / "committed", tmp_path / "user"
    Store.at(committed).write_json("a.json", {"v": 1})
    s = Store(user, (committed,))
    assert s.read_json("a.json") == {"v": 1}
    s.write_json("a.json", {"v": 2})  # goes to the user cache
    assert s.read_json("a.json") == {"v": 1}
    assert json.loads((committed / "a.json").read_text())["v"] == 1
    # a corrupted committed artifact is skipped for the user cache's valid one
    (committed / "a.json").write_text('{"v": 3, "sha256": "0"}')
    with caplog.at_level("WARNING", logger=LOG):
        assert s.read_json("a.json") == {"v": 2}
    assert str(committed / "a.json") in caplog.text
    assert (committed / "a.json").read_text() == '{"v": 3, "sha256": "0"}'


def test_alternative_names_are_tried_per_folder(tmp_path):
    committed, user = tmp_path / "committed", tmp_path / "user"
    Store.at(committed).write_json("all.json", {"which": "all"})
    Store.at(user).write_json("some.json", {"which": "some"})
    s = Store(user, (committed,))
    # the committed folder's full table before the user cache's own subset
    assert s.read_json("some.json", "all.json") == {"which": "all"}


def test_file_artifacts_are_verified_through_their_sidecar(tmp_path, caplog):
    s = Store.at(tmp_path)
    path = s.write_file("blob-1.bin", lambda t: t.write_bytes(b"0123456789" * 100),
                        meta={"key": "1"})
    side = json.loads(path.with_suffix(".json").read_text())
    assert side["key"] == "1" and FILE_CHECKSUM in side and CHECKSUM in side
    assert s.find_file("blob-1.bin") == path
    path.write_bytes(b"0123456789" * 50)  # truncated
    with caplog.at_level("WARNING", logger=LOG):
        assert s.find_file("blob-1.bin") is None
    assert "truncated" in caplog.text
    s.write_file("blob-1.bin", lambda t: t.write_bytes(b"x"))
    path.with_suffix(".json").unlink()
    assert s.find_file("blob-1.bin") is None  # no sidecar: unverified


def test_a_truncated_mesh_is_rebuilt_with_a_warning(tmp_path, caplog):
    s = Store.at(tmp_path)
    g = _small()
    path = field_cache.cached_mesh(g, store=s)
    good = path.read_bytes()
    path.write_bytes(good[: len(good) // 3])
    with caplog.at_level("WARNING", logger=LOG):
        again = field_cache.cached_mesh(g, store=s)
    assert again == path and "not used" in caplog.text
    assert again.read_bytes() == good  # gmsh writes the same mesh again
    from msens.field.sensor_model import load_mesh

    axi, _ = load_mesh(g, store=s)  # and it reads
    assert "bead_13" in axi.subdomains


def test_an_old_mesh_without_checksum_is_rebuilt(tmp_path, caplog, monkeypatch):
    s = Store.at(tmp_path)
    g = _small()
    path = field_cache.cached_mesh(g, store=s)
    side = path.with_suffix(".json")
    meta = json.loads(side.read_text())
    del meta[FILE_CHECKSUM], meta[CHECKSUM]
    side.write_text(json.dumps(meta))  # as msens wrote it before the store
    built = []
    real = field_cache.build_mesh
    monkeypatch.setattr(field_cache, "build_mesh", lambda *a: built.append(1) or real(*a))
    with caplog.at_level("WARNING", logger=LOG):
        field_cache.cached_mesh(g, store=s)
    assert built == [1] and "no checksum" in caplog.text
    field_cache.cached_mesh(g, store=s)
    assert built == [1]  # now verified


def _main_study_transducers():
    from msens.api import load_default

    g = geometry_from_study(load_default())
    key = cache_key(g, stress_force=g.beads.contact_load, law=law_for_steel(g.steel),
                    material=BEAD_STEEL, approach=True)
    name = f"transducer-{key}.json"
    committed = next(d / name for d in committed_dirs() if (d / name).is_file())
    return g, name, committed


def test_a_transducer_file_with_altered_numbers_is_rebuilt_not_used(tmp_path, caplog,
                                                                     monkeypatch):
    """Issue 38: a transducer artifact that is valid JSON with altered numbers (the coil's
    inductance and sensitivities x 3.5) is computed again, never read."""
    g, name, committed = _main_study_transducers()
    s = Store.at(tmp_path)
    shutil.copy(committed, tmp_path / name)
    pristine = Store.at(committed.parent).read_json(name)
    calls = []

    def compute(geometry, **kwargs):  # stands in for the minute of field solves
        calls.append(geometry)
        return transducer_cache._from_json(pristine)

    monkeypatch.setattr(transducer_cache, "compute_transducers", compute)
    nominal = transducer_cache.transducers_for(g, store=s)
    assert calls == []  # the valid copy is read
    data = json.loads((tmp_path / name).read_text())
    tr = data["transducers"]["13"]
    tr["inductance_H"] *= 3.5
    tr["dLambda_dapproach_Wb_per_m"] = [3.5 * v for v in tr["dLambda_dapproach_Wb_per_m"]]
    (tmp_path / name).write_text(json.dumps(data, indent=1))
    with caplog.at_level("WARNING", logger=LOG):
        again = transducer_cache.transducers_for(g, store=s)
    assert len(calls) == 1 and "corrupted or altered" in caplog.text
    assert again[13].inductance_H == nominal[13].inductance_H
    assert (again[13].dlambda_dapproach == nominal[13].dlambda_dapproach).all()
    assert s.read_json(name) == pristine  # rewritten valid
    # truncated: rebuilt too, not a "delete it" error
    text = (tmp_path / name).read_text()
    (tmp_path / name).write_text(text[:1000])
    transducer_cache.transducers_for(g, store=s)
    assert len(calls) == 2


def test_the_committed_artifacts_verify():
    here = [d for d in committed_dirs() if any(d.glob("transducer-*.json"))]
    assert here, "no committed artifacts found"
    s = Store.at(here[0].parent / "unused", committed=[here[0]])
    names = sorted(p.name for p in here[0].iterdir())
    files = (".msh", ".npz")  # file artifacts (meshes, coil tables): a JSON sidecar each
    for n in names:
        if n.endswith(files):
            assert s.find_file(n) == here[0] / n, n
        elif not any((here[0] / n).with_suffix(x).exists() for x in files):
            assert s.read_json(n) is not None, n


def test_stamp_adds_checksums_without_changing_content(tmp_path):
    data = {"schema": "x", "values": [0.1, 0.2]}
    (tmp_path / "t-1.json").write_text(json.dumps(data, indent=1))
    (tmp_path / "m-1.msh").write_bytes(b"mesh")
    meta = {"key": "1", "geometry": {"a": "0.1"}}
    (tmp_path / "m-1.json").write_text(json.dumps(meta, indent=1, sort_keys=True))
    s = Store.at(tmp_path)
    assert s.read_json("t-1.json") is None and s.find_file("m-1.msh") is None
    changed = stamp(sorted(tmp_path.iterdir()))
    assert sorted(p.name for p in changed) == ["m-1.json", "t-1.json"]
    assert s.read_json("t-1.json") == data
    assert s.find_file("m-1.msh") == tmp_path / "m-1.msh"
    assert stamp(sorted(tmp_path.iterdir())) == []  # once
    text = (tmp_path / "t-1.json").read_text()
    assert text.startswith(json.dumps(data, indent=1)[:-2])  # the old lines kept


def test_the_user_cache_is_bounded_least_recently_used_first(tmp_path):
    s = Store(tmp_path, (), max_bytes=2500)
    t0 = 1_000_000_000
    for i in range(3):
        s.write_json(f"a-{i}.json", {"x": "y" * 1000})
        for p in tmp_path.glob(f"a-{i}.*"):
            os.utime(p, (t0 + i, t0 + i))
    assert len(list(tmp_path.glob("a-*.json"))) == 2  # the third write evicted a-0
    assert not (tmp_path / "a-0.json").exists()
    assert s.read_json("a-1.json") is not None  # a-1 is now the most recently used
    s.write_json("a-3.json", {"x": "y" * 1000})
    assert sorted(p.name for p in tmp_path.glob("a-*.json")) == ["a-1.json", "a-3.json"]
    assert s.size() <= 2500
    # a file and its sidecar go together; the one just written stays even if too big
    s.write_file("m-1.msh", lambda t: t.write_bytes(b"z" * 5000))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m-1.json", "m-1.msh"]


def test_unbounded_stores_and_committed_folders_are_never_trimmed(tmp_path):
    s = Store.at(tmp_path)  # max_bytes None
    for i in range(5):
        s.write_json(f"r-{i}.json", {"x": "y" * 1000})
    assert len(list(tmp_path.iterdir())) == 5
    small = Store(tmp_path / "user", (tmp_path,), max_bytes=0)
    small.write_json("n.json", {})
    assert len(list(tmp_path.glob("r-*.json"))) == 5


def test_the_default_bound_comes_from_the_environment(monkeypatch):
    monkeypatch.setenv("MSENS_CACHE_MAX_BYTES", "12345")
    monkeypatch.setenv("MSENS_MESH_DIR", "/tmp/msens-test-cache")
    s = Store.default()
    assert s.max_bytes == 12345 and str(s.directory) == "/tmp/msens-test-cache"
    assert s.search[-1] == s.directory
    monkeypatch.setenv("MSENS_CACHE_MAX_BYTES", "lots")
    from msens.errors import InputError

    with pytest.raises(InputError, match="MSENS_CACHE_MAX_BYTES"):
        Store.default()
    monkeypatch.delenv("MSENS_CACHE_MAX_BYTES")
    assert Store.default().max_bytes == store_module.DEFAULT_MAX_BYTES


def test_a_store_travels_to_workers(tmp_path):
    s = Store(tmp_path, (tmp_path / "c",), 10)
    assert pickle.loads(pickle.dumps(s)) == s


def test_no_module_level_cache_state():
    """The caches keep nothing at module level (the store is a value; the diagnosis's field
    models belong to its run): no private module-level dict, set or list, no lru_cache."""
    import ast

    from msens.design import cache as design_cache
    from msens.diagnose import models, physics
    from msens.magnetics import contact_map, dynamic

    mutable = (ast.Dict, ast.DictComp, ast.Set, ast.List)
    for mod in (store_module, field_cache, transducer_cache, dynamic, contact_map,
                design_cache, physics, models):
        tree = ast.parse(Path(mod.__file__).read_text(encoding="utf-8"))
        for node in tree.body:
            if isinstance(node, ast.Assign | ast.AnnAssign) and node.value is not None:
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names = [t.id for t in targets if isinstance(t, ast.Name)]
                assert not (isinstance(node.value, mutable)
                            and any(n.startswith("_") and not n.startswith("__") for n in names)), \
                    f"{mod.__name__}: module-level {names}"
            if isinstance(node, ast.FunctionDef):
                text = " ".join(ast.unparse(d) for d in node.decorator_list)
                assert "cache" not in text, f"{mod.__name__}.{node.name}: {text}"


def test_each_diagnosis_context_owns_its_field_models(monkeypatch):
    from msens.api import load_default
    from msens.diagnose import models, physics
    from msens.diagnose.effects.base import Context

    calls = []

    def fake(geometry, **kwargs):
        calls.append(kwargs)
        return {13: "t13", 18: "t18"}

    monkeypatch.setattr(models, "transducers_for", fake)
    study = load_default()
    a, b = Context(study, study.setups[0]), Context(study, study.setups[0])
    pa, pb = physics.setup_physics(a), physics.setup_physics(b)
    assert len(calls) == 2  # one registration per run
    assert physics.setup_physics(a)[0].model is pa[0].model  # kept within a run
    assert len(calls) == 2
    assert pa[0].model is not pb[0].model
    assert physics.transducers(pa[0].model) == {13: "t13", 18: "t18"}
    assert isinstance(calls[0]["store"], Store)


def test_mesh_options_enter_the_key():
    g = _small()
    assert field_cache.mesh_name(g) != field_cache.mesh_name(g, MeshOptions(bead_size=3e-4))


def test_a_cache_that_cannot_be_written(tmp_path, caplog):
    """A read-only cache: an optional write (a value the caller holds) warns, a required one
    names the file and the folder."""
    from msens.errors import InputError

    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    s = Store.at(blocker / "cache")
    with caplog.at_level("WARNING", logger=LOG):
        assert s.write_json("a.json", {"v": 1}, optional=True) is None
    assert "used but not kept" in caplog.text
    with pytest.raises(InputError, match=r"a\.json.*make that folder writable"):
        s.write_json("a.json", {"v": 1})


def test_design_results_are_verified_and_never_evicted(tmp_path, caplog):
    from msens.design.cache import ResultCache, content_key

    cache = ResultCache(tmp_path / "cache")
    assert cache.store.max_bytes is None  # a resumed sweep needs every result
    key = content_key("design", 1)
    cache.put(key, {"peak_voltage_V": 0.70, "status": "ok"})
    assert cache.get(key) == {"peak_voltage_V": 0.70, "status": "ok"}
    path = cache.path(key)
    path.write_text(path.read_text().replace("0.7", "2.44"))
    with caplog.at_level("WARNING", logger=LOG):
        assert cache.get(key) is None  # the runner computes the design again
    assert key in caplog.text

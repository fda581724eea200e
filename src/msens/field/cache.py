"""Mesh artifacts: one gmsh ``.msh`` per geometry in the artifact store, keyed by content.

The key is :func:`msens.store.content_key` of the canonical JSON of the geometry and the mesh
options (plus :data:`BUILDER_VERSION`, bumped whenever :mod:`msens.field.build` changes what it
writes), so a changed dimension gives a new mesh and an unchanged one reuses the old one. The
store (:class:`msens.store.Store`) finds it among the committed artifacts or in the user cache,
verifies it against the checksum in its sidecar ``sensor-<key>.json`` (which also records the
geometry) and writes a new one atomically.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from msens.field.build import MeshOptions, build_mesh
from msens.field.geometry import SensorGeometry
from msens.io import hashing
from msens.store import Store, content_key

#: Version of the mesh builder's output; part of every cache key.
BUILDER_VERSION = "sensor-mesh/3"


def _mesh_relevant(f: dataclasses.Field, value: object) -> bool:
    # Materials (metadata mesh=False) leave the mesh unchanged; options added later are left
    # out at their default value, so existing meshes keep their keys.
    return f.metadata.get("mesh", True) and not (f.metadata.get("omit_if_default")
                                                 and value == f.default)


def canonical(obj: object) -> object:
    """:func:`msens.io.hashing.canonical` of what a mesh depends on.

    Dataclass fields with ``metadata={"mesh": False}`` (materials, such as
    :attr:`SensorGeometry.steel`) are left out: the mesh does not depend on them. Fields with
    ``metadata={"omit_if_default": True}`` are left out at their default value (options added
    later keep the keys of existing meshes).
    """
    return hashing.canonical(obj, _mesh_relevant)


def geometry_key(geometry: SensorGeometry, options: MeshOptions | None = None) -> str:
    """Content hash (16 hex digits) of a geometry and its mesh options."""
    return content_key({"builder": BUILDER_VERSION, "geometry": canonical(geometry),
                        "options": canonical(options or MeshOptions())}, 16)


def mesh_name(geometry: SensorGeometry, options: MeshOptions | None = None) -> str:
    """The mesh's artifact name, ``sensor-<key>.msh``."""
    return f"sensor-{geometry_key(geometry, options)}.msh"


def cached_mesh(geometry: SensorGeometry, options: MeshOptions | None = None,
                store: Store | None = None) -> Path:
    """Path of the mesh of ``geometry``, building it first when the store has no valid one.

    Parameters
    ----------
    geometry : SensorGeometry
    options : MeshOptions, optional
    store : Store, optional
        Where meshes are found and written (default :meth:`msens.store.Store.default`: the
        committed meshes, then the user cache).

    Returns
    -------
    Path
        ``sensor-<key>.msh``; the sidecar ``sensor-<key>.json`` beside it records the
        geometry and the mesh's checksum.
    """
    store = Store.default() if store is None else store
    options = options or MeshOptions()
    name = mesh_name(geometry, options)
    path = store.find_file(name)
    if path is not None:
        return path
    key = geometry_key(geometry, options)
    meta = {"key": key, "builder": BUILDER_VERSION, "geometry": canonical(geometry),
            "options": canonical(options)}
    return store.write_file(name, lambda tmp: build_mesh(geometry, str(tmp), options), meta)

"""Mesh cache: one ``.msh`` per geometry, keyed by a content hash.

The key is a SHA-256 of the canonical JSON of the geometry and the mesh options (plus
:data:`BUILDER_VERSION`, bumped whenever :mod:`msens.field.build` changes what it writes), so a
changed dimension gives a new file and an unchanged one reuses the old mesh. Files are written
atomically (temporary file in the same directory, then :func:`os.replace`), so a crashed or
concurrent run never leaves a half-written mesh under a valid name.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
from pathlib import Path

from msens.field.build import MeshOptions, build_mesh
from msens.field.geometry import SensorGeometry
from msens.io import hashing
from msens.io.atomic import atomic_write, atomic_write_text, clean_stale

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
    return hashing.content_hash({"builder": BUILDER_VERSION, "geometry": canonical(geometry),
                                 "options": canonical(options or MeshOptions())}, 16)


def committed_mesh_dirs() -> list[Path]:
    """Folders searched for an existing mesh before one is built: ``$MSENS_MESH_DIR``,
    ``./meshes``, the source checkout's ``meshes/`` (the project commits the meshes of its
    default studies there, so a fresh clone needs no meshing) and their installed copy
    (``<prefix>/share/msens/meshes``, so an installed msens finds them from any folder)."""
    dirs = []
    env = os.environ.get("MSENS_MESH_DIR")
    if env:
        dirs.append(Path(env))
    dirs.append(Path.cwd() / "meshes")
    dirs.append(Path(__file__).resolve().parents[3] / "meshes")
    dirs.append(Path(sys.prefix) / "share" / "msens" / "meshes")
    return dirs


def default_mesh_dir() -> Path:
    """Where new meshes are written: ``$MSENS_MESH_DIR``, else the user cache
    (``$XDG_CACHE_HOME/msens/meshes``, default ``~/.cache/msens/meshes``) — never the
    project's committed ``meshes/``, which changes only by a deliberate commit."""
    env = os.environ.get("MSENS_MESH_DIR")
    if env:
        return Path(env)
    cache = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(cache) / "msens" / "meshes"


def cached_mesh(geometry: SensorGeometry, options: MeshOptions | None = None,
                directory: str | Path | None = None) -> Path:
    """Path of the mesh of ``geometry``, building it first when absent.

    Parameters
    ----------
    geometry : SensorGeometry
    options : MeshOptions, optional
    directory : str or Path, optional
        Cache directory (created if needed); default: an existing mesh in
        :func:`committed_mesh_dirs`, else built into :func:`default_mesh_dir`.

    Returns
    -------
    Path
        ``<directory>/sensor-<key>.msh``; a ``.json`` beside it records the geometry.
    """
    options = options or MeshOptions()
    key = geometry_key(geometry, options)
    name = f"sensor-{key}.msh"
    if directory is None:
        for d in committed_mesh_dirs():
            if (d / name).is_file():
                return d / name
    directory = Path(directory) if directory is not None else default_mesh_dir()
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    if path.is_file():
        return path
    clean_stale(directory)  # the temporary files of builds that were killed
    atomic_write(path, lambda tmp: build_mesh(geometry, str(tmp), options))
    meta = {"key": key, "builder": BUILDER_VERSION, "geometry": canonical(geometry),
            "options": canonical(options)}
    atomic_write_text(path.with_suffix(".json"), json.dumps(meta, indent=1, sort_keys=True))
    return path

"""Mesh cache: one ``.msh`` per geometry, keyed by a content hash.

The key is a SHA-256 of the canonical JSON of the geometry and the mesh options (plus
:data:`BUILDER_VERSION`, bumped whenever :mod:`msens.field.build` changes what it writes), so a
changed dimension gives a new file and an unchanged one reuses the old mesh. Files are written
atomically (temporary file in the same directory, then :func:`os.replace`), so a crashed or
concurrent run never leaves a half-written mesh under a valid name.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import tempfile
from pathlib import Path

from msens.field.build import MeshOptions, build_mesh
from msens.field.geometry import SensorGeometry

#: Version of the mesh builder's output; part of every cache key.
BUILDER_VERSION = "sensor-mesh/3"


def _canonical(obj: object) -> object:
    """JSON-ready form of nested frozen dataclasses (floats by repr, exact)."""
    if dataclasses.is_dataclass(obj):
        return {"__type__": type(obj).__name__,
                **{f.name: _canonical(getattr(obj, f.name)) for f in dataclasses.fields(obj)}}
    if isinstance(obj, tuple | list):
        return [_canonical(v) for v in obj]
    if isinstance(obj, float):
        return repr(obj)
    return obj


def geometry_key(geometry: SensorGeometry, options: MeshOptions | None = None) -> str:
    """Content hash (16 hex digits) of a geometry and its mesh options."""
    payload = {"builder": BUILDER_VERSION, "geometry": _canonical(geometry),
               "options": _canonical(options or MeshOptions())}
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def default_mesh_dir() -> Path:
    """Where meshes live: ``$MSENS_MESH_DIR``, else the project's ``meshes/`` (source
    checkout), else ``./.msens-cache/meshes``."""
    env = os.environ.get("MSENS_MESH_DIR")
    if env:
        return Path(env)
    project = Path(__file__).resolve().parents[3] / "meshes"
    if project.is_dir() and os.access(project, os.W_OK):
        return project
    return Path.cwd() / ".msens-cache" / "meshes"


def _atomic_write_text(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def cached_mesh(geometry: SensorGeometry, options: MeshOptions | None = None,
                directory: str | Path | None = None) -> Path:
    """Path of the mesh of ``geometry``, building it first when absent.

    Parameters
    ----------
    geometry : SensorGeometry
    options : MeshOptions, optional
    directory : str or Path, optional
        Cache directory (created if needed); default :func:`default_mesh_dir`.

    Returns
    -------
    Path
        ``<directory>/sensor-<key>.msh``; a ``.json`` beside it records the geometry.
    """
    options = options or MeshOptions()
    directory = Path(directory) if directory is not None else default_mesh_dir()
    directory.mkdir(parents=True, exist_ok=True)
    key = geometry_key(geometry, options)
    path = directory / f"sensor-{key}.msh"
    if path.is_file():
        return path
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".sensor-{key}.", suffix=".msh")
    os.close(fd)
    try:
        build_mesh(geometry, tmp, options)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    meta = {"key": key, "builder": BUILDER_VERSION, "geometry": _canonical(geometry),
            "options": _canonical(options)}
    _atomic_write_text(path.with_suffix(".json"), json.dumps(meta, indent=1, sort_keys=True))
    return path

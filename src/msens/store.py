"""The one artifact store: meshes, transducers, frequency responses, contact maps, results.

Everything msens computes once and reads again (field meshes, transducer sets, eddy-current
frequency responses, contact maps, design-sweep results) lives in a :class:`Store`:

- **Where.** An artifact is looked up in the committed folders first (the project commits the
  artifacts of its default studies to ``meshes/`` in the checkout; an installed msens has them
  in ``<prefix>/share/msens/meshes``), then in the store's own folder, the user cache
  (``$MSENS_MESH_DIR``, else ``$XDG_CACHE_HOME/msens/meshes``, default
  ``~/.cache/msens/meshes``). New artifacts are written to the user cache only: a committed
  folder changes only by a deliberate commit.
- **Keyed by content.** Its name holds :func:`content_key` of everything it depends on (the
  canonical JSON of the inputs and the code's version, :mod:`msens.io.hashing`), so equal
  inputs find it in any process and on any machine, and a changed input gives a new name.
- **Written atomically** (:func:`msens.io.atomic.atomic_write`): a reader sees the old file
  or the new one, never half of one, even after a crash.
- **Verified when read.** A JSON artifact carries the SHA-256 of its own content under
  :data:`CHECKSUM` (of its canonical JSON text without that key, so formatting does not
  matter); any other file (a gmsh mesh) has a JSON sidecar ``<stem>.json`` that carries the
  SHA-256 of the file's bytes under :data:`FILE_CHECKSUM` (and its own checksum). A file that
  does not parse, has no checksum (written before msens checked them) or fails it (truncated,
  corrupted, numbers altered) is never used: a warning on the ``msens.store`` logger names
  it, and the caller computes the artifact again, which replaces it in the user cache.
  The keys hash the inputs, not the outputs, so an artifact without a checksum cannot be
  verified by recomputing its key: it is rebuilt.
- **Bounded.** After every write the user cache is trimmed to ``max_bytes``
  (:data:`DEFAULT_MAX_BYTES`, or ``$MSENS_CACHE_MAX_BYTES``), the least recently used
  artifacts first (a read marks an artifact used). An artifact and its sidecar go together;
  the one just written is kept even if it alone is larger than the bound.

A store is a small frozen value (folders and a bound): it pickles, so worker processes and
Dask tasks receive the store of the workflow that started them.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from msens.errors import InputError, internal
from msens.io.atomic import TEMP_MARK, atomic_write, atomic_write_bytes, clean_stale
from msens.io.hashing import FieldFilter, content_hash

_log = logging.getLogger(__name__)

#: Key of a JSON artifact's own checksum (SHA-256 hex of its other content).
CHECKSUM = "sha256"
#: Key, in a file's JSON sidecar, of the SHA-256 hex of the file's bytes.
FILE_CHECKSUM = "file_sha256"
#: Default bound of the user cache, bytes (2 GiB: a few hundred meshes with their
#: transducers; the default studies' artifacts take about 6 MB).
DEFAULT_MAX_BYTES = 2 * 1024**3
#: Environment variable that overrides :data:`DEFAULT_MAX_BYTES` (a whole number of bytes).
MAX_BYTES_ENV = "MSENS_CACHE_MAX_BYTES"
#: Environment variable naming the user cache folder.
DIR_ENV = "MSENS_MESH_DIR"


def content_key(obj: Any, digits: int | None = None, include: FieldFilter | None = None
                ) -> str:
    """The one cache key of msens: SHA-256 (hex) of the canonical JSON of ``obj``.

    Parameters
    ----------
    obj : any
        Everything the artifact depends on (:func:`msens.io.hashing.canonical`), including
        the version of the code that computes it.
    digits : int, optional
        Keep the first ``digits`` hex digits (default: all 64).
    include : callable, optional
        ``include(field, value)``: which dataclass fields enter (default: all).

    Returns
    -------
    str
    """
    return content_hash(obj, digits, include)


def committed_dirs() -> tuple[Path, ...]:
    """Folders of committed artifacts, searched first: ``./meshes``, the source checkout's
    ``meshes/`` and its installed copy ``<prefix>/share/msens/meshes`` (duplicates once)."""
    dirs = [Path.cwd() / "meshes", Path(__file__).resolve().parents[2] / "meshes",
            Path(sys.prefix) / "share" / "msens" / "meshes"]
    out: list[Path] = []
    for d in dirs:
        if d not in out:
            out.append(d)
    return tuple(out)


def user_cache_dir() -> Path:
    """Where new artifacts are written: ``$MSENS_MESH_DIR``, else
    ``$XDG_CACHE_HOME/msens/meshes`` (default ``~/.cache/msens/meshes``)."""
    env = os.environ.get(DIR_ENV)
    if env:
        return Path(env)
    cache = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(cache) / "msens" / "meshes"


def default_max_bytes() -> int:
    """``$MSENS_CACHE_MAX_BYTES`` if set, else :data:`DEFAULT_MAX_BYTES`.

    Raises
    ------
    InputError
        The variable is not a whole number of bytes >= 0.
    """
    env = os.environ.get(MAX_BYTES_ENV)
    if env is None or not env.strip():
        return DEFAULT_MAX_BYTES
    try:
        value = int(env.strip())
    except ValueError:
        value = -1
    if value < 0:
        raise InputError(f"${MAX_BYTES_ENV} must be a whole number of bytes >= 0, "
                         f"got {env[:40]!r}")
    return value


def json_checksum(payload: dict) -> str:
    """SHA-256 (hex) of the canonical JSON text of ``payload`` without :data:`CHECKSUM`
    (sorted keys, no spaces; floats as Python writes them, which round-trip exactly)."""
    rest = {k: v for k, v in payload.items() if k != CHECKSUM}
    text = json.dumps(rest, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def file_checksum(path: Path) -> str:
    """SHA-256 (hex) of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _sidecar(name: str) -> str:
    return Path(name).with_suffix(".json").name


def _group(name: str) -> str:
    # an artifact and its sidecar share the name up to the first dot
    return name.split(".", 1)[0]


class _Unverified(Exception):
    """An artifact that exists but cannot be trusted (the reason is the message)."""


@dataclass(frozen=True)
class Store:
    """Committed folders (read only) and a user cache folder (read and written).

    Parameters
    ----------
    directory : Path
        The user cache: searched after ``committed``; new artifacts are written here
        (created on the first write).
    committed : tuple of Path
        Read-only folders searched first, in order.
    max_bytes : int or None
        Bound of ``directory``'s total size in bytes, enforced after every write by evicting
        the least recently used artifacts; None: unbounded (e.g. a design sweep's results,
        which a resumed sweep needs).
    """

    directory: Path
    committed: tuple[Path, ...] = ()
    max_bytes: int | None = DEFAULT_MAX_BYTES

    def __post_init__(self) -> None:
        object.__setattr__(self, "directory", Path(self.directory))
        object.__setattr__(self, "committed", tuple(Path(d) for d in self.committed))
        internal(self.max_bytes is None or self.max_bytes >= 0,
                 f"internal: Store.max_bytes must be >= 0, got {self.max_bytes!r}")

    @classmethod
    def default(cls) -> Store:
        """The committed folders (:func:`committed_dirs`) and the user cache
        (:func:`user_cache_dir`, bounded by :func:`default_max_bytes`)."""
        return cls(user_cache_dir().resolve(), committed_dirs(), default_max_bytes())

    @classmethod
    def at(cls, directory: str | os.PathLike[str], max_bytes: int | None = None,
           committed: Iterable[str | os.PathLike[str]] = ()) -> Store:
        """A store that writes to ``directory`` (made absolute) and reads ``committed``
        first; unbounded unless ``max_bytes``."""
        return cls(Path(directory).resolve(), tuple(Path(d) for d in committed), max_bytes)

    @property
    def search(self) -> tuple[Path, ...]:
        """Folders searched, in order: the committed ones, then :attr:`directory`."""
        return (*(d for d in self.committed if d != self.directory), self.directory)

    def path(self, name: str) -> Path:
        """Where an artifact named ``name`` is written (in :attr:`directory`)."""
        internal("/" not in name and name not in ("", ".", ".."),
                 f"internal: an artifact name is a plain file name, got {name!r}")
        return self.directory / name

    # ------------------------------------------------------------------- JSON artifacts

    def read_json(self, name: str, *alternatives: str) -> dict | None:
        """The verified content of JSON artifact ``name`` (without its checksum), from the
        first folder of :attr:`search` that holds a valid one; None if none does (an invalid
        one is reported on the ``msens.store`` logger and skipped). ``alternatives``: other
        names that serve too, tried after ``name`` in each folder."""
        for d in self.search:
            for n in (name, *alternatives):
                path = d / n
                if not path.is_file():
                    continue
                try:
                    payload = self._verified_json(path)
                except _Unverified as exc:
                    self._reject(path, str(exc))
                    continue
                self._used(path)
                _log.debug("%s: verified", path)
                return payload
        return None

    def write_json(self, name: str, payload: dict, *, indent: int | None = 1,
                   optional: bool = False) -> Path | None:
        """Write ``payload`` (a dict of JSON values) with its checksum as artifact ``name``
        in :attr:`directory` (atomically), then trim the cache. Returns the path.

        ``optional``: the caller holds the value and only wants it kept, so a write that
        fails (read-only or full disk) is a warning and None is returned; otherwise it
        raises :class:`~msens.errors.InputError` naming the file and the reason.
        """
        internal(isinstance(payload, dict) and CHECKSUM not in payload,
                 f"internal: a JSON artifact is a dict without a {CHECKSUM!r} key")
        path = self.path(name)
        text = json.dumps({**payload, CHECKSUM: json_checksum(payload)}, indent=indent)
        try:
            self._write(path, lambda t: t.write_bytes(text.encode()))
        except InputError as exc:
            if not optional:
                raise
            _log.warning("%s; the result is used but not kept", exc)
            return None
        return path

    # ------------------------------------------------------------------- file artifacts

    def find_file(self, name: str) -> Path | None:
        """Path of verified file artifact ``name`` (e.g. a gmsh mesh), from the first folder
        of :attr:`search` that holds a valid one with its sidecar; None if none does."""
        for d in self.search:
            path = d / name
            if not path.is_file():
                continue
            try:
                self._verify_file(path)
            except _Unverified as exc:
                self._reject(path, str(exc))
                continue
            self._used(path)
            _log.debug("%s: verified", path)
            return path
        return None

    def write_file(self, name: str, write: Callable[[Path], None],
                   meta: dict | None = None) -> Path:
        """Write file artifact ``name`` through ``write(tmp_path)`` (atomically), then its
        sidecar ``<stem>.json`` (``meta`` plus the file's checksum), then trim the cache.

        Returns
        -------
        Path
            The file.
        """
        internal(not name.endswith(".json"),
                 f"internal: a file artifact is not JSON (use write_json), got {name!r}")
        internal(meta is None or FILE_CHECKSUM not in meta,
                 f"internal: {FILE_CHECKSUM!r} is the store's")
        path = self.path(name)
        self._write(path, write, evict=False)
        side = {**(meta or {}), FILE_CHECKSUM: file_checksum(path)}
        text = json.dumps({**side, CHECKSUM: json_checksum(side)}, indent=1, sort_keys=True)
        self._write(path.with_suffix(".json"), lambda t: t.write_bytes(text.encode()))
        return path

    def _write(self, path: Path, write: Callable[[Path], None], evict: bool = True) -> None:
        """Atomic write into :attr:`directory`, then trim the cache (keeping ``path``)."""
        clean_stale(self.directory)  # the temporary files of writers that were killed
        try:
            atomic_write(path, write)
        except InputError as exc:
            hint = (f" or set ${DIR_ENV} to a writable folder"
                    if self.directory == user_cache_dir().resolve() else "")
            raise InputError(f"{exc}; msens keeps computed results in {self.directory}: make "
                             f"that folder writable{hint}") from None
        if evict:
            self.evict(keep=(path.name,))

    # ------------------------------------------------------------------- verification

    @staticmethod
    def _verified_json(path: Path) -> dict:
        try:
            payload = json.loads(path.read_bytes().decode("utf-8"))
        except OSError as exc:
            raise _Unverified(f"cannot be read ({exc.strerror or exc})") from None
        except ValueError as exc:  # not UTF-8, not JSON (e.g. truncated)
            raise _Unverified(f"is not valid JSON ({exc})") from None
        if not isinstance(payload, dict):
            raise _Unverified("is not a JSON object")
        stored = payload.pop(CHECKSUM, None)
        if stored is None:
            raise _Unverified("has no checksum (written before msens verified its artifacts)")
        if stored != json_checksum(payload):
            raise _Unverified("does not match its checksum (corrupted or altered)")
        return payload

    def _verify_file(self, path: Path) -> None:
        side = path.with_suffix(".json")
        if not side.is_file():
            raise _Unverified(f"has no sidecar {side.name} with its checksum")
        try:
            meta = self._verified_json(side)
        except _Unverified as exc:
            raise _Unverified(f"has a sidecar {side.name} that {exc}") from None
        stored = meta.get(FILE_CHECKSUM)
        if stored is None:
            raise _Unverified(f"has no checksum in its sidecar {side.name} (written before "
                             "msens verified its artifacts)")
        try:
            actual = file_checksum(path)
        except OSError as exc:
            raise _Unverified(f"cannot be read ({exc.strerror or exc})") from None
        if actual != stored:
            raise _Unverified("does not match its checksum (truncated, corrupted or altered)")

    @staticmethod
    def _reject(path: Path, reason: str) -> None:
        hint = (f" (to trust it as it is instead: python -m msens.store stamp {path})"
                if "written before" in reason else "")
        _log.warning("%s %s: not used (msens computes it again unless a later cache folder "
                     "holds a valid copy)%s", path, reason, hint)

    # ------------------------------------------------------------------- size bound

    def _used(self, path: Path) -> None:
        """Mark an artifact of the user cache used now (its access time orders eviction)."""
        if path.parent != self.directory or self.max_bytes is None:
            return
        try:
            now = time.time()
            os.utime(path, (now, path.stat().st_mtime))
        except OSError:
            pass  # a read-only cache still serves; only the eviction order suffers

    def size(self) -> int:
        """Total bytes of the artifacts in :attr:`directory`."""
        return sum(size for _, size, _ in self._artifacts())

    def _artifacts(self) -> list[tuple[str, int, float]]:
        """(group, bytes, last use) of every artifact group in :attr:`directory`."""
        groups: dict[str, list[float]] = {}
        try:
            entries = list(os.scandir(self.directory))
        except OSError:
            return []
        for e in entries:
            if TEMP_MARK in e.name or e.name.startswith("."):
                continue
            try:
                if not e.is_file(follow_symlinks=False):
                    continue
                st = e.stat(follow_symlinks=False)
            except OSError:
                continue
            g = groups.setdefault(_group(e.name), [0.0, 0.0])
            g[0] += st.st_size
            g[1] = max(g[1], st.st_atime, st.st_mtime)
        return [(k, int(v[0]), v[1]) for k, v in groups.items()]

    def evict(self, keep: Iterable[str] = ()) -> list[Path]:
        """Delete the least recently used artifacts of :attr:`directory` until its total
        size is at most :attr:`max_bytes` (never those named in ``keep``, nor their
        sidecars). Returns the files deleted."""
        if self.max_bytes is None:
            return []
        artifacts = self._artifacts()
        total = sum(size for _, size, _ in artifacts)
        if total <= self.max_bytes:
            return []
        kept = {_group(n) for n in keep}
        removed: list[Path] = []
        for group, size, _ in sorted(artifacts, key=lambda a: a[2]):
            if total <= self.max_bytes:
                break
            if group in kept:
                continue
            for p in self.directory.glob(f"{group}.*"):
                if TEMP_MARK in p.name:
                    continue
                try:
                    p.unlink()
                    removed.append(p)
                except OSError:
                    pass
            total -= size
        if removed:
            _log.info("cache %s: %d least recently used files removed (bound %d bytes)",
                      self.directory, len(removed), self.max_bytes)
        return removed


def stamp(paths: Iterable[str | os.PathLike[str]]) -> list[Path]:
    """Add the store's checksums to existing artifacts that have none (the committed ones,
    written before msens verified its artifacts), without computing anything again.

    A ``.json`` artifact gets :data:`CHECKSUM` (its other content unchanged, written as the
    store writes it: one-space indent, keys in their order); any other file gets
    :data:`FILE_CHECKSUM` in its sidecar ``<stem>.json`` (which must exist), and the sidecar
    its own checksum. A sidecar given on its own is skipped (its file stamps it). Artifacts
    that already have a checksum are left alone.

    Returns
    -------
    list of Path
        The files changed.
    """
    paths = [Path(p) for p in paths]
    changed = []
    for path in paths:
        if path.suffix == ".json":
            if any(q.suffix != ".json" and q.is_file() and q.stem == path.stem
                   for q in path.parent.glob(f"{path.stem}.*")):
                continue  # the sidecar of a file artifact
            data = json.loads(path.read_text(encoding="utf-8"))
            if CHECKSUM in data:
                continue
            text = json.dumps({**data, CHECKSUM: json_checksum(data)}, indent=1)
            atomic_write_bytes(path, text.encode())
            changed.append(path)
        else:
            side = path.with_suffix(".json")
            meta = json.loads(side.read_text(encoding="utf-8"))
            if FILE_CHECKSUM in meta:
                continue
            meta.pop(CHECKSUM, None)
            meta[FILE_CHECKSUM] = file_checksum(path)
            text = json.dumps({**meta, CHECKSUM: json_checksum(meta)}, indent=1,
                              sort_keys=True)
            atomic_write_bytes(side, text.encode())
            changed.append(side)
    return changed


def main(argv: list[str] | None = None) -> int:
    """``python -m msens.store stamp FILE...``: :func:`stamp` the given artifacts."""
    args = sys.argv[1:] if argv is None else argv
    if not args or args[0] != "stamp":
        print("usage: python -m msens.store stamp FILE...", file=sys.stderr)
        return 2
    for p in stamp(args[1:]):
        print(f"stamped {p}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = ["CHECKSUM", "DEFAULT_MAX_BYTES", "DIR_ENV", "FILE_CHECKSUM", "MAX_BYTES_ENV",
           "Store", "committed_dirs", "content_key", "default_max_bytes", "file_checksum",
           "json_checksum", "stamp", "user_cache_dir"]

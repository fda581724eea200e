"""Waveform NPZ archives: ``time_s`` plus one 1-D array per channel (design.md §8).

Array names are ``time_s`` and canonical channel names (``bead@13``, ``mss@18#2``); the
optional ``__metadata__`` array holds the metadata as a JSON object of strings. Arrays
are stored as float64 with ``numpy.savez`` and loaded with pickling disabled, so a
round trip is exact and a file cannot run code.
"""

from __future__ import annotations

import io
import json
import os

import numpy as np

from msens.errors import InputError, shorten
from msens.io._files import atomic_write_bytes, read_bytes
from msens.io.waveform import (
    CHANNEL_FORMAT_HELP,
    TIME_NAME,
    Channel,
    Waveform,
    check_channels,
    check_metadata_item,
    check_time,
    check_values,
)

METADATA_NAME = "__metadata__"


def read_npz(path: str | os.PathLike[str]) -> Waveform:
    """Read a waveform NPZ archive.

    Parameters
    ----------
    path : path-like
        File to read.

    Returns
    -------
    Waveform

    Raises
    ------
    InputError
        On any malformed content, naming the file and the array.
    """
    raw = read_bytes(path)
    source = str(path)
    if not raw:
        raise InputError(f"{source}: empty file")
    arrays = _load_arrays(raw, source)
    if TIME_NAME not in arrays:
        raise InputError(f"{source}: no time column: the archive has no {TIME_NAME!r} array")
    time = _numeric_vector(arrays.pop(TIME_NAME), TIME_NAME, source)
    check_time(time, source, lambda i: f"{source}: {TIME_NAME}[{i}]")
    metadata = _metadata(arrays.pop(METADATA_NAME, None), source)
    if not arrays:
        raise InputError(f"{source}: no channel arrays besides {TIME_NAME!r}")
    channels = []
    columns = []
    for name, array in arrays.items():
        try:
            channel = Channel.parse(name)
        except InputError as exc:
            if str(exc).startswith("channel "):  # a channel name with a value out of range
                raise InputError(f"{source}: array {shorten(name)}: {exc}") from None
            raise InputError(
                f"{source}: unknown array {shorten(name)}: allowed are {TIME_NAME!r}, "
                f"{METADATA_NAME!r} and channels; {CHANNEL_FORMAT_HELP}"
            ) from None
        values = _numeric_vector(array, name, source)
        if values.size != time.size:
            raise InputError(
                f"{source}: channel {name} has {values.size} samples but {TIME_NAME} has "
                f"{time.size} (unequal lengths)"
            )
        check_values(values, name, source, lambda i, n=name: f"{source}: {n}[{i}]")
        channels.append(channel)
        columns.append(values)
    check_channels(channels, source)
    return Waveform(time, np.column_stack(columns), tuple(channels), metadata)


def _load_arrays(raw: bytes, source: str) -> dict[str, np.ndarray]:
    """All arrays of the archive, in stored order."""
    # numpy's loader raises many types on corrupt bytes (BadZipFile, ValueError, EOFError,
    # OSError, zlib.error, ...); any of them means the same thing to the user.
    try:
        loaded = np.load(io.BytesIO(raw), allow_pickle=False)
        if not isinstance(loaded, np.lib.npyio.NpzFile):
            raise InputError(
                f"{source}: a single .npy array, not an NPZ archive of {TIME_NAME} and channels"
            )
        with loaded:
            arrays = {}
            for name in loaded.files:
                value = loaded[name]
                if not isinstance(value, np.ndarray):  # numpy returns a non-.npy member as bytes
                    raise InputError(f"{source}: member {shorten(name)} of the archive is not "
                                     "a .npy array; an NPZ waveform holds only .npy arrays")
                arrays[name] = value
            return arrays
    except InputError:
        raise
    except Exception as exc:
        raise InputError(
            f"{source}: not a readable NPZ archive ({type(exc).__name__}: {exc})"
        ) from None


def _numeric_vector(array: np.ndarray, name: str, source: str) -> np.ndarray:
    if array.dtype.kind not in "iuf":
        raise InputError(f"{source}: array {name!r} must be real numbers, got dtype {array.dtype}")
    if array.ndim != 1:
        raise InputError(f"{source}: array {name!r} must be 1-D, got shape {array.shape}")
    return array.astype(np.float64)


def _metadata(array: np.ndarray | None, source: str) -> dict[str, str]:
    if array is None:
        return {}
    where = f"{source}: {METADATA_NAME}"
    if array.dtype.kind != "U" or array.ndim != 0:
        raise InputError(f"{where} must be a 0-d string array holding a JSON object")
    try:
        metadata = json.loads(str(array))
    except json.JSONDecodeError as exc:
        raise InputError(f"{where} is not valid JSON ({exc})") from None
    if not isinstance(metadata, dict):
        raise InputError(f"{where} must be a JSON object of strings")
    for key, value in metadata.items():
        check_metadata_item(key, value, where)
    return metadata


def format_npz(waveform: Waveform) -> bytes:
    """NPZ archive bytes of ``waveform``."""
    arrays = {TIME_NAME: waveform.time}
    arrays.update({ch.name: waveform.data[:, j] for j, ch in enumerate(waveform.channels)})
    arrays[METADATA_NAME] = np.array(json.dumps(dict(waveform.metadata)))
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def write_npz(waveform: Waveform, path: str | os.PathLike[str], *, overwrite: bool = False) -> None:
    """Write ``waveform`` to an NPZ archive atomically; never replaces a file unless asked.

    Raises
    ------
    InputError
        If ``path`` exists and ``overwrite`` is false.
    """
    atomic_write_bytes(path, format_npz(waveform), overwrite)

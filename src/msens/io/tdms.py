"""Waveform LabVIEW TDMS files, through npTDMS (design.md §8).

Reading: every channel in every group is a data channel except one named ``time_s``
(the time axis, s). Each data channel needs properties ``kind`` (bead, rod, mss) and
``particle`` (1-based, striker = 1), and may give ``repeat`` (default 1); its TDMS name
is free (LabVIEW names such as ``Dev1/ai0`` are fine). Without a ``time_s`` channel, time
is built from the LabVIEW waveform properties ``wf_start_offset`` and ``wf_increment``,
which all data channels must then share. File (root) properties become metadata: values
are turned into one-line strings; properties whose names are not valid metadata keys
(e.g. containing spaces) are skipped.

Writing: one group ``waveform`` with a ``time_s`` channel and one channel per waveform
channel (named canonically, with kind/particle/repeat, unit and ``wf_*`` properties so
LabVIEW and DIAdem show the time axis); metadata as root properties. Round trips are exact.
"""

from __future__ import annotations

import io
import logging
import os
from collections.abc import Mapping

import numpy as np
from nptdms import ChannelObject, GroupObject, RootObject, TdmsFile, TdmsWriter

from msens.errors import InputError
from msens.io._files import atomic_write_bytes, read_bytes
from msens.io.waveform import (
    KINDS,
    METADATA_KEY_RE,
    TIME_NAME,
    VERSION_KEY,
    Channel,
    Waveform,
    check_channels,
    check_time,
    check_values,
)

GROUP_NAME = "waveform"
_PROPERTY_HELP = (
    f"each data channel needs properties kind ({', '.join(KINDS)}) and particle "
    "(1-based, striker = 1), optionally repeat (>= 1)"
)


def read_tdms(path: str | os.PathLike[str]) -> Waveform:
    """Read a waveform from a LabVIEW TDMS file.

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
        On unreadable files and on channels without kind/particle properties, naming
        the file and the channel.
    """
    raw = read_bytes(path)
    source = str(path)
    if not raw:
        raise InputError(f"{source}: empty file")
    tdms = _parse(raw, source)
    time_channels = []
    data_channels = []
    for group in tdms.groups():
        for channel in group.channels():
            (time_channels if channel.name == TIME_NAME else data_channels).append(channel)
    if len(time_channels) > 1:
        raise InputError(f"{source}: {len(time_channels)} channels named {TIME_NAME!r}")
    if not data_channels:
        raise InputError(f"{source}: no data channels")
    channels = [_channel_of(ch, source) for ch in data_channels]
    check_channels(channels, source)
    columns = [_samples(ch, source) for ch in data_channels]
    if time_channels:
        time = _samples(time_channels[0], source)
    else:
        time = _time_from_properties(data_channels, columns[0].size, source)
    for ch, values in zip(channels, columns, strict=True):
        if values.size != time.size:
            raise InputError(
                f"{source}: channel {ch.name} has {values.size} samples but {TIME_NAME} has "
                f"{time.size} (unequal lengths)"
            )
    check_time(time, source, lambda i: f"{source}: {TIME_NAME}[{i}]")
    for ch, values in zip(channels, columns, strict=True):
        check_values(values, ch.name, source, lambda i, n=ch.name: f"{source}: {n}[{i}]")
    metadata = _metadata(tdms.properties)
    return Waveform(time, np.column_stack(columns), tuple(channels), metadata)


def _parse(raw: bytes, source: str) -> TdmsFile:
    if not raw.startswith(b"TDSm"):
        raise InputError(f"{source}: not a TDMS file (no 'TDSm' lead-in)")
    # npTDMS raises many types on corrupt segments (ValueError, KeyError, struct.error,
    # UnicodeDecodeError, ...); they all mean the file is damaged.
    # npTDMS logs a warning per damaged segment: the one message below says it instead
    logs = [logging.getLogger(name) for name in list(logging.root.manager.loggerDict)
            if name.startswith("nptdms")]  # npTDMS sets each module logger's level
    levels = [log.level for log in logs]
    for log in logs:
        log.setLevel(logging.CRITICAL)
    try:
        return TdmsFile.read(io.BytesIO(raw))
    except Exception as exc:
        detail = " ".join(str(exc).split())[:200]  # an exception may quote raw bytes
        raise InputError(
            f"{source}: not a readable TDMS file ({type(exc).__name__}: {detail})"
        ) from None
    finally:
        for log, level in zip(logs, levels, strict=True):
            log.setLevel(level)


def _label(channel: object) -> str:
    return f"TDMS channel {channel.group_name!r}/{channel.name!r}"  # type: ignore[attr-defined]


def _channel_of(channel: object, source: str) -> Channel:
    props: Mapping[str, object] = channel.properties  # type: ignore[attr-defined]
    where = f"{source}: {_label(channel)}"
    for key in ("kind", "particle"):
        if key not in props:
            raise InputError(f"{where} has no {key!r} property; {_PROPERTY_HELP}")
    kind = props["kind"]
    if not isinstance(kind, str) or kind.strip() not in KINDS:
        raise InputError(f"{where}: property kind {kind!r} is not one of {', '.join(KINDS)}")
    particle = _positive_int(props["particle"], "particle", where)
    repeat = _positive_int(props.get("repeat", 1), "repeat", where)
    return Channel(kind.strip(), particle, repeat)  # type: ignore[arg-type]


def _positive_int(value: object, key: str, where: str) -> int:
    """LabVIEW may store integers as strings or doubles; accept exact integers only."""
    number: float | int | None = None
    if isinstance(value, bool):
        number = None
    elif isinstance(value, int | np.integer):
        number = int(value)
    elif isinstance(value, float | np.floating) and float(value).is_integer():
        number = int(value)
    elif isinstance(value, str) and value.strip().isdecimal():
        number = int(value.strip())
    if number is None or number < 1:
        raise InputError(f"{where}: property {key} {value!r} is not a positive integer")
    return number


def _samples(channel: object, source: str) -> np.ndarray:
    try:
        values = np.asarray(channel[:])  # type: ignore[index]
    except Exception as exc:  # npTDMS reads lazily in places; corrupt data surfaces here
        detail = " ".join(str(exc).split())[:200]
        raise InputError(f"{source}: {_label(channel)} unreadable ({detail})") from None
    if values.dtype.kind not in "iuf" or values.ndim != 1:
        raise InputError(
            f"{source}: {_label(channel)} must hold real numbers, got dtype {values.dtype}"
        )
    return values.astype(np.float64)


def _time_from_properties(channels: list, n: int, source: str) -> np.ndarray:
    first = channels[0].properties
    if "wf_increment" not in first:
        raise InputError(
            f"{source}: no time column: no channel named {TIME_NAME!r} and no wf_increment "
            "property to build the time axis from"
        )
    start, step = first.get("wf_start_offset", 0.0), first["wf_increment"]
    for ch in channels[1:]:
        props = ch.properties
        if props.get("wf_increment") != step or props.get("wf_start_offset", 0.0) != start:
            raise InputError(
                f"{source}: {_label(ch)} has a different time axis (wf_start_offset, "
                "wf_increment) than the first channel; add a time_s channel"
            )
    try:
        start, step = float(start), float(step)
    except (TypeError, ValueError):
        raise InputError(f"{source}: wf_start_offset/wf_increment are not numbers") from None
    if not (np.isfinite(start) and np.isfinite(step) and step > 0):
        raise InputError(f"{source}: wf_increment must be a positive number, got {step!r}")
    return start + step * np.arange(n)


def _metadata(properties: Mapping[str, object]) -> dict[str, str]:
    metadata = {}
    for key, value in properties.items():
        if METADATA_KEY_RE.fullmatch(key) is None or key == VERSION_KEY:
            continue
        metadata[key] = " ".join(str(value).replace("\x00", " ").split())
    return metadata


def format_tdms(waveform: Waveform) -> bytes:
    """TDMS file bytes of ``waveform``."""
    t0, dt = float(waveform.time[0]), waveform.dt
    objects = [RootObject(properties=dict(waveform.metadata)), GroupObject(GROUP_NAME)]
    objects.append(
        ChannelObject(GROUP_NAME, TIME_NAME, waveform.time, properties={"unit_string": "s"})
    )
    for j, ch in enumerate(waveform.channels):
        props = {
            "kind": ch.kind,
            "particle": int(ch.particle),
            "repeat": int(ch.repeat),
            "unit_string": "V",
            "wf_start_offset": t0,
            "wf_increment": dt,
        }
        objects.append(
            ChannelObject(GROUP_NAME, ch.name, np.ascontiguousarray(waveform.data[:, j]), props)
        )
    buffer = io.BytesIO()
    with TdmsWriter(buffer) as writer:
        writer.write_segment(objects)
    return buffer.getvalue()


def write_tdms(
    waveform: Waveform, path: str | os.PathLike[str], *, overwrite: bool = False
) -> None:
    """Write ``waveform`` to a TDMS file atomically; never replaces a file unless asked.

    Raises
    ------
    InputError
        If ``path`` exists and ``overwrite`` is false.
    """
    atomic_write_bytes(path, format_tdms(waveform), overwrite)

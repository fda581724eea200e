"""Measured waveforms: named channels sampled on one uniform time axis.

A channel is ``<kind>@<particle>`` with an optional ``#<repeat>`` suffix (design.md §8):
``bead@13``, ``rod@18#2``, ``mss@13``. ``kind`` is the sensor type, ``particle`` the 1-based
particle number counting the striker as 1 (the paper's numbering), ``repeat`` numbers
repeated recordings of the same channel (1 when no suffix is given).

All validation of waveform content lives here, so every reader and writer applies the
same rules. Readers call the ``check_*`` functions first with a ``locate`` callback that
turns a sample index into ``file:line`` text; the :class:`Waveform` constructor repeats
the checks without locations as the final guard.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal, get_args

import numpy as np

from msens.errors import InputError, shorten

Kind = Literal["bead", "rod", "mss"]
KINDS: tuple[str, ...] = get_args(Kind)

#: Name of the time column / array / channel in every format.
TIME_NAME = "time_s"

#: Largest allowed deviation of a time stamp from the uniform grid, as a fraction of dt.
#: Float64 files written by msens deviate by ~1e-10; a missing or doubled sample deviates
#: by ~0.5. The limit rejects irregular sampling; text files whose times are printed with few
#: digits get the printed resolution on top (see ``check_time``'s ``resolution``).
TIME_RTOL = 1e-3
#: Most that the rounding of printed times may add to the allowed deviation, in steps.
PRINTED_RTOL_MAX = 0.1

_CHANNEL_RE = re.compile(r"(bead|rod|mss)@([1-9][0-9]*)(?:#([1-9][0-9]*))?")
#: Format-version key written by the CSV writer and consumed by the reader; reserved.
VERSION_KEY = "msens-waveform"
VERSION = "1"
#: Metadata keys: what a ``# key: value`` line can carry unambiguously.
METADATA_KEY_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*")

CHANNEL_FORMAT_HELP = (
    "channel names are <kind>@<particle>[#<repeat>] with kind one of "
    f"{', '.join(KINDS)}, particle and repeat positive integers (e.g. bead@13, mss@18#2)"
)
METADATA_KEY_HELP = (
    "metadata keys are letters, digits, '_', '.', '-' (not starting with '.' or '-')"
)


#: Largest particle or repeat number of a channel: far above any chain's particles (a study
#: has at most 1000 beads) and shots, and within every format's integer (TDMS stores int32).
MAX_CHANNEL_INDEX = 1_000_000


def _default_locate(index: int) -> str:
    return f"sample {index}"


@dataclass(frozen=True, order=True)
class Channel:
    """One recorded signal (particle and repeat at most :data:`MAX_CHANNEL_INDEX`).

    Parameters
    ----------
    kind : {"bead", "rod", "mss"}
        Sensor type: instrumented bead, piezo rod, magnetostrictive sensor.
    particle : int
        1-based particle number, the striker being particle 1.
    repeat : int
        Repeat number of the same (kind, particle) recording, >= 1; 1 means no suffix.
    """

    kind: Kind
    particle: int
    repeat: int = 1

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"channel kind {self.kind!r} is not one of {', '.join(KINDS)}")
        for label, value in (("particle", self.particle), ("repeat", self.repeat)):
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise InputError(f"channel {label} must be a positive integer, got "
                                 f"{shorten(value)}")
            if value > MAX_CHANNEL_INDEX:  # one rule for every reader and writer
                raise InputError(f"channel {label} must be <= {MAX_CHANNEL_INDEX:,} (chains "
                                 f"have at most a thousand beads), got {shorten(value)}")

    @property
    def name(self) -> str:
        """Canonical name, ``kind@particle`` or ``kind@particle#repeat`` for repeat > 1."""
        base = f"{self.kind}@{self.particle}"
        return base if self.repeat == 1 else f"{base}#{self.repeat}"

    @classmethod
    def parse(cls, name: str) -> Channel:
        """Parse a channel name such as ``"bead@13"`` or ``"mss@18#2"``.

        Surrounding whitespace is ignored; ``#1`` is the same channel as no suffix.

        Raises
        ------
        InputError
            If ``name`` does not follow the grammar; the message says what is allowed.
        """
        if not isinstance(name, str):
            raise InputError(f"channel name must be a string, got {shorten(name)}")
        match = _CHANNEL_RE.fullmatch(name.strip())
        if match is None:
            raise InputError(f"unknown channel name {shorten(name)}: {CHANNEL_FORMAT_HELP}")
        kind, particle, repeat = match.groups()
        return cls(kind, int(particle), int(repeat) if repeat else 1)  # type: ignore[arg-type]

    def __str__(self) -> str:
        return self.name


# ---------------------------------------------------------------------------------------
# Checks shared by readers and the Waveform constructor
# ---------------------------------------------------------------------------------------


def check_time(
    time: np.ndarray,
    where: str,
    locate: Callable[[int], str] = _default_locate,
    resolution: float = 0.0,
) -> None:
    """Check a time axis: >= 2 finite samples, strictly increasing, uniform.

    Parameters
    ----------
    time : ndarray, shape (nt,)
        Sample times, s.
    where : str
        Name of the source (file or object) for messages.
    locate : callable
        Maps a sample index to a location text (e.g. ``"data.csv:14"``).
    resolution : float
        Rounding of the times as stored, s (half a unit of the last printed digit for text
        files; 0 for binary). A uniform grid printed with few digits deviates from itself by
        up to this much at each sample and at both end points, so ``2 * resolution`` is
        allowed on top of ``TIME_RTOL * dt``, but at most :data:`PRINTED_RTOL_MAX` dt (a
        missing sample, 0.5 dt, is always caught).

    Raises
    ------
    InputError
        Naming the first offending sample.
    """
    if time.ndim != 1:
        raise InputError(f"{where}: {TIME_NAME} must be one-dimensional, got shape {time.shape}")
    if time.size < 2:
        raise InputError(f"{where}: need at least 2 samples, got {time.size}")
    bad = np.flatnonzero(~np.isfinite(time))
    if bad.size:
        raise InputError(
            f"{locate(int(bad[0]))}: {TIME_NAME} is not finite ({float(time[bad[0]])!r})"
        )
    steps = np.diff(time)
    bad = np.flatnonzero(steps <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(
            f"{locate(i)}: {TIME_NAME} must increase strictly, but {float(time[i])!r} follows "
            f"{float(time[i - 1])!r}"
        )
    dt, deviation = grid_deviation(time)
    worst = int(np.argmax(deviation))
    allowed = TIME_RTOL + min(2.0 * resolution / dt, PRINTED_RTOL_MAX)
    if deviation[worst] > allowed:
        printed = (f" ({TIME_RTOL:g} dt + twice the printed resolution {resolution:.3g} s)"
                   if resolution > 0.0 else "")
        raise InputError(
            f"{locate(worst)}: {TIME_NAME} is not uniformly sampled: sample deviates from the "
            f"uniform grid (dt = {dt:.6g} s) by {deviation[worst]:.3g} dt, allowed "
            f"{allowed:.3g} dt{printed}; resample to a uniform grid"
        )


def grid_deviation(time: np.ndarray) -> tuple[float, np.ndarray]:
    """Step dt (s) of the grid through the end points of ``time`` (s, shape (nt,)), and each
    sample's deviation from it in steps, shape (nt,); exact for uniform float64 times."""
    dt = (time[-1] - time[0]) / (time.size - 1)
    return dt, np.abs(time - (time[0] + dt * np.arange(time.size))) / dt


def uniform_axis(time: np.ndarray) -> np.ndarray:
    """The uniform grid t0 + k dt closest (least squares) to ``time`` (s), shape (nt,).

    For time columns printed with fewer digits than the sampling needs: the rounding errors
    of the individual samples average out in t0 and dt.
    """
    k = np.arange(time.size, dtype=np.float64)
    dt, t0 = np.polyfit(k, time, 1)
    return t0 + dt * k


def check_values(
    values: np.ndarray,
    channel: str,
    where: str,
    locate: Callable[[int], str] = _default_locate,
) -> None:
    """Check that one channel's samples (shape (nt,)) are all finite."""
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        i = int(bad[0])
        raise InputError(
            f"{locate(i)}: channel {channel} value {float(values[i])!r} is not finite "
            "(NaN and infinity are not allowed)"
        )


def check_channels(channels: Iterable[Channel], where: str) -> None:
    """Check that channels are not repeated (same kind, particle and repeat)."""
    seen: set[Channel] = set()
    for ch in channels:
        if ch in seen:
            raise InputError(
                f"{where}: duplicate channel {ch.name}; number repeats as {ch.kind}@"
                f"{ch.particle}#2, #3, ..."
            )
        seen.add(ch)


def check_metadata_item(key: object, value: object, where: str) -> None:
    """Check one metadata entry: a key per ``METADATA_KEY_RE`` and a one-line, stripped string."""
    if not isinstance(key, str) or METADATA_KEY_RE.fullmatch(key) is None:
        raise InputError(f"{where}: bad metadata key {key!r}: {METADATA_KEY_HELP}")
    if key == VERSION_KEY:
        raise InputError(
            f"{where}: metadata key {VERSION_KEY!r} is reserved for the format version"
        )
    if not isinstance(value, str):
        raise InputError(f"{where}: metadata {key!r} must be a string, got {value!r}")
    if value != value.strip() or any(c in value for c in "\r\n\x00"):
        raise InputError(
            f"{where}: metadata {key!r} value {value!r} must be one line without leading or "
            "trailing whitespace"
        )


# ---------------------------------------------------------------------------------------
# Waveform
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Waveform:
    """Channels sampled on one uniform time axis.

    Parameters
    ----------
    time : ndarray, shape (nt,)
        Sample times, s, strictly increasing and uniform (see :data:`TIME_RTOL`), nt >= 2.
        Any start; negative times are pre-trigger samples.
    data : ndarray, shape (nt, nch)
        Samples, V, column j belonging to ``channels[j]``; finite; nch >= 1.
    channels : tuple of Channel, length nch
        Distinct channels.
    metadata : Mapping[str, str]
        Free ``key: value`` annotations (e.g. ``drop_height_m``), stored read-only.

    Notes
    -----
    Arrays are copied to float64 and made read-only. Equality compares arrays exactly.
    """

    time: np.ndarray
    data: np.ndarray
    channels: tuple[Channel, ...]
    metadata: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = "waveform"
        time = _readonly(self.time, "time", where)
        data = _readonly(self.data, "data", where)
        channels = tuple(self.channels)
        for ch in channels:
            if not isinstance(ch, Channel):
                raise InputError(f"{where}: channels must be Channel objects, got {ch!r}")
        check_time(time, where)
        if data.ndim != 2 or data.shape != (time.size, len(channels)):
            raise InputError(
                f"{where}: data must have shape (nt, nch) = ({time.size}, {len(channels)}), "
                f"got {data.shape}"
            )
        if not channels:
            raise InputError(f"{where}: at least one channel is required")
        check_channels(channels, where)
        for j, ch in enumerate(channels):
            check_values(data[:, j], ch.name, where)
        meta = dict(self.metadata)
        for key, value in meta.items():
            check_metadata_item(key, value, where)
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "metadata", MappingProxyType(meta))

    # Arrays make the generated __eq__ ambiguous; compare exactly instead.
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Waveform):
            return NotImplemented
        return (
            self.channels == other.channels
            and dict(self.metadata) == dict(other.metadata)
            and np.array_equal(self.time, other.time)
            and np.array_equal(self.data, other.data)
        )

    __hash__ = None  # type: ignore[assignment]

    @property
    def dt(self) -> float:
        """Sampling interval, s (mean over the record)."""
        return float((self.time[-1] - self.time[0]) / (self.time.size - 1))

    @property
    def names(self) -> tuple[str, ...]:
        """Canonical channel names, in column order."""
        return tuple(ch.name for ch in self.channels)

    def channel(self, name: str | Channel) -> np.ndarray:
        """Samples of one channel, shape (nt,), V (read-only view).

        Raises
        ------
        InputError
            If the channel is not present; the message lists the channels present.
        """
        ch = name if isinstance(name, Channel) else Channel.parse(name)
        try:
            j = self.channels.index(ch)
        except ValueError:
            raise InputError(
                f"channel {ch.name} not in waveform; present: {', '.join(self.names)}"
            ) from None
        return self.data[:, j]

    def select(self, kind: str | None = None, particle: int | None = None) -> Waveform:
        """Waveform restricted to channels of a kind and/or particle (all repeats).

        Raises
        ------
        InputError
            If no channel matches.
        """
        if kind is not None and kind not in KINDS:
            raise InputError(f"kind {kind!r} is not one of {', '.join(KINDS)}")
        keep = [
            j
            for j, ch in enumerate(self.channels)
            if (kind is None or ch.kind == kind) and (particle is None or ch.particle == particle)
        ]
        if not keep:
            raise InputError(
                f"no channel with kind={kind!r}, particle={particle!r}; present: "
                f"{', '.join(self.names)}"
            )
        return Waveform(
            self.time,
            self.data[:, keep],
            tuple(self.channels[j] for j in keep),
            self.metadata,
        )


def _readonly(array: object, label: str, where: str) -> np.ndarray:
    try:
        raw = np.asarray(array)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: {label} must be a real numeric array ({exc})") from None
    if raw.dtype.kind not in "iuf":
        raise InputError(f"{where}: {label} must be a real numeric array, got dtype {raw.dtype}")
    out = np.array(raw, dtype=np.float64, copy=True)
    out.setflags(write=False)
    return out

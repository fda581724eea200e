"""Figures of chain studies (matplotlib, Agg). Each function returns a Figure."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple

from msens.results import SetupResult, StudyResult

matplotlib.use("Agg")


_US = 1e6

#: Figure file formats the commands can write (``--format``).
FORMATS = ("png", "pdf", "svg")


def _read_contacts(result: StudyResult) -> dict[int, list[int]]:
    """1-based contacts each sensor position reads, by sensor particle, over all setups.

    Bead and rod sensors read the two contacts of their particle, an MsS (four-contact or
    physics) the four around its coil, c_{p-2} .. c_{p+1}
    (:func:`msens.readout.sensors.sensor_contacts`).
    """
    from msens.readout.sensors import sensor_contacts

    out: dict[int, set[int]] = {}
    for s in result.setups:
        n = s.history.force.shape[1]
        for r in s.sensors:
            k = sensor_contacts(r.sensor.kind, r.sensor.particle, n)
            out.setdefault(r.sensor.particle, set()).update(int(c) + 1 for c in k)
    return {p: sorted(out[p]) for p in sorted(out)}


def contact_profiles(result: StudyResult, contacts: tuple[int, ...] | None = None,
                     t_max_s: float | None = None) -> Figure:
    """Dynamic force F_c - F_c,static at the contacts around the study's sensors (those each
    sensor kind averages), every setup (like the paper's Fig. 4), over the whole record.

    Parameters
    ----------
    result : StudyResult
    contacts : tuple of int, optional
        1-based contact numbers (c_i joins particles i and i+1), shown in one column.
        Default: one column per sensor position with the contacts its sensors read.
    t_max_s : float, optional
        Last time shown, s after impact (default: the whole record, reflected pulse included).

    Returns
    -------
    Figure
    """
    columns = ({0: list(contacts)} if contacts is not None else _read_contacts(result))
    n_rows = max(len(c) for c in columns.values())
    fig, axes = plt.subplots(n_rows, len(columns), figsize=(4.2 * len(columns) + 1.2,
                                                           1.45 * n_rows + 1.0),
                             sharex=True, sharey=True, squeeze=False)
    for j, (particle, cs) in enumerate(columns.items()):
        for i in range(n_rows):
            ax = axes[i, j]
            if i >= len(cs):
                ax.set_visible(False)
                continue
            c = cs[i]
            for s in result.setups:
                t = s.history.t
                m = np.ones(t.size, bool) if t_max_s is None else t <= t_max_s
                f = s.history.force[:, c - 1] - s.static_force[c - 1]
                ax.plot(t[m] * _US, f[m], label=s.setup.name, lw=0.9)
            ax.text(0.99, 0.92, f"c{c}  (particles {c}–{c + 1})", transform=ax.transAxes,
                    ha="right", va="top", fontsize=8)
            ax.grid(alpha=0.3)
        if contacts is None:
            axes[0, j].set_title(f"contacts around the sensors at particle {particle}",
                                 fontsize=9)
        axes[len(cs) - 1, j].set_xlabel("time since impact (µs)")
        axes[len(cs) - 1, j].xaxis.set_tick_params(labelbottom=True)
    if len(result.setups) > 1:
        axes[0, -1].legend(fontsize=7, loc="center right", title="setup", title_fontsize=7)
    fig.supylabel(r"dynamic contact force $F_c - F_{c,\mathrm{static}}$ (N)", fontsize=10)
    fig.suptitle(f"Contact forces at the sensors, study {result.study.name}", fontsize=10)
    fig.tight_layout()
    return fig


def _sensor_contacts(setup: SetupResult, particle: int) -> list[int]:
    from msens.readout.sensors import sensor_contacts

    kind = next(s.sensor.kind for s in setup.sensors if s.sensor.particle == particle)
    return [int(k) + 1 for k in sensor_contacts(kind, particle, setup.chain.n_particles)]


def sensor_profiles(result: StudyResult, particle: int = 13,
                    window_s: tuple[float, float] = (50e-6, 250e-6)) -> Figure:
    """Each setup's sensor at ``particle``: its contacts (dashed) and its reading (solid),
    like the paper's Fig. 5."""
    setups = [s for s in result.setups if any(r.sensor.particle == particle for r in s.sensors)]
    fig, axes = plt.subplots(1, len(setups), figsize=(4.0 * len(setups), 3.2), sharey=True,
                             squeeze=False)
    for ax, s in zip(axes[0], setups, strict=True):
        t = s.history.t
        m = (t >= window_s[0]) & (t <= window_s[1])
        for c in _sensor_contacts(s, particle):
            f = s.history.force[:, c - 1] - s.static_force[c - 1]
            ax.plot(t[m] * _US, f[m], "--", lw=0.9, label=f"c{c}")
        reading = next(r for r in s.sensors if r.sensor.particle == particle)
        ax.plot(t[m] * _US, reading.force[m], "k", lw=1.6, label="sensor")
        ax.set_title(f"{s.setup.name} at particle {particle}")
        ax.set_xlabel("time (µs)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("dynamic force (N)")
    fig.tight_layout()
    return fig


def _record_quantity(r) -> tuple[str, np.ndarray, str]:
    """What a sensor's record is, per kind: (axis label with unit, values, kind of marks).

    A physics MsS records its coil's DAQ voltage (plotted in mV; its TOF and AR are read
    from the integrated signal, so its peak times are marked, not values); a four-contact
    MsS is the paper's mean force of its four contacts; bead and rod sensors read a force.
    """
    from msens.config.schema import MssModel
    from msens.readout.sensors import SensorKind

    if r.sensor.kind is SensorKind.MSS and r.sensor.model is MssModel.PHYSICS:
        return "DAQ voltage (mV)", np.asarray(r.voltage_shape) * 1e3, "times"
    if r.sensor.kind is SensorKind.MSS:
        return "four-contact mean force (N)", r.force, "peaks"
    return f"{r.sensor.kind.value} sensor force (N)", r.force, "peaks"


def sensor_records(result: StudyResult) -> Figure:
    """Full records of every sensor, in each kind's quantity, with the incident and
    reflected peaks (or, for a physics MsS, their times) marked.

    One panel per setup and quantity: a physics MsS record is a voltage (mV), bead, rod and
    four-contact MsS records are forces (N).
    """
    from matplotlib.lines import Line2D

    panels = []  # (setup, label, [(sensor, values, marks)])
    for s in result.setups:
        groups: dict[str, list] = {}
        for r in s.sensors:
            label, values, marks = _record_quantity(r)
            groups.setdefault(label, []).append((r, values, marks))
        panels += [(s, label, rs) for label, rs in groups.items()]
    fig, axes = plt.subplots(len(panels), 1, figsize=(7, 2.3 * len(panels) + 0.5),
                             sharex=True, squeeze=False)
    for ax, (s, label, rs) in zip(axes[:, 0], panels, strict=True):
        t = s.history.t * _US
        times = False
        for r, values, marks in rs:
            (line,) = ax.plot(t, values, lw=1.0,
                              label=f"{r.sensor.kind.value}@{r.sensor.particle}")
            f = r.features
            if marks == "peaks":
                ax.plot([f.t_incident * _US, f.t_reflected * _US],
                        [f.f_incident, f.f_reflected], "o", color=line.get_color(), ms=4)
            else:
                # the features belong to the integrated signal, not to this voltage
                times = True
                for tk in (f.t_incident, f.t_reflected):
                    ax.axvline(tk * _US, color=line.get_color(), ls=":", lw=0.9)
        handles, labels = ax.get_legend_handles_labels()
        if times:
            handles.append(Line2D([], [], color="0.3", ls=":", lw=0.9))
            labels.append("incident / reflected peak time\n(integrated signal)")
        else:
            handles.append(Line2D([], [], color="0.3", ls="", marker="o", ms=4))
            labels.append("incident / reflected peak")
        ax.legend(handles, labels, fontsize=7, loc="upper right")
        ax.set_ylabel(label.replace(" (", "\n("), fontsize=9)
        ax.set_title(f"setup {s.setup.name}", fontsize=9, loc="left")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time since impact (µs)")
    axes[-1, 0].set_xlim(t[0], t[-1])
    fig.tight_layout()
    return fig


def table2(rows: list[dict]) -> Figure:
    """Model TOF and AR against the published experiment and the published model."""
    labels = [f"{r['setup']} {r['position']}" for r in rows]
    x = np.arange(len(rows))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, key, unit in ((a1, "tof", "TOF (µs)"),
                          (a2, "ar", "AR (reflected / incident peak, –)")):
        model = [r[f"{key}_us" if key == "tof" else key] for r in rows]
        ref = [r.get("reference", {}) for r in rows]
        exp = [c.get(f"experiment_{key}_us" if key == "tof" else f"experiment_{key}", np.nan)
               for c in ref]
        std = [c.get(f"experiment_{key}_std_us" if key == "tof" else f"experiment_{key}_std",
                     0.0) for c in ref]
        paper = [c.get(f"paper_model_{key}_us" if key == "tof" else f"paper_model_{key}",
                       np.nan) for c in ref]
        ax.errorbar(x - 0.15, exp, yerr=std, fmt="ks", ms=4, label="experiment (paper)")
        ax.plot(x, paper, "b^", ms=5, label="model (paper)")
        ax.plot(x + 0.15, model, "ro", ms=5, label="model (msens)")
        ax.set_xticks(x, labels, rotation=30, ha="right", fontsize=8)
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
        # every setup's rows, each setup on a band of its own
        setups = [r["setup"] for r in rows]
        for k, name in enumerate(dict.fromkeys(setups)):
            idx = [i for i, n in enumerate(setups) if n == name]
            if k % 2:
                ax.axvspan(min(idx) - 0.5, max(idx) + 0.5, color="0.93", zorder=0, lw=0)
        ax.set_xlim(-0.5, len(rows) - 0.5)
    a1.legend(fontsize=7)
    fig.suptitle("Table 2: time of flight and amplitude ratio")
    fig.tight_layout()
    return fig


def close(fig: Figure) -> None:
    """Release a figure's memory."""
    plt.close(fig)


def _overlay_quantity(sensor) -> tuple[str, float, str]:
    """Axis quantity of a compared channel: (name, scale to plotted units, unit).

    A physics MsS is compared as its integrated DAQ voltage, ~1e-5 V s: plotted in µV s so
    the axis needs no offset exponent. Bead, rod and four-contact MsS records are forces, N.
    """
    from msens.synth import is_physics_mss

    if is_physics_mss(sensor):
        return "integrated DAQ voltage", 1e6, "µV s"
    return "force", 1.0, "N"


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _overlay_number(x: float) -> str:
    """Four significant digits, as 6.966×10⁵ rather than 6.966e+05 outside 1e-3 .. 1e4."""
    if x == 0 or not np.isfinite(x) or 1e-3 <= abs(x) < 1e4:
        return f"{x:#.4g}"
    exp = int(np.floor(np.log10(abs(x))))
    mant = f"{x / 10.0**exp:#.4g}"
    if mant.lstrip("-").startswith("10."):  # rounding reached the next decade
        exp, mant = exp + 1, f"{x / 10.0**(exp + 1):#.4g}"
    return f"{mant}×10{str(exp).translate(_SUPERSCRIPT)}"


def overlay(setup: SetupResult, shots: list, t_max_s: float | None = None) -> Figure:
    """Calibrated measurement over the model, one panel per channel, like the paper's
    Fig. 7(b, d, f).

    Each panel shows the measured record (the mean over shots, with a ±1 standard deviation
    band when there are several) and the model record it was compared with, processed the
    same way (:func:`msens.compare.model_record`): force in N for bead, rod and four-contact
    MsS channels; the integrated DAQ voltage in µV s for a physics MsS.

    Parameters
    ----------
    setup : SetupResult
        The setup the data were matched to.
    shots : list of list of msens.compare.ShotRecord
        Aligned and calibrated records, per shot and channel (:func:`msens.compare.shot_records`).
    t_max_s : float, optional
        Last time shown, s after impact (default: the whole model record).

    Returns
    -------
    Figure
    """
    from msens.compare import gain_unit, model_record

    sensors = setup.sensors
    fig, axes = plt.subplots(len(sensors), 1, figsize=(7, 2.5 * len(sensors) + 0.6),
                             sharex=True, squeeze=False)
    t = setup.history.t
    m = np.ones(t.size, bool) if t_max_s is None else t <= t_max_s
    t_us = t[m] * _US
    handles: dict = {}  # legend label -> artist(s), first panel's wins
    for ax, sensor in zip(axes[:, 0], sensors, strict=True):
        name = f"{sensor.sensor.kind.value}@{sensor.sensor.particle}"
        recs = [r for shot in shots for r in shot
                if r.channel.kind == sensor.sensor.kind.value
                and r.channel.particle == sensor.sensor.particle]
        quantity, scale, unit = _overlay_quantity(sensor)
        # the record the measurement was calibrated against, not the chain force: for a
        # physics MsS these differ in unit (V s against N)
        model = next((r.model for r in recs if r.model is not None), None)
        if model is None:
            model = model_record(sensor, t)
        if recs:
            stack = np.array([r.force for r in recs]) * scale
            # samples every shot covers: a mean over fewer shots would jump at the edges
            covered = np.all(np.isfinite(stack), axis=0)
            mean = np.where(covered, stack.mean(axis=0), np.nan)[m]
            (line,) = ax.plot(t_us, mean, color="k", lw=0.9, gid="measured")
            handle, label = line, "measured"
            if len(recs) > 1:
                std = np.where(covered, stack.std(axis=0, ddof=1), np.nan)[m]
                band = ax.fill_between(t_us, mean - std, mean + std, color="0.7", lw=0,
                                       gid="measured scatter")
                # one legend entry: the band drawn under the mean line
                handle, label = (band, line), f"measured, mean ± 1 s.d. of {len(recs)} shots"
            handles.setdefault(label, handle)
            gain = float(np.mean([r.gain for r in recs]))
            ax.set_title(f"K = {_overlay_number(gain)} {gain_unit(sensor)}", loc="right",
                         fontsize=9)
        (line,) = ax.plot(t_us, model[m] * scale, color="C3", ls="--", lw=1.1, gid="model")
        handles.setdefault("model", line)
        ax.set_ylabel(f"{quantity} ({unit})")
        ax.set_title(name, loc="left", fontsize=9)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(list(handles.values()), list(handles), fontsize=8, loc="upper right",
                      handler_map={tuple: HandlerTuple(ndivide=1)})
    axes[-1, 0].set_xlabel("time since impact (µs)")
    axes[-1, 0].set_xlim(t_us[0], t_us[-1])
    fig.suptitle(f"Measured (aligned, calibrated) and model records: setup "
                 f"{setup.setup.name}", fontsize=10)
    fig.tight_layout()
    return fig

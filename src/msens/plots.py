"""Figures of chain studies (matplotlib, Agg). Each function returns a Figure."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple

from msens.results import SetupResult, StudyResult
from msens.vocabulary import TIME_LABEL, contact_name, sensor_name, setup_name

matplotlib.use("Agg")


_US = 1e6

#: Figure file formats the commands can write (``--format``).
FORMATS = ("png", "pdf", "svg")


def _read_contacts(result: StudyResult) -> dict[int, tuple[list[int], set[str]]]:
    """1-based contacts each sensor position reads, and the sensor kinds there, by sensor
    particle, over all setups.

    Bead and rod sensors read the two contacts of their particle, an MsS (four-contact or
    physics) the four around its coil, contacts p-2 .. p+1
    (:func:`msens.readout.sensors.sensor_contacts`).
    """
    from msens.readout.sensors import sensor_contacts

    out: dict[int, set[int]] = {}
    kinds: dict[int, set[str]] = {}
    for s in result.setups:
        n = s.history.force.shape[1]
        for r in s.sensors:
            k = sensor_contacts(r.sensor.kind, r.sensor.particle, n)
            out.setdefault(r.sensor.particle, set()).update(int(c) + 1 for c in k)
            kinds.setdefault(r.sensor.particle, set()).add(r.sensor.kind.value)
    return {p: (sorted(out[p]), kinds[p]) for p in sorted(out)}


def _readers(particle: int, kinds: set[str]) -> str:
    """Who reads a column of contacts: "the coil at particle 13", or "the sensors at
    particle 13" when several kinds sit there (over the setups)."""
    if len(kinds) == 1:
        return f"the {sensor_name(next(iter(kinds)), particle)}"
    return f"the sensors at particle {particle}"


def contact_profiles(result: StudyResult, contacts: tuple[int, ...] | None = None,
                     t_max_s: float | None = None) -> Figure:
    """Dynamic force F_c - F_c,static at the contacts around the study's sensors (those each
    sensor kind averages), every setup (like the paper's Fig. 4), over the whole record.

    Parameters
    ----------
    result : StudyResult
    contacts : tuple of int, optional
        1-based contact numbers (contact c joins particles c and c+1), shown in one column.
        Default: one column per sensor position with the contacts its sensors read.
    t_max_s : float, optional
        Last time shown, s after impact (default: the whole record, reflected pulse included).

    Returns
    -------
    Figure
    """
    columns = ({0: (list(contacts), set())} if contacts is not None
               else _read_contacts(result))
    n_rows = max(len(c) for c, _ in columns.values())
    fig, axes = plt.subplots(n_rows, len(columns), figsize=(4.2 * len(columns) + 1.2,
                                                           1.45 * n_rows + 1.0),
                             sharex=True, sharey=True, squeeze=False)
    for j, (particle, (cs, kinds)) in enumerate(columns.items()):
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
                ax.plot(t[m] * _US, f[m], label=setup_name(s.setup.name), lw=0.9)
            ax.text(0.99, 0.92, contact_name(c), transform=ax.transAxes,
                    ha="right", va="top", fontsize=8)
            ax.grid(alpha=0.3)
        if contacts is None:
            axes[0, j].set_title(f"contacts read by {_readers(particle, kinds)}", fontsize=9)
        axes[len(cs) - 1, j].set_xlabel(TIME_LABEL)
        axes[len(cs) - 1, j].xaxis.set_tick_params(labelbottom=True)
    if len(result.setups) > 1:
        axes[0, -1].legend(fontsize=7, loc="center right")
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
    like the paper's Fig. 5.

    Parameters
    ----------
    result : StudyResult
    particle : int
        1-based particle of the sensors shown.
    window_s : (float, float)
        Time window shown, s since striker impact.

    Returns
    -------
    Figure
    """
    setups = [s for s in result.setups if any(r.sensor.particle == particle for r in s.sensors)]
    fig, axes = plt.subplots(1, len(setups), figsize=(4.0 * len(setups), 3.4), sharey=True,
                             squeeze=False)
    for ax, s in zip(axes[0], setups, strict=True):
        t = s.history.t
        m = (t >= window_s[0]) & (t <= window_s[1])
        for c in _sensor_contacts(s, particle):
            f = s.history.force[:, c - 1] - s.static_force[c - 1]
            ax.plot(t[m] * _US, f[m], "--", lw=0.9, label=contact_name(c, particles=False))
        reading = next(r for r in s.sensors if r.sensor.particle == particle)
        ax.plot(t[m] * _US, reading.force[m], "k", lw=1.6, label="sensor reading")
        ax.set_title(f"{sensor_name(reading.sensor.kind, particle)}\n"
                     f"({setup_name(s.setup.name)})", fontsize=9)
        ax.set_xlabel(TIME_LABEL)
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
                              label=sensor_name(r.sensor.kind, r.sensor.particle))
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
        ax.set_title(setup_name(s.setup.name), fontsize=9, loc="left")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(TIME_LABEL)
    axes[-1, 0].set_xlim(t[0], t[-1])
    fig.tight_layout()
    return fig


#: Table 2 quantities: (row key of the model value, reference key stem, axis name).
_TABLE2_QUANTITIES = (("tof", "time of flight"), ("ar", "amplitude ratio"))


def _table2_errors(r: dict, key: str) -> tuple[float, float, float]:
    """Per-cent errors of one row's quantity against the experiment: (msens, paper's model,
    experimental standard deviation), % of the experimental mean; NaN where not given."""
    ref = r.get("reference", {})
    suffix = "_us" if key == "tof" else ""
    exp = ref.get(f"experiment_{key}{suffix}", np.nan)
    std = ref.get(f"experiment_{key}_std{suffix}", np.nan)
    # a row whose record holds no reflected pulse has no TOF or AR (None)
    model, paper, exp, std = (np.nan if v is None else float(v) for v in (
        r.get(f"{key}{suffix}"), ref.get(f"paper_model_{key}{suffix}", np.nan), exp, std))
    with np.errstate(invalid="ignore", divide="ignore"):
        return (100.0 * (model - exp) / exp, 100.0 * (paper - exp) / exp,
                100.0 * std / abs(exp))


def table2(rows: list[dict], study: str | None = None) -> Figure:
    """Model error in time of flight and amplitude ratio against the published experiment,
    per sensor row, for msens and for the paper's model.

    Each row is a horizontal line: the experiment's ±1 standard deviation as a grey bar
    around 0 (the experiment is the origin), the paper's model and msens as markers above
    and below the line, so that neither hides the bar. A rule separates the setups.

    Parameters
    ----------
    rows : list of dict
        :meth:`msens.results.StudyResult.rows` (a row without a ``reference`` shows no
        marks).
    study : str, optional
        Study name, for the title.

    Returns
    -------
    Figure
    """
    n = len(rows)
    y = np.arange(n)[::-1].astype(float)  # first row on top
    labels = [f"{sensor_name(r['sensor'], r['particle'])}\n{r['position']}, "
              f"{setup_name(r['setup'])}" for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 0.62 * n + 1.7), sharey=True,
                             layout="constrained")
    for ax, (key, name) in zip(axes, _TABLE2_QUANTITIES, strict=True):
        err = np.array([_table2_errors(r, key) for r in rows]).reshape(n, 3)
        ours, paper, std = err.T
        ax.barh(y, 2 * std, left=-std, height=0.55, color="0.8", lw=0, zorder=1,
                label="experiment (paper), ±1 s.d.")
        ax.axvline(0.0, color="k", lw=0.8, zorder=2)
        ax.plot(paper, y + 0.15, "^", color="C0", ms=6, zorder=3, label="model (paper)")
        ax.plot(ours, y - 0.15, "o", color="C3", ms=6, zorder=3, label="model (msens)")
        for yi, v in zip(y, ours, strict=True):
            if np.isfinite(v):
                # a value that rounds to zero is written "+0.0 %", never "-0.0 %"
                ax.annotate(f"{round(v, 1) + 0.0:+.1f} %", (v, yi - 0.15), xytext=(6, 0),
                            textcoords="offset points", va="center", fontsize=7,
                            color="C3")
        lim = np.nanmax(np.abs(np.concatenate([ours, paper, std, [1.0]])))
        ax.set_xlim(-1.3 * lim, 1.45 * lim)
        ax.set_xlabel(f"{name}: model error (%)")
        ax.grid(alpha=0.3, axis="x")
        # a rule between setups
        for i in range(1, n):
            if rows[i]["setup"] != rows[i - 1]["setup"]:
                ax.axhline(y[i] + 0.5, color="0.5", lw=0.6)
    axes[0].set_yticks(y, labels, fontsize=8)
    axes[0].set_ylim(-0.5, n - 0.5)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=3, fontsize=8,
               frameon=False)
    title = ("Time of flight and amplitude ratio: model error against the paper's "
             "experiment,\n(model − experiment) / experiment")
    fig.suptitle(f"{title}, study {study}" if study else title, fontsize=10)
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


def _shot_stack(recs: list, values) -> tuple[np.ndarray, np.ndarray | None]:
    """Mean over shots of ``values(record)`` where every shot covers the sample (NaN
    elsewhere: a mean over fewer shots would jump at the edges), and the shots' standard
    deviation (None for one shot)."""
    stack = np.array([values(r) for r in recs])
    covered = np.all(np.isfinite(stack), axis=0)
    mean = np.where(covered, stack.mean(axis=0), np.nan)
    if len(recs) < 2:
        return mean, None
    return mean, np.where(covered, stack.std(axis=0, ddof=1), np.nan)


def _overlay_panels(sensor) -> list[str]:
    """Panels of one compared channel: the DAQ voltage first for a physics MsS (what the
    scope shows), then the compared record and its residual."""
    from msens.synth import is_physics_mss

    return (["voltage"] if is_physics_mss(sensor) else []) + ["record", "residual"]


def overlay(setup: SetupResult, shots: list, t_max_s: float | None = None) -> Figure:
    """Calibrated measurement over the model, and their difference, per channel, like the
    paper's Fig. 7(b, d, f).

    Each channel has a panel of the measured record (the mean over shots, with a ±1
    standard deviation band when there are several) over the model record it was compared
    with, processed the same way (:func:`msens.compare.model_record`): force in N for bead,
    rod and four-contact MsS channels, the integrated DAQ voltage in µV s for a physics MsS;
    and a panel of the residual, measured − model, in the same unit, with the noise of the
    shots' mean (rms of their scatter over √shots) as dashed lines. A physics MsS channel
    first shows the DAQ voltage itself (mV): the calibrated measured voltage (the time
    derivative of its integrated record, so a 1-2-1 average of neighbouring samples) over
    the model's.

    Parameters
    ----------
    setup : SetupResult
        The setup the data were matched to.
    shots : list of list of msens.compare.ShotRecord
        Aligned and calibrated records, per shot and channel (:func:`msens.compare.shot_records`).
    t_max_s : float, optional
        Last time shown, s since striker impact (default: the whole model record).

    Returns
    -------
    Figure
    """
    from msens.compare import gain_unit, model_record

    sensors = setup.sensors
    kinds = [p for s in sensors for p in _overlay_panels(s)]
    ratios = [1.0 if k == "residual" else 2.0 for k in kinds]
    fig, axes = plt.subplots(len(kinds), 1, figsize=(7, 1.05 * sum(ratios) + 1.0),
                             sharex=True, squeeze=False, layout="constrained",
                             gridspec_kw={"height_ratios": ratios})
    t = setup.history.t
    m = np.ones(t.size, bool) if t_max_s is None else t <= t_max_s
    t_us = t[m] * _US
    handles: dict = {}  # legend label -> artist(s), first channel's win
    row = iter(axes[:, 0])

    def measured(ax, mean, std, n: int) -> None:
        (line,) = ax.plot(t_us, mean, color="k", lw=0.9, gid="measured")
        handle, label = line, "measured"
        if std is not None:
            band = ax.fill_between(t_us, mean - std, mean + std, color="0.7", lw=0,
                                   gid="measured scatter")
            handle, label = (band, line), f"measured, mean ± 1 s.d. of {n} shots"
        handles.setdefault(label, handle)

    for sensor in sensors:
        recs = [r for shot in shots for r in shot
                if r.channel.kind == sensor.sensor.kind.value
                and r.channel.particle == sensor.sensor.particle]
        quantity, scale, unit = _overlay_quantity(sensor)
        # the record the measurement was calibrated against, not the chain force: for a
        # physics MsS these differ in unit (V s against N)
        model = next((r.model for r in recs if r.model is not None), None)
        if model is None:
            model = model_record(sensor, t)
        model = model[m] * scale
        first = None
        for kind in _overlay_panels(sensor):
            ax = next(row)
            first = first or ax
            ax.grid(alpha=0.3)
            if kind == "voltage":
                if recs:
                    mean, std = _shot_stack(recs, lambda r: r.gain * np.gradient(r.raw, t))
                    measured(ax, mean[m] * 1e3, None if std is None else std[m] * 1e3,
                             len(recs))
                (line,) = ax.plot(t_us, np.asarray(sensor.voltage_shape)[m] * 1e3,
                                  color="C3", ls="--", lw=1.1, gid="model voltage")
                handles.setdefault("model", line)
                ax.set_ylabel("DAQ voltage\n(mV)")
            elif kind == "record":
                if recs:
                    mean, std = _shot_stack(recs, lambda r: r.force)
                    measured(ax, mean[m] * scale, None if std is None else std[m] * scale,
                             len(recs))
                (line,) = ax.plot(t_us, model, color="C3", ls="--", lw=1.1, gid="model")
                handles.setdefault("model", line)
                ax.set_ylabel(f"{quantity}\n({unit})")
            else:
                if recs:
                    mean, std = _shot_stack(recs, lambda r: r.force)
                    res = mean[m] * scale - model
                    (line,) = ax.plot(t_us, res, color="C0", lw=0.7, gid="residual")
                    handles.setdefault("measured − model", line)
                    if std is not None:
                        # the noise of a mean over the shots: their scatter's rms / √n
                        noise = float(np.sqrt(np.nanmean(std[m] ** 2) / len(recs))) * scale
                        for sign in (-1, 1):
                            edge = ax.axhline(sign * noise, color="k", ls="--", lw=0.8,
                                              gid="residual noise")
                        handles.setdefault("±1 s.d. of the shots' mean (noise)", edge)
                ax.axhline(0.0, color="0.3", lw=0.7)
                ax.set_ylabel(f"residual\n({unit})")
        first.set_title(sensor_name(sensor.sensor.kind, sensor.sensor.particle), loc="left",
                        fontsize=9)
        if recs:
            gain = float(np.mean([r.gain for r in recs]))
            first.set_title(f"calibration factor K = {_overlay_number(gain)} "
                            f"{gain_unit(sensor)}", loc="right", fontsize=9)
    fig.legend(list(handles.values()), list(handles), fontsize=8, loc="outside lower center",
               ncol=2, frameon=False, handler_map={tuple: HandlerTuple(ndivide=1)})
    axes[-1, 0].set_xlabel(TIME_LABEL)
    axes[-1, 0].set_xlim(t_us[0], t_us[-1])
    fig.align_ylabels(axes[:, 0])
    fig.suptitle(f"Measured (aligned, calibrated) and model records, "
                 f"{setup_name(setup.setup.name)}", fontsize=10)
    return fig

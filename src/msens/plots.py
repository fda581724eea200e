"""Figures of chain studies (matplotlib, Agg). Each function returns a Figure."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple

from msens.pipeline import SetupResult, StudyResult

_US = 1e6


def contact_profiles(result: StudyResult, contacts: tuple[int, ...] = (8, 11, 12, 13),
                     t_max_s: float = 400e-6) -> Figure:
    """Dynamic force at some contacts for every setup (like the paper's Fig. 4).

    Parameters
    ----------
    contacts : tuple of int
        1-based contact numbers (c_i joins particles i and i+1).
    """
    fig, axes = plt.subplots(len(contacts), 1, figsize=(7, 2.0 * len(contacts)), sharex=True)
    for ax, c in zip(np.atleast_1d(axes), contacts, strict=True):
        for s in result.setups:
            t = s.history.t
            m = t <= t_max_s
            f = s.history.force[:, c - 1] - s.static_force[c - 1]
            ax.plot(t[m] * _US, f[m], label=s.setup.name, lw=1.1)
        ax.set_ylabel(f"c{c} force (N)")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time (µs)")
    fig.suptitle("Dynamic contact forces")
    fig.tight_layout()
    return fig


def _sensor_contacts(setup: SetupResult, particle: int) -> list[int]:
    from msens.sensors import sensor_contacts

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


def sensor_records(result: StudyResult) -> Figure:
    """Full records of every sensor, with the incident and reflected peaks marked."""
    fig, axes = plt.subplots(len(result.setups), 1, figsize=(7, 2.4 * len(result.setups)),
                             sharex=True, squeeze=False)
    for ax, s in zip(axes[:, 0], result.setups, strict=True):
        t = s.history.t * _US
        for r in s.sensors:
            (line,) = ax.plot(t, r.force, lw=1.0,
                              label=f"{r.sensor.kind.value}@{r.sensor.particle}")
            f = r.features
            ax.plot([f.t_incident * _US, f.t_reflected * _US], [f.f_incident, f.f_reflected],
                    "o", color=line.get_color(), ms=4)
        ax.set_ylabel("force (N)")
        ax.set_title(s.setup.name, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time since impact (µs)")
    fig.tight_layout()
    return fig


def table2(rows: list[dict]) -> Figure:
    """Model TOF and AR against the published experiment and the published model."""
    labels = [f"{r['setup']} {r['position']}" for r in rows]
    x = np.arange(len(rows))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, key, unit in ((a1, "tof", "µs"), (a2, "ar", "")):
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
        ax.set_ylabel(f"{key.upper()} ({unit})" if unit else key.upper())
        ax.grid(alpha=0.3)
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


def _physics(result: StudyResult):
    """(setup, sensor) pairs of physics MsS sensors."""
    return [(s, r) for s in result.setups for r in s.sensors if r.mss is not None]


def mss_voltages(result: StudyResult, t_max_s: float = 600e-6) -> Figure:
    """Predicted coil EMF and DAQ voltage of every physics MsS."""
    pairs = _physics(result)
    fig, axes = plt.subplots(len(pairs), 1, figsize=(7, 2.6 * len(pairs)), sharex=True,
                             squeeze=False)
    for ax, (_, r) in zip(axes[:, 0], pairs, strict=True):
        m = r.mss
        keep = m.t <= t_max_s
        kd = m.t_daq <= t_max_s
        ax.plot(m.t[keep] * _US, m.emf[keep] * 1e3, color="0.6", lw=1.0, label="EMF")
        ax.plot(m.t_daq[kd] * _US, m.voltage[kd] * 1e3, "C0", lw=1.2, label="at the DAQ")
        ax.set_ylabel(f"coil @{r.sensor.particle} (mV)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time since impact (µs)")
    fig.suptitle("Predicted MsS voltage: contact approach + Villari (field model), chain, "
                 "read-out")
    fig.tight_layout()
    return fig


def mss_integrated(result: StudyResult, t_max_s: float = 600e-6) -> Figure:
    """Sensitivity-weighted contact force (the integrated coil signal) next to the paper's
    four-contact average on the same chain run."""
    from msens.sensors import mss_four_contact

    pairs = _physics(result)
    fig, axes = plt.subplots(len(pairs), 1, figsize=(7, 2.6 * len(pairs)), sharex=True,
                             squeeze=False)
    for ax, (s, r) in zip(axes[:, 0], pairs, strict=True):
        t = s.history.t
        keep = t <= t_max_s
        four = mss_four_contact(s.history.force, r.sensor.particle)
        ax.plot(t[keep] * _US, four[keep], "k--", lw=1.0, label="four-contact mean (paper)")
        ax.plot(t[keep] * _US, r.force[keep], "C3", lw=1.2,
                label="physics: flux change ΔΛ / Σ_c ∂Λ/∂F_c (both mechanisms)")
        ax.set_ylabel(f"coil @{r.sensor.particle}: force or\nforce equivalent (N)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time since impact (µs)")
    fig.suptitle("Integrated MsS signal (coil flux change in newtons at the static-load "
                 "sensitivity)\nvs the paper's four-contact mean force")
    fig.tight_layout()
    return fig


def sensitivity_profile(result: StudyResult) -> Figure:
    """∂Λ/∂F_c along the chain for each physics MsS, by mechanism."""
    pairs = _physics(result)
    fig, ax = plt.subplots(figsize=(7, 3.4))
    for i, (s, r) in enumerate(pairs):
        tr = s.transducers[r.sensor.particle]
        c = np.asarray(tr.contacts)
        ax.plot(c, np.asarray(tr.sensitivity_villari) * 1e9, "o-", color=f"C{i}", ms=3,
                label=f"coil @{r.sensor.particle}: Villari")
        ax.plot(c, np.asarray(tr.sensitivity_approach) * 1e9, "s--", color=f"C{i}", ms=3,
                alpha=0.6, label=f"coil @{r.sensor.particle}: contact approach")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("contact c (joins particles c and c+1)")
    ax.set_ylabel("∂Λ/∂F_c (nWb/N)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig

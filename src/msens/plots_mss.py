"""Figures of physics-MsS runs (matplotlib, Agg): DAQ voltages, their integrals, the coils'
sensitivity profiles and the magnets' precompression. Each function returns a Figure."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple
from matplotlib.ticker import MultipleLocator

from msens.plots import _US
from msens.results import SetupResult, StudyResult
from msens.vocabulary import CONTACT_AXIS, TIME_LABEL, coil_name


def _physics(result: StudyResult):
    """(setup, sensor) pairs of physics MsS sensors."""
    return [(s, r) for s in result.setups for r in s.sensors if r.mss is not None]


def _field_model_text(result: StudyResult) -> str:
    f = result.study.field
    model = "eddy currents" if f.eddy_currents else "magnetostatic"
    if f.small_signal_permeability != "differential":
        model += f", {f.small_signal_permeability} permeability"
    if f.contact_map:
        model += ", nonlinear contact maps"
    return model


def mss_voltages(result: StudyResult, t_max_s: float = 600e-6) -> Figure:
    """Predicted coil EMF and DAQ voltage of every physics MsS, and what the read-out does
    to it: per coil, a panel of both voltages and a panel of their difference (DAQ − EMF,
    the EMF interpolated onto the DAQ samples), on a scale of its own.

    Parameters
    ----------
    result : StudyResult
    t_max_s : float
        Last time shown, s since striker impact.

    Returns
    -------
    Figure
    """
    pairs = _physics(result)
    fig, axes = plt.subplots(2 * len(pairs), 1, figsize=(7, 3.4 * len(pairs) + 0.9),
                             sharex=True, squeeze=False,
                             gridspec_kw={"height_ratios": [2.2, 1.0] * len(pairs)})
    for k, (_, r) in enumerate(pairs):
        ax, dax = axes[2 * k, 0], axes[2 * k + 1, 0]
        m = r.mss
        keep = m.t <= t_max_s
        kd = m.t_daq <= t_max_s
        ax.plot(m.t[keep] * _US, m.emf[keep] * 1e3, color="0.55", lw=1.0,
                label="coil EMF")
        ax.plot(m.t_daq[kd] * _US, m.voltage[kd] * 1e3, "C0", lw=1.0, ls="--",
                label="at the DAQ input")
        ax.set_ylabel("voltage (mV)")
        ax.set_title(coil_name(r.sensor.particle), loc="left", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
        diff = m.voltage[kd] - np.interp(m.t_daq[kd], m.t, m.emf)
        dax.plot(m.t_daq[kd] * _US, diff * 1e3, "C3", lw=1.0)
        dax.axhline(0.0, color="0.4", lw=0.7)
        dax.set_ylabel("DAQ − EMF\n(mV)")
        dax.grid(alpha=0.3)
        peak = float(np.max(np.abs(m.emf[keep]))) if keep.any() else float("nan")
        dax.set_title(f"read-out: largest change {np.max(np.abs(diff)) * 1e3:.3g} mV, "
                      f"{100 * np.max(np.abs(diff)) / peak:.2g} % of the EMF's peak",
                      loc="left", fontsize=8)
    fig.align_ylabels(axes[:, 0])
    axes[-1, 0].set_xlabel(TIME_LABEL)
    fig.suptitle("Predicted MsS voltage: contact approach + Villari, chain, read-out\n"
                 f"(field model: {_field_model_text(result)})", fontsize=10)
    fig.tight_layout()
    return fig


def mss_integrated(result: StudyResult, t_max_s: float = 600e-6) -> Figure:
    """Sensitivity-weighted contact force (the integrated coil signal) next to the paper's
    four-contact average on the same chain run.

    Parameters
    ----------
    result : StudyResult
    t_max_s : float
        Last time shown, s since striker impact.

    Returns
    -------
    Figure
    """
    from msens.readout.sensors import mss_four_contact

    pairs = _physics(result)
    fig, axes = plt.subplots(len(pairs), 1, figsize=(7, 2.7 * len(pairs) + 0.4), sharex=True,
                             squeeze=False)
    for ax, (s, r) in zip(axes[:, 0], pairs, strict=True):
        t = s.history.t
        keep = t <= t_max_s
        four = mss_four_contact(s.history.force, r.sensor.particle)
        ax.plot(t[keep] * _US, four[keep], "k--", lw=1.0,
                label="four-contact mean force (paper's model)")
        ax.plot(t[keep] * _US, r.force[keep], "C3", lw=1.2,
                label=r"flux change $\Delta\Lambda\,/\,\Sigma_c\,\partial\Lambda/"
                      r"\partial F_c$ (both mechanisms)")
        ax.set_ylabel("force or force\nequivalent (N)")
        ax.set_title(coil_name(r.sensor.particle), loc="left", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel(TIME_LABEL)
    fig.suptitle("Integrated MsS signal (coil flux change in newtons at the static-load "
                 "sensitivity)\nagainst the paper's four-contact mean force", fontsize=10)
    fig.tight_layout()
    return fig


def _part_spans(result: StudyResult, setup: SetupResult) -> list[tuple[str, int, float, float]]:
    """Coils and pole pieces of a setup's MsS on the contact axis.

    Contact c lies (count - c) bead pitches above the wall and particle p's centre at
    contact coordinate p - 1/2, so a part from z0 to z1 covers count - z1/pitch ..
    count - z0/pitch.

    Returns
    -------
    list of (kind, particle, c0, c1)
        ``kind`` is "coil" or "pole"; empty when the setup has no field-model geometry.
    """
    from msens.config.fieldsetup import geometry_from_study
    from msens.errors import InputError

    try:
        g = geometry_from_study(result.study, setup.setup)
    except InputError:  # no MsS or no valid geometry: nothing to mark
        return []
    b = g.beads
    pitch = b.pitch
    z_wall = b.contact_z(b.count)  # the wall contact's plane (0 for touching beads)

    def span(r) -> tuple[float, float]:
        return (b.count - (r.z1 - z_wall) / pitch, b.count - (r.z0 - z_wall) / pitch)

    out = []
    for u in g.iter_units():
        out.append(("coil", u.coil.particle, *span(g.coil_rect(u))))
        out += [("pole", u.coil.particle, *span(r)) for r in g.magnet_rects(u)
                if r.name.startswith("pole_")]
    return out


#: Opacity of a coil winding's band, in the plot and in its legend patch.
_WINDING_ALPHA = 0.15


def _mark_parts(ax, spans, colors: dict[int, str], *, label: bool) -> None:
    """Shade coil windings (in their coil's colour) and pole pieces (grey hatched) on a
    contact axis; name the coils above the top panel when ``label``."""
    for kind, particle, c0, c1 in spans:
        if kind == "coil":
            ax.axvspan(c0, c1, color=colors.get(particle, "0.5"), alpha=_WINDING_ALPHA, lw=0)
            if label:
                # on two lines: neighbouring coils' names must not run into each other
                ax.text((c0 + c1) / 2, 1.01, coil_name(particle).replace(" at ", " at\n"),
                        ha="center", va="bottom", linespacing=1.0,
                        transform=ax.get_xaxis_transform(), fontsize=7,
                        color=colors.get(particle, "0.3"))
        else:
            ax.axvspan(c0, c1, facecolor="0.85", edgecolor="0.55", hatch="///", lw=0.0,
                       alpha=0.6, zorder=0)


def _parts_legend(spans, colors: dict[int, str]) -> tuple[list, list[str]]:
    """Legend entries of :func:`_mark_parts`' shading, drawn as in the plot: one entry for
    the windings with a patch in each coil's colour, one for the pole pieces.

    Returns
    -------
    handles, labels : list
        Handles (a tuple of patches for the windings: pass
        ``handler_map={tuple: HandlerTuple(ndivide=None)}``) and their labels.
    """
    from matplotlib.patches import Patch

    handles, labels = [], []
    coils = list(dict.fromkeys(p for k, p, *_ in spans if k == "coil"))
    if coils:
        handles.append(tuple(Patch(facecolor=colors.get(p, "0.5"), alpha=_WINDING_ALPHA,
                                   lw=0) for p in coils))
        labels.append("coil winding (in its coil's colour)" if len(coils) > 1
                      else "coil winding")
    if any(k == "pole" for k, *_ in spans):
        handles.append(Patch(facecolor="0.85", edgecolor="0.55", hatch="///", alpha=0.6,
                             lw=0.0))
        labels.append("magnet pole pieces")
    return handles, labels


def sensitivity_profile(result: StudyResult) -> Figure:
    """∂Λ/∂F_c along the chain for each physics MsS: the contact approach and the Villari
    effect on panels of their own (the Villari sensitivity is ~60 times smaller), coil
    windings and magnet pole pieces marked along the contact axis.

    The contact approach is linearised at the transducer's static reference load.
    """
    pairs = _physics(result)
    fig, (a_app, a_vil) = plt.subplots(2, 1, figsize=(7, 5.4), sharex=True)
    colors = {r.sensor.particle: f"C{i}" for i, (_, r) in enumerate(pairs)}
    sums = {"approach": 0.0, "villari": 0.0}
    done = set()
    for s, r in pairs:
        tr = s.transducers[r.sensor.particle]
        c = np.asarray(tr.contacts)
        col = colors[r.sensor.particle]
        a_app.plot(c, tr.sensitivity_approach * 1e9, "s-", color=col, ms=3, lw=1.1,
                   label=coil_name(r.sensor.particle))
        a_vil.plot(c, np.asarray(tr.sensitivity_villari) * 1e9, "o-", color=col, ms=3,
                   lw=1.1, label=coil_name(r.sensor.particle))
        sums["approach"] += float(np.sum(np.abs(tr.sensitivity_approach)))
        sums["villari"] += float(np.sum(np.abs(tr.sensitivity_villari)))
        if s.setup.name not in done:
            done.add(s.setup.name)
            spans = _part_spans(result, s)
            for ax in (a_app, a_vil):
                _mark_parts(ax, spans, colors, label=ax is a_app)
    f0 = pairs[0][0].transducers[pairs[0][1].sensor.particle].reference_force if pairs else 0
    ratio = sums["approach"] / sums["villari"] if sums["villari"] else float("nan")
    a_app.set_title(f"contact approach (linearised at the static load {f0:.2f} N)",
                    fontsize=9, loc="left", pad=22)
    a_vil.set_title(r"Villari effect (own scale: $\Sigma_c\,|\partial\Lambda/\partial F_c|$ is "
                    f"{ratio:.0f} times smaller)", fontsize=9, loc="left")
    for ax in (a_app, a_vil):
        ax.axhline(0.0, color="0.4", lw=0.7)
        ax.set_ylabel(r"$\partial\Lambda/\partial F_c$ (nWb/N)")
        ax.grid(alpha=0.3)
    handles, labels = a_app.get_legend_handles_labels()
    parts, names = _parts_legend([x for s, _ in pairs[:1] for x in _part_spans(result, s)],
                                 colors)
    a_app.legend(handles + parts, labels + names, fontsize=7, loc="lower left",
                 handler_map={tuple: HandlerTuple(ndivide=None, pad=0)})
    a_vil.set_xlabel(CONTACT_AXIS)
    a_vil.xaxis.set_minor_locator(MultipleLocator(1))  # one tick per contact
    fig.tight_layout()
    return fig


#: The paper's guessed magnetic precompression of the four contacts around each coil, N.
PAPER_PRECOMPRESSION_N = 1.8


def magnetic_precompression(result: StudyResult) -> Figure:
    """Static compression of every contact by the bias magnets, per physics-MsS setup, coil
    windings and pole pieces marked, against the paper's guessed 1.8 N on the four contacts
    p-2 .. p+1 around the coil at particle p.

    The compression of contact c is the magnets' pull on particles 1..c toward the wall
    (the same numbers as ``magnetic_precompression_N`` in ``summary.json``).
    """
    from msens.magnetics.transducer import magnetic_precompression as particle_forces

    setups = [s for s in result.setups if s.transducers]
    fig, ax = plt.subplots(figsize=(7, 4.0))
    width = 0.8 / max(len(setups), 1)
    colors = {}
    for i, s in enumerate(setups):
        force = np.cumsum(particle_forces(s.transducers))[:-1]  # contacts 1 .. n-1
        c = np.arange(1, force.size + 1)
        x = c + (i - (len(setups) - 1) / 2) * width
        ax.bar(x, force, width, color=f"C{i}" if len(setups) > 1 else "C2",
               label=f"field model (magnets' pull on the beads), setup {s.setup.name}"
               if len(setups) > 1 else "field model (magnets' pull on the beads)", zorder=2)
        for xi, fi in zip(x, force, strict=True):
            if abs(fi) >= 0.1:
                ax.text(xi, fi, f"{fi:.2f}", ha="center", va="bottom" if fi > 0 else "top",
                        fontsize=6)
        for j, r in enumerate(q for q in s.sensors if q.mss is not None):
            colors.setdefault(r.sensor.particle, f"C{j}")
            p = r.sensor.particle
            ax.hlines(PAPER_PRECOMPRESSION_N, p - 2 - 0.45, p + 1 + 0.45, colors="k",
                      linestyles="--", lw=1.2, zorder=3,
                      label=f"paper's guess: {PAPER_PRECOMPRESSION_N} N on the four "
                            "contacts of each coil" if j == 0 and i == 0 else None)
    spans = _part_spans(result, setups[0]) if setups else []
    _mark_parts(ax, spans, colors, label=True)
    ax.axhline(0.0, color="0.4", lw=0.7)
    ax.set_ylim(top=1.1 * max(ax.get_ylim()[1], PAPER_PRECOMPRESSION_N))  # room for values
    handles, labels = ax.get_legend_handles_labels()
    parts, names = _parts_legend(spans, colors)
    # below the axes: the tallest bars sit in the middle, under any inside corner
    ax.legend(handles + parts, labels + names, fontsize=7, ncol=2, loc="upper center",
              bbox_to_anchor=(0.5, -0.2), frameon=False,
              handler_map={tuple: HandlerTuple(ndivide=None, pad=0)})
    ax.set_xlabel(CONTACT_AXIS)
    ax.set_ylabel("static magnetic compression (N)")
    ax.xaxis.set_minor_locator(MultipleLocator(1))
    ax.set_title("Magnetic precompression of the contacts by the bias magnets", fontsize=9,
                 loc="left", pad=22)
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    return fig

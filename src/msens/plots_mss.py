"""Figures of physics-MsS runs (matplotlib, Agg): DAQ voltages, their integrals, the coils'
sensitivity profiles and the magnets' precompression. Each function returns a Figure."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MultipleLocator

from msens.plots import _US
from msens.results import SetupResult, StudyResult


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
    f = result.study.field
    model = "eddy currents" if f.eddy_currents else "magnetostatic"
    if f.small_signal_permeability != "differential":
        model += f", {f.small_signal_permeability} permeability"
    if f.contact_map:
        model += ", nonlinear contact maps"
    fig.suptitle("Predicted MsS voltage: contact approach + Villari, chain, read-out\n"
                 f"(field model: {model})", fontsize=10)
    fig.tight_layout()
    return fig


def mss_integrated(result: StudyResult, t_max_s: float = 600e-6) -> Figure:
    """Sensitivity-weighted contact force (the integrated coil signal) next to the paper's
    four-contact average on the same chain run."""
    from msens.readout.sensors import mss_four_contact

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


def _mark_parts(ax, spans, colors: dict[int, str], *, label: bool) -> None:
    """Shade coil windings (in their coil's colour) and pole pieces (grey hatched) on a
    contact axis; name the coils above the top panel when ``label``."""
    for kind, particle, c0, c1 in spans:
        if kind == "coil":
            ax.axvspan(c0, c1, color=colors.get(particle, "0.5"), alpha=0.12, lw=0)
            if label:
                ax.text((c0 + c1) / 2, 1.01, f"coil @{particle}", ha="center", va="bottom",
                        transform=ax.get_xaxis_transform(), fontsize=7,
                        color=colors.get(particle, "0.3"))
        else:
            ax.axvspan(c0, c1, facecolor="0.85", edgecolor="0.55", hatch="///", lw=0.0,
                       alpha=0.6, zorder=0)


def _parts_legend_handles(spans) -> list:
    from matplotlib.patches import Patch

    out = []
    if any(k == "coil" for k, *_ in spans):
        out.append(Patch(facecolor="0.5", alpha=0.15, label="coil winding"))
    if any(k == "pole" for k, *_ in spans):
        out.append(Patch(facecolor="0.85", edgecolor="0.55", hatch="///",
                         label="magnet pole pieces"))
    return out


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
                   label=f"coil @{r.sensor.particle}")
        a_vil.plot(c, np.asarray(tr.sensitivity_villari) * 1e9, "o-", color=col, ms=3,
                   lw=1.1, label=f"coil @{r.sensor.particle}")
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
                    fontsize=9, loc="left", pad=14)
    a_vil.set_title(r"Villari effect (own scale: $\Sigma_c\,|\partial\Lambda/\partial F_c|$ is "
                    f"{ratio:.0f} times smaller)", fontsize=9, loc="left")
    for ax in (a_app, a_vil):
        ax.axhline(0.0, color="0.4", lw=0.7)
        ax.set_ylabel(r"$\partial\Lambda/\partial F_c$ (nWb/N)")
        ax.grid(alpha=0.3)
    handles, _ = a_app.get_legend_handles_labels()
    a_app.legend(handles=handles + _parts_legend_handles(
        [x for s, _ in pairs[:1] for x in _part_spans(result, s)]), fontsize=7,
        loc="lower left")
    a_vil.set_xlabel("contact c (joins particles c and c+1)")
    a_vil.xaxis.set_minor_locator(MultipleLocator(1))  # one tick per contact
    fig.tight_layout()
    return fig


#: The paper's guessed magnetic precompression of the four contacts around each coil, N.
PAPER_PRECOMPRESSION_N = 1.8


def magnetic_precompression(result: StudyResult) -> Figure:
    """Static compression of every contact by the bias magnets, per physics-MsS setup, coil
    windings and pole pieces marked, against the paper's guessed 1.8 N on the four contacts
    c_{p-2} .. c_{p+1} around each coil.

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
    handles, _ = ax.get_legend_handles_labels()
    # below the axes: the tallest bars sit in the middle, under any inside corner
    ax.legend(handles=handles + _parts_legend_handles(spans), fontsize=7, ncol=2,
              loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False)
    ax.set_xlabel("contact c (joins particles c and c+1)")
    ax.set_ylabel("static magnetic compression (N)")
    ax.xaxis.set_minor_locator(MultipleLocator(1))
    ax.set_title("Magnetic precompression of the contacts by the bias magnets", fontsize=9,
                 loc="left", pad=14)
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    return fig

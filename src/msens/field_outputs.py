"""Outputs of the sensor field model: field.json, field.vtu, figures.

- ``field.json``: coils (R, L), bead fields, contact forces, the axial profile, solver data and
  the statement that the magnet is an equivalent (schema ``msens.field/1``).
- ``field.vtu``: the meridian-plane mesh (x = r, y = z, metres) with A_φ and ψ = r A_φ at the
  vertices and B, |B| and the region number per triangle (ParaView: "Threshold" on region).
- ``field_B.png`` (``.pdf``, ``.svg`` by ``fig_format``): |B| map with field lines (contours of
  ψ, which are exactly the field lines of an axisymmetric field), parts outlined and named,
  zoomed on the sensors.
- ``field_3d.png``: the meridian solution revolved through 270° (pyvista, off-screen EGL).
  When pyvista cannot render, the figure is skipped and :func:`write_field_outputs` returns the
  reason under ``"field_3d.png"`` instead of a path.

All files are written atomically (:func:`msens.io.atomic.atomic_write`).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from msens.field.forms import flux_density_qp
from msens.field.sensor_model import FieldReport
from msens.io.atomic import atomic_write

SCHEMA = "msens.field/1"


def _atomic(path: Path, write: Callable[[str], None]) -> Path:
    """Call ``write(tmp_path)`` then move the temporary file onto ``path``
    (:func:`msens.io.atomic.atomic_write`)."""
    return atomic_write(path, lambda tmp: write(str(tmp)))


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def report_dict(report: FieldReport) -> dict:
    """The JSON-ready content of ``field.json``."""
    g = report.geometry
    return {
        "schema": SCHEMA,
        "note": report.note,
        "coils": [{"particle": c.particle, "turns": c.turns,
                   "resistance_ohm": c.resistance_ohm,
                   "inductance_H": _finite(c.inductance_H),
                   "air_core_inductance_H": _finite(c.air_core_inductance_H),
                   "inner_radius_m": c.inner_radius_m, "outer_radius_m": c.outer_radius_m,
                   "length_m": c.length_m} for c in report.coils],
        "beads": [{"particle": b.particle, "B_center_T": list(b.B_center_T),
                   "Bz_mean_T": b.Bz_mean_T} for b in report.beads],
        "contacts": [{"upper": c.upper, "lower": c.lower,
                      "magnetic_force_N": c.magnetic_force_N} for c in report.contacts],
        "axis": {"z_m": report.axis_z_m.tolist(), "Bz_T": report.axis_Bz_T.tolist()},
        "newton_iterations": report.newton_iterations,
        "newton_residuals": list(report.newton_residuals),
        "dofs": report.dofs,
        "elements": report.elements,
        "mesh": str(report.mesh_path),
        "timings_s": dict(report.timings_s),
        "model": {
            "beads": [g.beads.first, g.beads.last], "bead_diameter_m": g.beads.diameter,
            "contact_flat_radius_m": g.beads.flat_radius,
            "contact_gap_m": g.beads.contact_gap,
            "air_box": {"radius_m": g.air.radius, "margin_m": g.air.margin},
            "magnets": [{"particle": u.magnet.particle, "grade": u.magnet.grade,
                         "remanence_T": u.magnet.remanence,
                         "recoil_permeability": u.magnet.recoil_permeability}
                        for u in g.iter_units() if u.magnet is not None],
            "steel_bh": {"name": g.steel.name, "source": g.steel.source,
                         "B_T": [float(x) for x in g.steel.b],
                         "H_A_per_m": [float(x) for x in g.steel.h]},
            "force_sign": "magnetic_force_N > 0 compresses the contact",
            "z_origin": "wall (chain base) at z = 0, z upwards",
        },
    }


def write_json(report: FieldReport, path: str | Path) -> Path:
    """Write ``field.json``."""
    text = json.dumps(report_dict(report), indent=1)
    return _atomic(Path(path), lambda tmp: Path(tmp).write_text(text))


def _element_fields(report: FieldReport) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Mean B per triangle (n_elements, 2), region index per triangle, region names."""
    sol = report.solution
    q = sol.disc.quad
    b = flux_density_qp(q, sol.a)
    w = q.w / q.w.sum(axis=1, keepdims=True)
    b_mean = np.einsum("eq,eqc->ec", w, b)
    names = sorted(sol.problem.mesh.subdomains)
    region = np.zeros(b.shape[0], dtype=np.int32)
    for i, n in enumerate(names):
        region[sol.problem.mesh.subdomains[n]] = i
    return b_mean, region, names


def _vertex_potential(report: FieldReport) -> np.ndarray:
    """A_φ at the mesh vertices, T m."""
    sol = report.solution
    return sol.a[sol.basis.nodal_dofs[0]]


def write_vtu(report: FieldReport, path: str | Path) -> Path:
    """Write the meridian solution as VTU (meshio)."""
    import meshio

    mesh = report.solution.problem.mesh.mesh
    b_mean, region, _ = _element_fields(report)
    a = _vertex_potential(report)
    pts = np.column_stack([mesh.p[0], mesh.p[1], np.zeros(mesh.p.shape[1])])
    b3 = np.column_stack([b_mean, np.zeros(len(b_mean))])
    out = meshio.Mesh(
        pts, [("triangle", mesh.t.T)],
        point_data={"A_phi": a, "psi": a * mesh.p[0]},
        cell_data={"B": [b3], "B_magnitude": [np.linalg.norm(b_mean, axis=1)],
                   "region": [region]})
    return _atomic(Path(path), lambda tmp: meshio.write(tmp, out, file_format="vtu"))


def _refined_psi(report: FieldReport) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """ψ = r A_φ on the mesh split into four triangles per element (vertices and edge
    midpoints, where the P2 potential has its nodal values), for smooth field lines.

    Returns
    -------
    r, z : ndarray
        Node coordinates, m.
    triangles : ndarray, shape (4 n_elements, 3)
    psi : ndarray
        r A_φ at the nodes, T m² (Wb per radian).
    """
    sol = report.solution
    mesh = sol.basis.mesh
    p, t = mesh.p, mesh.t
    a = sol.a[sol.basis.nodal_dofs[0]]
    if sol.basis.facet_dofs.size == 0:  # P1: the vertices are all there is
        return p[0], p[1], t.T, a * p[0]
    mid = 0.5 * (p[:, mesh.facets[0]] + p[:, mesh.facets[1]])
    r = np.concatenate([p[0], mid[0]])
    z = np.concatenate([p[1], mid[1]])
    psi = r * np.concatenate([a, sol.a[sol.basis.facet_dofs[0]]])
    n = p.shape[1]
    v0, v1, v2 = t
    # skfem's edge order of a triangle: (0, 1), (1, 2), (0, 2)
    m01, m12, m02 = n + mesh.t2f
    tri = np.concatenate([np.stack([v0, m01, m02]), np.stack([v1, m12, m01]),
                          np.stack([v2, m02, m12]), np.stack([m01, m12, m02])], axis=1)
    return r, z, tri.T, psi


def _smooth_bmag(ax, report: FieldReport, b_elem: np.ndarray, norm, cmap, scale: float,
                 keep: np.ndarray):
    """|B| drawn with Gouraud shading, region by region: vertex values are area-weighted
    means over the region's own triangles, so a bead's 1.5 T does not bleed into the air."""
    from matplotlib.tri import Triangulation

    sol = report.solution
    mesh = sol.problem.mesh.mesh
    x, y = mesh.p
    t = mesh.t
    area = 0.5 * np.abs((x[t[1]] - x[t[0]]) * (y[t[2]] - y[t[0]])
                        - (x[t[2]] - x[t[0]]) * (y[t[1]] - y[t[0]]))
    pc = None
    for elements in sol.problem.mesh.subdomains.values():
        e = np.asarray(elements)
        e = e[keep[e]]
        if e.size == 0:
            continue
        num = np.zeros(x.size)
        den = np.zeros(x.size)
        for k in range(3):
            np.add.at(num, t[k, e], area[e] * b_elem[e])
            np.add.at(den, t[k, e], area[e])
        used = den > 0
        vals = np.where(used, num / np.where(used, den, 1.0), 1.0)
        tri = Triangulation(scale * x, scale * y, t[:, e].T)
        pc = ax.tripcolor(tri, vals, shading="gouraud", norm=norm, cmap=cmap,
                          rasterized=True)
    return pc


def _outline(ax, report: FieldReport, scale: float, z_view: tuple[float, float]) -> None:
    """Outline and name the parts: beads, tube, and each sensor's coil, magnet and pole
    pieces (labels only for the parts inside ``z_view``, m)."""
    from matplotlib.patches import Rectangle

    g = report.geometry
    box = {"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.75}
    z_lo, z_hi = z_view

    def inside(z0, z1) -> bool:
        return z_lo <= 0.5 * (z0 + z1) <= z_hi

    # the tube: non-magnetic (meshed as air), drawn so the gap it leaves is visible
    t = g.tube
    ax.add_patch(Rectangle((scale * t.inner_radius, scale * z_lo),
                           scale * (t.outer_radius - t.inner_radius), scale * (z_hi - z_lo),
                           fill=False, ec="0.85", lw=0.7, ls="--"))
    names = {"coil": "coil", "magnet": "magnet", "pole": "pole piece"}
    for u in g.iter_units():
        for q in (g.coil_rect(u), *g.magnet_rects(u)):
            ax.add_patch(Rectangle((scale * q.r0, scale * q.z0), scale * (q.r1 - q.r0),
                                   scale * (q.z1 - q.z0), fill=False, ec="w", lw=0.8))
            if not inside(q.z0, q.z1):
                continue
            kind = q.name.split("_")[0]
            text = f"coil @{u.coil.particle}" if kind == "coil" else names[kind]
            ax.text(scale * 0.5 * (q.r0 + q.r1), scale * 0.5 * (q.z0 + q.z1), text,
                    ha="center", va="center", fontsize=6.5, bbox=box,
                    rotation=90 if kind != "pole" else 0)
    th = np.linspace(-math.pi / 2, math.pi / 2, 60)
    b = g.beads
    for p in b.particles:
        ax.plot(scale * b.radius * np.cos(th), scale * (b.center(p) + b.radius * np.sin(th)),
                color="w", lw=0.5)
    # one label each for the bead column and the tube, near the top of the view
    z_text = z_hi - 0.06 * (z_hi - z_lo)
    ax.text(scale * 0.5 * (t.inner_radius + t.outer_radius), scale * z_text, "tube",
            ha="center", va="center", fontsize=6.5, rotation=90, bbox=box)
    ax.text(scale * 0.5 * b.radius, scale * z_text, "beads", ha="center", va="center",
            fontsize=6.5, rotation=90, bbox=box)


def _sensor_z_span(report: FieldReport) -> tuple[float, float]:
    """z range of the coils and magnets (the whole model without sensors), m."""
    g = report.geometry
    rects = [r for u in g.sensors for r in (g.coil_rect(u), *g.magnet_rects(u))]
    if not rects:
        return g.parts_z_span()
    return min(r.z0 for r in rects), max(r.z1 for r in rects)


#: Number of flux lines (contours of ψ = r A_φ) in the field map: each carries the same flux.
FLUX_LINES = 20


def field_map_figure(report: FieldReport):
    """The |B| map with flux lines, parts outlined and named, zoomed on the sensors.

    |B| is Gouraud-shaded region by region on a log scale; the flux lines are
    :data:`FLUX_LINES` equally spaced contours of ψ = r A_φ over the view (the field lines
    of an axisymmetric field; equal flux between neighbours, so their density is |B|).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    mesh = report.solution.problem.mesh.mesh
    b_mean, _, _ = _element_fields(report)
    bmag = np.maximum(np.linalg.norm(b_mean, axis=1), 1e-4)
    mm = 1e3
    g = report.geometry
    z0, z1 = _sensor_z_span(report)
    z0, z1 = z0 - 0.008, z1 + 0.008
    r1 = max(q.r1 for q in g.rectangles()) * 1.3
    # triangles touching the view only: the far air would cost time and file size
    px, pz = mesh.p[0, mesh.t], mesh.p[1, mesh.t]
    keep = (px.min(axis=0) <= r1) & (pz.max(axis=0) >= z0) & (pz.min(axis=0) <= z1)
    fig, ax = plt.subplots(figsize=(5.6, 7.6), constrained_layout=True)
    norm = LogNorm(vmin=1e-2, vmax=2.5)  # the view holds 0.01 .. 2 T
    pc = _smooth_bmag(ax, report, bmag, norm, "magma", mm, keep)
    r, z, tri, psi = _refined_psi(report)
    view = (r <= r1) & (z >= z0) & (z <= z1)
    lo, hi = psi[view].min(), psi[view].max()
    ax.tricontour(mm * r, mm * z, tri, psi, levels=np.linspace(lo, hi, FLUX_LINES + 2)[1:-1],
                  colors="#7fd3ff", linewidths=0.5, linestyles="solid")
    _outline(ax, report, mm, (z0, z1))
    ax.set_xlim(0, mm * r1)
    ax.set_ylim(mm * z0, mm * z1)
    ax.set_aspect("equal")
    ax.set_xlabel("r (mm)")
    ax.set_ylabel("z above the wall (mm)")
    ax.set_title("Bias flux density |B| and flux lines (contours of r·A_φ)\n"
                 "magnet: axisymmetric equivalent", fontsize=9)
    fig.colorbar(pc, ax=ax, label="|B| (T)", shrink=0.6)
    return fig


def plot_field_map(report: FieldReport, path: str | Path, fmt: str | None = None) -> Path:
    """Write :func:`field_map_figure` to ``path``.

    Parameters
    ----------
    report : FieldReport
    path : str or Path
    fmt : {"png", "pdf", "svg"}, optional
        File format (default: from ``path``'s suffix, else PNG); rasters at
        :data:`msens.io.output.DPI`.

    Returns
    -------
    Path
    """
    import matplotlib.pyplot as plt

    from msens.io.output import DPI

    path = Path(path)
    fmt = fmt or path.suffix.lstrip(".") or "png"
    fig = field_map_figure(report)
    try:
        return _atomic(path, lambda tmp: fig.savefig(tmp, dpi=DPI, format=fmt))
    finally:
        plt.close(fig)


#: Scalar-bar title of the 3-D view ("|B| (T)" through VTK's mathtext, see plot_field_3d).
_BAR_TITLE = r"$\mathrm{\vert B\vert}$ (T)"


def plot_field_3d(report: FieldReport, path: str | Path) -> Path:
    """Meridian |B| revolved through 270° around the axis, rendered off-screen (PNG)."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    try:
        import pyvista as pv
    except ImportError as exc:  # an optional extra: the base install has no VTK (~0.6 GB)
        import logging

        hint = 'pyvista is not installed: pip install "msens[viz]" for this figure'
        logging.getLogger(__name__).info("field_3d.png skipped: %s", hint)
        raise ImportError(hint) from exc

    pv.OFF_SCREEN = True
    mesh = report.solution.problem.mesh.mesh
    b_mean, _, _ = _element_fields(report)
    g = report.geometry
    z0, z1 = _sensor_z_span(report)
    z0, z1 = z0 - 0.01, z1 + 0.01
    r_max = max(q.r1 for q in g.rectangles()) * 1.15
    # revolve the solid parts only (beads, magnets, pole pieces, coils): air would hide them
    air = report.solution.problem.mesh.subdomains["air"]
    keep = np.all((mesh.p[0, mesh.t] <= r_max) & (mesh.p[1, mesh.t] >= z0 - 2e-3)
                  & (mesh.p[1, mesh.t] <= z1 + 2e-3), axis=0)
    keep[air] = False
    t = mesh.t[:, keep]
    used, inv = np.unique(t, return_inverse=True)
    mm = 1e3
    pts = np.column_stack([mm * mesh.p[0, used], np.zeros(used.size), mm * mesh.p[1, used]])
    faces = np.column_stack([np.full(t.shape[1], 3), inv.reshape(3, -1).T]).ravel()
    surf = pv.PolyData(pts, faces)
    # VTK's text renderer takes "|" for a column separator and drops it: a mathtext \vert
    surf.cell_data[_BAR_TITLE] = np.linalg.norm(b_mean[keep], axis=1)
    vol = surf.extrude_rotate(resolution=54, angle=270.0, capping=True)
    plotter = pv.Plotter(off_screen=True, window_size=(900, 1100))
    plotter.add_mesh(vol, scalars=_BAR_TITLE, cmap="magma", log_scale=True,
                     clim=(1e-2, 2.5), show_scalar_bar=True)
    plotter.add_text(r"bias $\mathrm{\vert B\vert}$, 270° revolved (magnet: equivalent)",
                     font_size=10)
    plotter.camera_position = "xz"
    plotter.camera.azimuth = 45
    plotter.camera.elevation = 25
    path = Path(path)

    def shot(tmp: str) -> None:
        plotter.screenshot(tmp)
        plotter.close()

    return _atomic(path, shot)


def write_field_outputs(report: FieldReport, out_dir: str | Path,
                        fig_format: str = "png") -> dict[str, str]:
    """Write field.json, field.vtu, field_B.<fig_format> and field_3d.png into ``out_dir``.

    ``fig_format`` ("png", "pdf" or "svg") is the map's format; the 3-D view is a rendered
    raster and stays PNG.

    Returns
    -------
    dict
        File name -> path written, or -> "skipped: <reason>" for a figure that could not be
        rendered (pyvista without a working off-screen OpenGL).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = {"field.json": str(write_json(report, out / "field.json")),
               "field.vtu": str(write_vtu(report, out / "field.vtu")),
               f"field_B.{fig_format}": str(plot_field_map(report,
                                                            out / f"field_B.{fig_format}"))}
    try:
        written["field_3d.png"] = str(plot_field_3d(report, out / "field_3d.png"))
    except ImportError as exc:  # the base install has no pyvista: the message says how
        written["field_3d.png"] = f"skipped: {exc}"
    except Exception as exc:  # no OpenGL context here: say so, keep the other outputs
        written["field_3d.png"] = f"skipped: pyvista could not render off-screen ({exc})"
    return written

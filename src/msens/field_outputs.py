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
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from msens.field.forms import flux_density_qp
from msens.field.sensor_model import FieldReport
from msens.io.atomic import atomic_write
from msens.vocabulary import coil_name

SCHEMA = "msens.field/1"


def _atomic(path: Path, write: Callable[[str], None]) -> Path:
    """Call ``write(tmp_path)`` then move the temporary file onto ``path``
    (:func:`msens.io.atomic.atomic_write`)."""
    return atomic_write(path, lambda tmp: write(str(tmp)))


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def report_dict(report: FieldReport, timings_s: Mapping[str, float] | None = None) -> dict:
    """The JSON-ready content of ``field.json``; ``timings_s``: wall seconds of the model's
    stages as the workflow measured them around its calls (empty when not measured)."""
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
        "timings_s": dict(timings_s or {}),
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


def write_json(report: FieldReport, path: str | Path, *,
               timings_s: Mapping[str, float] | None = None) -> Path:
    """Write ``field.json`` (``timings_s``: see :func:`report_dict`)."""
    text = json.dumps(report_dict(report, timings_s), indent=1)
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


#: Sub-triangles per element edge on which the flux function is contoured.
FLUX_SUBDIVISION = 4


def _lattice(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric points and sub-triangles of a triangle split ``n`` times per edge.

    Returns
    -------
    lam : ndarray, shape ((n+1)(n+2)/2, 3)
        Barycentric coordinates (λ0, λ1, λ2) of the lattice points.
    tri : ndarray, shape (n², 3)
        Sub-triangles, indices into ``lam``.
    """
    index = {}
    lam = []
    for i in range(n + 1):
        for j in range(n + 1 - i):
            index[i, j] = len(lam)
            lam.append((1.0 - (i + j) / n, i / n, j / n))
    tri = []
    for i in range(n):
        for j in range(n - i):
            tri.append((index[i, j], index[i + 1, j], index[i, j + 1]))
            if i + j < n - 1:
                tri.append((index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]))
    return np.array(lam), np.array(tri)


def _refined_psi(report: FieldReport, keep: np.ndarray | None = None,
                 n: int = FLUX_SUBDIVISION) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                     np.ndarray]:
    """ψ = r A_φ evaluated exactly from the P2 potential on every element split ``n`` times
    per edge, for smooth field lines.

    The P2 potential of an element is Σ a_k λ_k (2 λ_k − 1) + 4 Σ m_ij λ_i λ_j (vertex
    values a_k, edge-midpoint values m_ij) and r is linear, so ψ is exact at the lattice
    points; contours of the piecewise-linear interpolant between them follow the curved
    field lines within elements instead of cutting across them in straight segments. A P1
    potential is linear per element: its vertices are all there is.

    Parameters
    ----------
    report : FieldReport
    keep : ndarray of bool, shape (n_elements,), optional
        Elements to evaluate (default all).
    n : int
        Subdivisions per element edge.

    Returns
    -------
    r, z : ndarray
        Point coordinates, m (each element has its own points).
    triangles : ndarray, shape (n² n_kept, 3)
    psi : ndarray
        r A_φ at the points, T m² (Wb per radian).
    """
    sol = report.solution
    mesh = sol.basis.mesh
    p, t = mesh.p, mesh.t
    if keep is not None:
        t = t[:, keep]
    a = sol.a[sol.basis.nodal_dofs[0]]
    if sol.basis.facet_dofs.size == 0:  # P1: the vertices are all there is
        return p[0], p[1], t.T, a * p[0]
    t2f = mesh.t2f if keep is None else mesh.t2f[:, keep]
    lam, sub = _lattice(n)
    av = a[t]  # (3, ne): vertex values
    # skfem's edge order of a triangle: (0, 1), (1, 2), (0, 2)
    am = sol.a[sol.basis.facet_dofs[0]][t2f]  # (3, ne): edge-midpoint values
    l0, l1, l2 = lam[:, 0, None], lam[:, 1, None], lam[:, 2, None]
    pot = (av[0] * l0 * (2 * l0 - 1) + av[1] * l1 * (2 * l1 - 1) + av[2] * l2 * (2 * l2 - 1)
           + 4 * (am[0] * l0 * l1 + am[1] * l1 * l2 + am[2] * l0 * l2))  # (points, ne)
    r = lam @ p[0, t]
    z = lam @ p[1, t]
    ne = t.shape[1]
    k = lam.shape[0]
    tri = (sub[None, :, :] + k * np.arange(ne)[:, None, None]).reshape(-1, 3)
    # element-major point order: element e's points are e*k .. e*k + k-1
    return r.T.ravel(), z.T.ravel(), tri, (r * pot).T.ravel()


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
            text = (coil_name(u.coil.particle).replace(" at ", " at\n") if kind == "coil"
                    else names[kind])
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


def _flux_levels(report: FieldReport, psi: np.ndarray, keep: np.ndarray,
                 bmag: np.ndarray) -> np.ndarray:
    """:data:`FLUX_LINES` equally spaced values of ψ over the view's range ``psi``, placed
    so that the weakest-field point of the air outside the tube (the null between opposed
    magnets, a saddle of ψ) falls midway between two lines.

    Near such a null the computed field is weakest and least accurate (coarse air
    elements): a line through it would show the mesh's kinks rather than the field.
    ``keep`` and ``bmag`` are the view's elements and the per-element |B|, T.
    """
    lo, hi = float(psi.min()), float(psi.max())
    step = (hi - lo) / (FLUX_LINES + 1)
    levels = np.linspace(lo, hi, FLUX_LINES + 2)[1:-1]
    sol = report.solution
    mesh = sol.basis.mesh
    air = np.zeros(keep.size, dtype=bool)
    air[sol.problem.mesh.subdomains.get("air", [])] = True
    centre = mesh.p[:, mesh.t].mean(axis=1)
    outside = air & keep & (centre[0] > report.geometry.tube.outer_radius)
    if step <= 0 or not outside.any():
        return levels
    e = np.flatnonzero(outside)[np.argmin(bmag[outside])]
    a = sol.a[sol.basis.nodal_dofs[0]]
    null = float(np.mean(a[mesh.t[:, e]] * mesh.p[0, mesh.t[:, e]]))
    shift = (null - lo) / step % 1.0 - 0.5  # null's place between two lines, -0.5 .. 0.5
    shifted = levels + shift * step
    return shifted[(shifted > lo) & (shifted < hi)]


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
    r, z, tri, psi = _refined_psi(report, keep)
    view = (r <= r1) & (z >= z0) & (z <= z1)
    ax.tricontour(mm * r, mm * z, tri, psi, levels=_flux_levels(report, psi[view], keep,
                                                                bmag),
                  colors="#7fd3ff", linewidths=0.5, linestyles="solid")
    _outline(ax, report, mm, (z0, z1))
    ax.set_xlim(0, mm * r1)
    ax.set_ylim(mm * z0, mm * z1)
    ax.set_aspect("equal")
    ax.set_xlabel("r (mm)")
    ax.set_ylabel("z above the wall (mm)")
    ax.set_title(r"Bias flux density $|B|$ and flux lines (contours of $r\,A_\varphi$)"
                 "\nmagnet: axisymmetric equivalent", fontsize=9)
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


def _solid_triangles(report: FieldReport, z0: float, z1: float, r_max: float) -> np.ndarray:
    """Triangles of the 3-D view: the solid parts (beads, magnets, pole pieces, coils) in
    ``z0 .. z1`` (m) and ``r <= r_max``, every bead whole (a bead whose centre lies in the
    range, never a half-shell cut at its edge), no air. Boolean mask over the elements."""
    mesh = report.solution.problem.mesh.mesh
    subdomains = report.solution.problem.mesh.subdomains
    beads = report.geometry.beads
    px, pz = mesh.p[0, mesh.t], mesh.p[1, mesh.t]
    keep = np.all((px <= r_max) & (pz >= z0) & (pz <= z1), axis=0)
    for name, elements in subdomains.items():
        kind, _, index = name.partition("_")
        if name == "air":
            keep[elements] = False
        elif kind == "bead" and index.isdigit():
            keep[elements] = z0 <= beads.center(int(index)) <= z1
    return keep


def _crop_white(img: np.ndarray, margin: int) -> np.ndarray:
    """``img`` (rows, columns, channels) cut to its non-white content plus ``margin``
    pixels."""
    content = np.any(img[..., :3] < 250, axis=2)
    rows, cols = np.flatnonzero(content.any(axis=1)), np.flatnonzero(content.any(axis=0))
    if rows.size == 0:
        return img
    r0, r1 = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, img.shape[0])
    c0, c1 = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, img.shape[1])
    return img[r0:r1, c0:c1]


def field_3d_figure(report: FieldReport):
    """The bias |B| on the solid parts revolved through 270° around the axis (pyvista,
    off-screen), cut to the parts, with its colour bar and title (matplotlib).

    The view spans the sensors' coils and magnets with 10 mm above and below, every bead in
    it whole. The colour scale is the field map's (:func:`field_map_figure`): log, 0.01 ..
    2.5 T.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ImportError
        pyvista is not installed (an optional extra), with the command that installs it.
    """
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    try:
        import pyvista as pv
    except ImportError as exc:  # an optional extra: the base install has no VTK (~0.6 GB)
        import logging

        hint = 'pyvista is not installed: pip install "msens[viz]" for this figure'
        logging.getLogger(__name__).info("field_3d.png skipped: %s", hint)
        raise ImportError(hint) from exc
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm

    pv.OFF_SCREEN = True
    mesh = report.solution.problem.mesh.mesh
    b_mean, _, _ = _element_fields(report)
    g = report.geometry
    z0, z1 = _sensor_z_span(report)
    z0, z1 = z0 - 0.01, z1 + 0.01
    r_max = max(q.r1 for q in g.rectangles()) * 1.15
    keep = _solid_triangles(report, z0, z1, r_max)
    t = mesh.t[:, keep]
    used, inv = np.unique(t, return_inverse=True)
    mm = 1e3
    pts = np.column_stack([mm * mesh.p[0, used], np.zeros(used.size), mm * mesh.p[1, used]])
    faces = np.column_stack([np.full(t.shape[1], 3), inv.reshape(3, -1).T]).ravel()
    surf = pv.PolyData(pts, faces)
    surf.cell_data["B_magnitude"] = np.linalg.norm(b_mean[keep], axis=1)
    vol = surf.extrude_rotate(resolution=54, angle=270.0, capping=True)
    lo, hi = 1e-2, 2.5  # the field map's scale
    plotter = pv.Plotter(off_screen=True, window_size=(1300, 1700))
    plotter.set_background("white")
    plotter.add_mesh(vol, scalars="B_magnitude", cmap="magma", log_scale=True,
                     clim=(lo, hi), show_scalar_bar=False)
    plotter.camera_position = "xz"
    plotter.camera.azimuth = 45
    plotter.camera.elevation = 25
    plotter.reset_camera()
    plotter.camera.zoom(1.35)
    try:
        img = _crop_white(np.asarray(plotter.screenshot(return_img=True)), margin=12)
    finally:
        plotter.close()
    height, width = img.shape[:2]
    dpi = 260.0  # rendered pixels per inch of the figure
    fig = plt.figure(figsize=(width / dpi + 1.3, height / dpi + 0.5))
    ax = fig.add_axes((0.0, 0.0, width / dpi / fig.get_figwidth(),
                       height / dpi / fig.get_figheight()))
    ax.imshow(img)
    ax.set_axis_off()
    cax = fig.add_axes((1.0 - 0.85 / fig.get_figwidth(), 0.2, 0.15 / fig.get_figwidth(), 0.55))
    bar = fig.colorbar(ScalarMappable(LogNorm(lo, hi), "magma"), cax=cax)
    bar.set_label("|B| (T)", fontsize=9)
    bar.ax.tick_params(labelsize=8)
    fig.suptitle("Bias flux density |B| on the beads, magnets, pole pieces and coils\n"
                 "(meridian solution revolved through 270°; magnet: axisymmetric "
                 "equivalent)", fontsize=8, y=1.0 - 0.05 / fig.get_figheight(), va="top")
    return fig


def plot_field_3d(report: FieldReport, path: str | Path) -> Path:
    """Write :func:`field_3d_figure` as PNG to ``path``
    (at :data:`msens.io.output.DPI`).

    Raises
    ------
    ImportError
        pyvista is not installed, with the command that installs it.
    """
    import matplotlib.pyplot as plt

    from msens.io.output import DPI

    fig = field_3d_figure(report)
    try:
        return _atomic(Path(path), lambda tmp: fig.savefig(tmp, dpi=DPI, format="png"))
    finally:
        plt.close(fig)


def write_field_outputs(report: FieldReport, out_dir: str | Path,
                        fig_format: str = "png", *,
                        timings_s: Mapping[str, float] | None = None) -> dict[str, str]:
    """Write field.json, field.vtu, field_B.<fig_format> and field_3d.png into ``out_dir``.

    ``fig_format`` ("png", "pdf" or "svg") is the map's format; the 3-D view is a rendered
    raster and stays PNG. ``timings_s``: the stages' wall seconds for ``field.json``
    (measured by the workflow; :func:`report_dict`).

    Returns
    -------
    dict
        File name -> path written, or -> "skipped: <reason>" for a figure that could not be
        rendered (pyvista without a working off-screen OpenGL).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = {"field.json": str(write_json(report, out / "field.json", timings_s=timings_s)),
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

"""Outputs of the sensor field model: field.json, field.vtu, figures.

- ``field.json``: coils (R, L), bead fields, contact forces, the axial profile, solver data and
  the statement that the magnet is an equivalent (schema ``msens.field/1``).
- ``field.vtu``: the meridian-plane mesh (x = r, y = z, metres) with A_φ and ψ = r A_φ at the
  vertices and B, |B| and the region number per triangle (ParaView: "Threshold" on region).
- ``field_B.png``: |B| map with field lines (contours of ψ, which are exactly the field lines of
  an axisymmetric field), parts outlined, zoomed on the sensors.
- ``field_3d.png``: the meridian solution revolved through 270° (pyvista, off-screen EGL).
  When pyvista cannot render, the figure is skipped and :func:`write_field_outputs` returns the
  reason under ``"field_3d.png"`` instead of a path.

All files are written atomically (temporary file in the same directory, then os.replace).
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from msens.field.forms import flux_density_qp
from msens.field.sensor_model import FieldReport

SCHEMA = "msens.field/1"


def _atomic(path: Path, write: Callable[[str], None]) -> Path:
    """Call ``write(tmp_path)`` then move the temporary file onto ``path``."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual permissions
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


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


def _outline(ax, report: FieldReport, scale: float) -> None:
    g = report.geometry
    for q in g.rectangles()[1:]:
        ax.plot(scale * np.array([q.r0, q.r1, q.r1, q.r0, q.r0]),
                scale * np.array([q.z0, q.z0, q.z1, q.z1, q.z0]), "k-", lw=0.6)
    t = np.linspace(-math.pi / 2, math.pi / 2, 60)
    b = g.beads
    for p in b.particles:
        ax.plot(scale * b.radius * np.cos(t), scale * (b.center(p) + b.radius * np.sin(t)),
                "k-", lw=0.4)
    for r in (g.tube.inner_radius, g.tube.outer_radius):
        ax.axvline(scale * r, color="0.5", lw=0.4, ls=":")


def _sensor_z_span(report: FieldReport) -> tuple[float, float]:
    """z range of the coils and magnets (the whole model without sensors), m."""
    g = report.geometry
    rects = [r for u in g.sensors for r in (g.coil_rect(u), *g.magnet_rects(u))]
    if not rects:
        return g.parts_z_span()
    return min(r.z0 for r in rects), max(r.z1 for r in rects)


def plot_field_map(report: FieldReport, path: str | Path) -> Path:
    """|B| map with field lines, zoomed on the sensors (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.tri import Triangulation

    mesh = report.solution.problem.mesh.mesh
    b_mean, _, _ = _element_fields(report)
    bmag = np.maximum(np.linalg.norm(b_mean, axis=1), 1e-4)
    psi = _vertex_potential(report) * mesh.p[0]
    mm = 1e3
    tri = Triangulation(mm * mesh.p[0], mm * mesh.p[1], mesh.t.T)
    g = report.geometry
    z0, z1 = _sensor_z_span(report)
    r1 = max(q.r1 for q in g.rectangles()) * 1.3
    fig, ax = plt.subplots(figsize=(6, 8), constrained_layout=True)
    pc = ax.tripcolor(tri, facecolors=bmag, norm=LogNorm(vmin=1e-3, vmax=2.5), cmap="magma",
                      shading="flat", rasterized=True)
    lim = np.max(np.abs(psi))
    ax.tricontour(tri, psi, levels=np.linspace(-lim, lim, 41)[1:-1], colors="c",
                  linewidths=0.5)
    _outline(ax, report, mm)
    ax.set_xlim(0, mm * r1)
    ax.set_ylim(mm * (z0 - 0.008), mm * (z1 + 0.008))
    ax.set_aspect("equal")
    ax.set_xlabel("r (mm)")
    ax.set_ylabel("z (mm, wall at 0)")
    ax.set_title("bias |B| and field lines\n(magnet: axisymmetric equivalent)", fontsize=9)
    fig.colorbar(pc, ax=ax, label="|B| (T)", shrink=0.6)
    path = Path(path)
    return _atomic(path, lambda tmp: fig.savefig(tmp, dpi=150, format="png")) and (
        plt.close(fig) or path)


def plot_field_3d(report: FieldReport, path: str | Path) -> Path:
    """Meridian |B| revolved through 270° around the axis, rendered off-screen (PNG)."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

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
    surf.cell_data["|B| (T)"] = np.linalg.norm(b_mean[keep], axis=1)
    vol = surf.extrude_rotate(resolution=54, angle=270.0, capping=True)
    plotter = pv.Plotter(off_screen=True, window_size=(900, 1100))
    plotter.add_mesh(vol, scalars="|B| (T)", cmap="magma", log_scale=True,
                     clim=(1e-2, 2.5), show_scalar_bar=True)
    plotter.add_text("bias |B|, 270° revolved (magnet: equivalent)", font_size=10)
    plotter.camera_position = "xz"
    plotter.camera.azimuth = 45
    plotter.camera.elevation = 25
    path = Path(path)

    def shot(tmp: str) -> None:
        plotter.screenshot(tmp)
        plotter.close()

    return _atomic(path, shot)


def write_field_outputs(report: FieldReport, out_dir: str | Path) -> dict[str, str]:
    """Write field.json, field.vtu, field_B.png and field_3d.png into ``out_dir``.

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
               "field_B.png": str(plot_field_map(report, out / "field_B.png"))}
    try:
        written["field_3d.png"] = str(plot_field_3d(report, out / "field_3d.png"))
    except Exception as exc:  # no OpenGL context here: say so, keep the other outputs
        written["field_3d.png"] = f"skipped: pyvista could not render off-screen ({exc})"
    return written

"""Axisymmetric magnetostatic solve: linear, Newton for nonlinear steel, incremental.

Formulation (see :mod:`.forms`): azimuthal vector potential A_φ, P2 (default) Lagrange
elements, A_φ = 0 on the axis r = 0 (automatically, every boundary facet on r = 0) and
A_φ = B_0 r/2 on the ``outer`` boundaries (B_0 = ``background_field``, 0 by default: a
truncated open domain; :mod:`.verify` shows the truncation error).
Nonlinear regions: Newton's method on the residual ∫ H(B)·B(v) r − ∫ J v r with the exact
tangent ν I + (ν_d − ν) b̂b̂ᵀ and a backtracking line search on the residual norm.
Linear systems: SuperLU in a nested-dissection ordering (:func:`.linsolve.factorize`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import skfem

from msens.errors import require
from msens.field.assembly import (
    Pattern,
    assemble_matrix,
    assemble_vector,
    build_pattern,
)
from msens.field.constitutive import (
    Materials,
    field_strength,
    material_fields,
    reluctivities,
    small_signal_tangent,
    tangent,
)
from msens.field.forms import (
    QuadratureData,
    element_internal_force,
    element_load,
    element_stiffness,
    flux_density_qp,
    quadrature_data,
)
from msens.field.linsolve import factorize
from msens.field.mesh import AxiMesh, axis_facets
from msens.field.probes import P2Field
from msens.field.regions import CurrentRegion, PermanentMagnet, Region


class FieldSolveError(RuntimeError):
    """The nonlinear field solve did not converge.

    Attributes
    ----------
    residuals : tuple of float
        Relative residual norm after each Newton iteration.
    """

    def __init__(self, message: str, residuals: tuple[float, ...]):
        super().__init__(message)
        self.residuals = residuals


@dataclass(frozen=True)
class MagnetostaticProblem:
    """An axisymmetric magnetostatic boundary-value problem.

    Attributes
    ----------
    mesh : AxiMesh
    regions : Mapping[str, Region]
        What fills each subdomain; every subdomain of ``mesh`` must be named exactly once.
    outer : tuple of str
        Boundary group names where A_φ = B_0 r/2 (A_φ = 0 for no background field).
    order : int
        Lagrange element order, 1 or 2.
    background_field : float
        Uniform axial field B_0 (T) imposed through the outer boundary values.
    outer_potential : callable, optional
        ``f(r, z) -> A_φ`` (T m) on the outer boundary, replacing B_0 r/2 (e.g. an exact
        solution, to remove the truncation error in convergence studies).
    """

    mesh: AxiMesh
    regions: Mapping[str, Region]
    outer: tuple[str, ...] = ("outer",)
    order: int = 2
    background_field: float = 0.0
    outer_potential: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None

    def __post_init__(self) -> None:
        subs, regs = set(self.mesh.subdomains), set(self.regions)
        require(subs == regs,
                f"regions must name every mesh subdomain exactly: missing {sorted(subs - regs)},"
                f" unknown {sorted(regs - subs)}")
        for name in self.outer:
            require(name in self.mesh.boundaries,
                    f"outer boundary '{name}' is not a boundary group of the mesh "
                    f"(have {sorted(self.mesh.boundaries)})")
        require(self.order in (1, 2), f"order must be 1 or 2, got {self.order}")


@dataclass(frozen=True)
class Discretisation:
    """Everything about a problem that does not depend on the solution (cached per solve)."""

    basis: skfem.CellBasis
    quad: QuadratureData
    pattern: Pattern
    materials: Materials
    fixed: np.ndarray
    fixed_values: np.ndarray


@dataclass(frozen=True)
class FieldSolution:
    """Solution of a :class:`MagnetostaticProblem`.

    Attributes
    ----------
    problem : MagnetostaticProblem
    basis : skfem.CellBasis
    a : ndarray, shape (n_dofs,)
        Dofs of A_φ, T m.
    iterations : int
        Newton iterations (1 for a linear problem).
    residuals : tuple of float
        Relative residual norm after each iteration.
    disc : Discretisation
        Cached discretisation (basis data, pattern, material fields).
    bias : FieldSolution or None
        For an incremental solution, the bias state it is linearised at.
    """

    problem: MagnetostaticProblem
    basis: skfem.CellBasis
    a: np.ndarray
    iterations: int
    residuals: tuple[float, ...]
    disc: Discretisation = field(repr=False, compare=False, default=None)
    bias: FieldSolution | None = field(repr=False, compare=False, default=None)

    @property
    def dofs(self) -> int:
        """Number of dofs (including Dirichlet ones)."""
        return int(self.a.size)


def discretise(problem: MagnetostaticProblem) -> Discretisation:
    """Basis, quadrature data, sparsity pattern and Dirichlet data of a problem."""
    mesh = problem.mesh.mesh
    elem = skfem.ElementTriP2() if problem.order == 2 else skfem.ElementTriP1()
    basis = skfem.CellBasis(mesh, elem, intorder=2 * problem.order)
    axis = axis_facets(mesh)
    outer = np.concatenate([problem.mesh.boundaries[n] for n in problem.outer] + [axis])
    fixed = np.unique(basis.get_dofs(outer.astype(np.int64)).flatten())
    r, z = basis.doflocs[:, fixed]
    if problem.outer_potential is not None:
        values = np.asarray(problem.outer_potential(r, z), dtype=float)
    else:
        values = problem.background_field * r / 2.0
    values = np.where(r <= 0.0, 0.0, values)
    return Discretisation(
        basis=basis, quad=quadrature_data(basis),
        pattern=build_pattern(basis.element_dofs, basis.N, fixed),
        materials=material_fields(problem.mesh, problem.regions),
        fixed=fixed, fixed_values=values)


def _external_load(d: Discretisation, mat: Materials) -> np.ndarray:
    fe = element_load(d.quad, mat.j, mat.hc)
    return assemble_vector(d.quad.dofs, fe, d.basis.N)


def _lift(d: Discretisation) -> np.ndarray:
    a = np.zeros(d.basis.N)
    a[d.fixed] = d.fixed_values
    return a


def _solve_linear(d: Discretisation, nu: np.ndarray, load: np.ndarray, lift: np.ndarray):
    """Solve K(ν) a = load with a = lift on the Dirichlet dofs; returns (a, relative residual)."""
    full, ff = assemble_matrix(d.pattern, element_stiffness(d.quad, nu))
    free = d.pattern.free
    rhs = load - full @ lift
    a = lift.copy()
    if free.size:
        a[free] = factorize(ff).solve(rhs[free])
    ref = max(np.linalg.norm(rhs[free]), 1e-300)
    res = float(np.linalg.norm((full @ a - load)[free]) / ref)
    return a, res


def _residual(d: Discretisation, a: np.ndarray, load: np.ndarray):
    """Residual vector, flux density, secant and differential reluctivity at ``a``."""
    b = flux_density_qp(d.quad, a)
    nu, nu_d = reluctivities(d.materials, b)
    # H_c enters through ``load``; the internal force uses ν B only
    h = nu[..., None] * b
    r = assemble_vector(d.quad.dofs, element_internal_force(d.quad, h), d.basis.N) - load
    return r, b, nu, nu_d


def _line_search(d: Discretisation, a: np.ndarray, da: np.ndarray, r0: np.ndarray,
                 load: np.ndarray, max_trials: int = 8):
    """Step length along the Newton direction ``da`` by the slope of the energy.

    The field problem minimises a convex functional Π whose gradient is the residual, so
    g(t) = da · R(a + t da) increases monotonically from g(0) < 0. The full step is kept when
    |g(1)| <= |g(0)|/2 (always so near the solution, which keeps Newton quadratic); otherwise
    the root of g in (0, 1) is bracketed by the Illinois (modified regula falsi) method. A
    residual-norm line search would instead accept damped steps and converge only linearly;
    Π itself cannot be compared near convergence (cancellation).
    """
    g0 = float(da @ r0)
    state = _residual(d, a + da, load)
    g1 = float(da @ state[0])
    if g0 >= 0.0 or abs(g1) <= 0.5 * abs(g0) or g1 < 0.0:
        return 1.0, state
    lo, glo, hi, ghi = 0.0, g0, 1.0, g1
    side = 0
    t = 1.0
    for _ in range(max_trials):
        t = (lo * ghi - hi * glo) / (ghi - glo)
        state = _residual(d, a + t * da, load)
        gt = float(da @ state[0])
        if abs(gt) <= 0.5 * abs(g0):
            break
        if gt > 0.0:
            hi, ghi = t, gt
            if side == -1:
                glo *= 0.5
            side = -1
        else:
            lo, glo = t, gt
            if side == 1:
                ghi *= 0.5
            side = 1
    return t, state


def solve(problem: MagnetostaticProblem, *, tol: float = 1e-8, max_iter: int = 15,
          initial: np.ndarray | None = None, start: FieldSolution | P2Field | None = None
          ) -> FieldSolution:
    """Solve the magnetostatic problem.

    Parameters
    ----------
    problem : MagnetostaticProblem
    tol : float
        Newton stops when the free-dof residual norm, relative to the norm of the source
        vector (currents, magnets and boundary values), is <= ``tol``.
    max_iter : int
        Maximum Newton iterations.
    initial : ndarray, shape (n_dofs,), optional
        Starting dofs for Newton (default: a linear solve with the secant reluctivity of
        the nonlinear regions at 1.8 T, ``constitutive.INITIAL_SECANT_B``).
    start : FieldSolution or P2Field, optional
        Instead of ``initial``: a solution of the same domain on another mesh, interpolated
        at this mesh's dofs (P2; the fixed dofs keep their boundary values, dofs outside its
        mesh start at 0).

    Returns
    -------
    FieldSolution

    Raises
    ------
    FieldSolveError
        If Newton does not reach ``tol`` within ``max_iter`` iterations.
    """
    d = discretise(problem)
    mat = d.materials
    load = _external_load(d, mat)
    lift = _lift(d)
    nu0 = np.broadcast_to(mat.nu[:, None], d.quad.w.shape)
    free = d.pattern.free
    if start is not None:
        require(initial is None, "give initial or start, not both")
        x = d.basis.doflocs
        field = start if isinstance(start, P2Field) else P2Field.of(start)
        initial = field.at(x[0], x[1], outside_zero=True)
        initial[d.fixed] = d.fixed_values
    if initial is None:
        a, res = _solve_linear(d, nu0, load, lift)
    else:
        a, res = np.asarray(initial, dtype=float).copy(), np.inf
    if not mat.nonlinear:
        return FieldSolution(problem, d.basis, a, 1, (res,), disc=d)
    full0, _ = assemble_matrix(d.pattern, element_stiffness(d.quad, nu0))
    ref = max(np.linalg.norm((load - full0 @ lift)[free]), 1e-300)
    history: list[float] = []
    r, b, nu, nu_d = _residual(d, a, load)
    for it in range(1, max_iter + 1):
        _, jff = assemble_matrix(d.pattern, element_stiffness(d.quad, tangent(b, nu, nu_d)))
        da = np.zeros_like(a)
        da[free] = factorize(jff).solve(-r[free])
        step, (r, b, nu, nu_d) = _line_search(d, a, da, r, load)
        a = a + step * da
        history.append(float(np.linalg.norm(r[free]) / ref))
        if history[-1] <= tol:
            return FieldSolution(problem, d.basis, a, it, tuple(history), disc=d)
    raise FieldSolveError(
        f"Newton did not converge in {max_iter} iterations (tol {tol:g}); relative residuals: "
        + ", ".join(f"{x:.3e}" for x in history), tuple(history))


def incremental(solution: FieldSolution, sources: Mapping[str, CurrentRegion]) -> FieldSolution:
    """Linearised (small-signal) solve at the bias point of ``solution``.

    Nonlinear regions get the tangent reluctivity tensor dH/dB of the bias state (differential
    reluctivity along B, secant across it); magnets keep μ_rec with their remanence switched
    off; only the windings in ``sources`` carry current; all boundary values are zero.

    Parameters
    ----------
    solution : FieldSolution
        Bias state.
    sources : Mapping[str, CurrentRegion]
        Winding subdomains and their current densities (e.g. N × 1 A / S).

    Returns
    -------
    FieldSolution
        With ``bias`` set to ``solution``; its ``problem`` has the sources' windings, no
        remanence and no background field.
    """
    prob = solution.problem
    for name, w in sources.items():
        require(name in prob.regions and isinstance(prob.regions[name], CurrentRegion),
                f"incremental source '{name}' is not a CurrentRegion of the problem")
        require(isinstance(w, CurrentRegion),
                f"incremental source '{name}' must be a CurrentRegion")
    regions = {}
    for name, reg in prob.regions.items():
        if isinstance(reg, CurrentRegion):
            regions[name] = sources.get(name, CurrentRegion(0.0))
        elif isinstance(reg, PermanentMagnet):
            regions[name] = replace(reg, remanence=0.0)
        else:
            regions[name] = reg
    inc = replace(prob, regions=regions, background_field=0.0, outer_potential=None)
    d0 = solution.disc if solution.disc is not None else discretise(prob)
    d = replace(d0, materials=material_fields(prob.mesh, regions),
                fixed_values=np.zeros_like(d0.fixed_values))
    b = flux_density_qp(d.quad, solution.a)
    load = _external_load(d, d.materials)
    a, res = _solve_linear(d, small_signal_tangent(d0.materials, b), load,
                           np.zeros(d.basis.N))
    return FieldSolution(inc, d.basis, a, 1, (res,), disc=d, bias=solution)


def internal_field_strength(sol: FieldSolution) -> np.ndarray:
    """H at the quadrature points, A/m, shape (n_elements, n_qp, 2)."""
    d = sol.disc
    b = flux_density_qp(d.quad, sol.a)
    if sol.bias is not None:
        bb = flux_density_qp(d.quad, sol.bias.a)
        return np.einsum("eqcd,eqd->eqc", small_signal_tangent(sol.bias.disc.materials, bb), b)
    nu, _ = reluctivities(d.materials, b)
    return field_strength(d.materials, b, nu)

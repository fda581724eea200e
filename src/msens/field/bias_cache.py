"""The nonlinear bias solution of a geometry, kept in the artifact store.

A run's field-map figure, ``msens field`` and the coil tables each need the bias state of a
geometry whose transducers are already cached: a Newton solve of some seconds on the main
study's mesh, always with the same result. :func:`solve_bias` keeps the converged potential
as the file artifact ``bias-<key>.npz`` (A_φ at every P2 dof, the Newton history), keyed on
the mesh (:func:`msens.field.cache.geometry_key`) and on everything the bias problem reads
(the whole geometry, materials included); a later call rebuilds the
:class:`~msens.field.solve.FieldSolution` from it. The stored dofs are the solved ones, so a
run that solved and one that read give the same bits.
"""

from __future__ import annotations

import io
import logging

import numpy as np

from msens.errors import InputError
from msens.field.build import MeshOptions
from msens.field.cache import geometry_key
from msens.field.geometry import SensorGeometry
from msens.field.solve import FieldSolution, MagnetostaticProblem, discretise, solve
from msens.store import Store, content_key

_log = logging.getLogger(__name__)

#: Version of the stored bias solutions; part of their key.
BIAS_VERSION = "bias/1"


def bias_name(geometry: SensorGeometry, options: MeshOptions | None = None) -> str:
    """The artifact name of ``geometry``'s bias solution on the mesh of ``options``."""
    key = content_key({"version": BIAS_VERSION,
                       "mesh": geometry_key(geometry, options or MeshOptions()),
                       "geometry": geometry}, 16)
    return f"bias-{key}.npz"


def solve_bias(problem: MagnetostaticProblem, geometry: SensorGeometry,
               options: MeshOptions | None = None, store: Store | None = None
               ) -> FieldSolution:
    """The solution of ``problem`` (``geometry``'s bias problem on its mesh of ``options``,
    :func:`msens.field.sensor_model.bias_problem`): read from ``store``, else solved
    (:func:`msens.field.solve.solve`, default tolerances) and stored.

    Parameters
    ----------
    problem : MagnetostaticProblem
    geometry : SensorGeometry
    options : MeshOptions, optional
    store : Store, optional
        Default :meth:`msens.store.Store.default`.

    Returns
    -------
    FieldSolution
    """
    store = Store.default() if store is None else store
    name = bias_name(geometry, options)
    path = store.find_file(name)
    if path is not None:
        with np.load(path) as f:
            a, iterations, residuals = f["a"], int(f["iterations"]), f["residuals"]
        d = discretise(problem)
        if a.shape == (d.basis.N,):
            _log.info("bias solution %s (cached: yes)", name)
            return FieldSolution(problem, d.basis, a, iterations,
                                 tuple(float(x) for x in residuals), disc=d)
        _log.warning("%s holds %d dofs, the mesh has %d: solving again", path, a.size,
                     d.basis.N)
    sol = solve(problem)
    arrays = {"a": sol.a, "iterations": np.array(sol.iterations),
              "residuals": np.asarray(sol.residuals, dtype=float)}

    def write(tmp):
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        tmp.write_bytes(buf.getvalue())

    try:
        store.write_file(name, write, {"schema": BIAS_VERSION, "dofs": int(sol.a.size)})
    except InputError as exc:  # a later call solves again: say nothing louder
        _log.debug("%s; bias solution not kept", exc)
    return sol


__all__ = ["BIAS_VERSION", "bias_name", "solve_bias"]

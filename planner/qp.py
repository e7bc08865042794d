"""OSQP for the planner's small dense QPs, without SciPy.

    minimise 1/2 x' P x + q' x   subject to   l <= A x <= u

The problems here (the grasp's contact forces: 15-21 variables, 60-120 rows) are
dense and change every solve but keep their size, so every entry of ``P`` (upper
triangle) and ``A`` is stored, zeros included: one sparsity pattern per size, set
up once, then only updated and warm-started (OSQP's own advice for a sequence of
alike problems).

The solver is OSQP's compiled core (``osqp.ext_builtin``, the "builtin" algebra of
the ``osqp`` package, 1.x), loaded on its own: the package's Python layer
(``osqp.interface``) also imports ``jinja2`` and its code generator, 40-50 ms of a
catch's start (``python -X importtime``), for nothing the planner uses. If a future
package moves the extension, the package is imported the ordinary way instead. The
core itself imports ``scipy.sparse`` to read a matrix (0.15-0.25 s), so SciPy is
imported when the first QP is solved, not when the planner starts.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.machinery
import importlib.util
import os
from dataclasses import dataclass
from functools import cache

import numpy as np

from planner.errors import SolverError

SOLVED = ("solved", "solved inaccurate")
PRIMAL_INFEASIBLE = ("primal infeasible", "primal infeasible inaccurate")


@cache
def _ext():
    """OSQP's compiled module, loaded without the package's SciPy-importing layer."""
    spec = importlib.util.find_spec("osqp")
    if spec is not None and spec.submodule_search_locations:
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = os.path.join(spec.submodule_search_locations[0], "ext_builtin" + suffix)
            if os.path.exists(path):
                loader = importlib.machinery.ExtensionFileLoader("osqp.ext_builtin", path)
                module = importlib.util.module_from_spec(
                    importlib.util.spec_from_loader("osqp.ext_builtin", loader))
                loader.exec_module(module)
                return module
    return importlib.import_module("osqp.ext_builtin")  # pragma: no cover - other layouts


@cache
def _pattern(m: int, n: int, upper: bool) -> tuple[np.ndarray, np.ndarray]:
    """Row indices and column pointers that store every entry of an m x n matrix
    (of its upper triangle, diagonal included, if ``upper``), column by column."""
    if upper:
        counts = np.arange(1, n + 1)
        indices = np.concatenate([np.arange(j + 1) for j in range(n)])
    else:
        counts = np.full(n, m)
        indices = np.tile(np.arange(m), n)
    indptr = np.concatenate([[0], np.cumsum(counts)])
    return indices.astype(np.int32), indptr.astype(np.int32)


def dense_csc(M: np.ndarray, upper: bool = False):
    """``M`` (its upper triangle if ``upper``) as a SciPy CSC matrix with every entry
    stored, zeros included. (SciPy is imported here, not at the top: OSQP's core needs
    it to read a matrix, and only the catch solves QPs.)"""
    import scipy.sparse as sp

    M = np.asarray(M, dtype=np.float64)
    m, n = M.shape
    indices, indptr = _pattern(m, n, upper)
    data = M.T[np.tril_indices(n)] if upper else M.flatten(order="F")
    out = sp.csc_matrix((m, n))
    out.data, out.indices, out.indptr = np.ascontiguousarray(data), indices, indptr
    return out


@dataclass(frozen=True)
class QpResult:
    """What one solve gave: OSQP's status text, the solution (None unless solved)
    and the iterations it took."""

    status: str
    x: np.ndarray | None
    iterations: int

    @property
    def solved(self) -> bool:
        return self.status in SOLVED

    @property
    def primal_infeasible(self) -> bool:
        return self.status in PRIMAL_INFEASIBLE


class _Sink:
    """A text stream that keeps nothing (``write``, ``flush``)."""

    def write(self, text: str) -> int:
        return len(text)

    def flush(self) -> None:
        pass


_SINK = _Sink()


class DenseQp:
    """One OSQP solver for dense problems of one size: ``solve`` sets it up on the
    first call and afterwards updates the data and warm-starts from the last answer.
    ``settings`` are OSQP's (eps_abs, eps_rel, max_iter, ...); verbose is off."""

    def __init__(self, **settings):
        self._settings = dict(settings)
        self._solver = None
        self._shape: tuple[int, int] | None = None

    def solve(self, P: np.ndarray, q: np.ndarray, A: np.ndarray, lower: np.ndarray,
              upper: np.ndarray) -> QpResult:
        ext = _ext()
        Pc, Ac = dense_csc(P, upper=True), dense_csc(A)
        inf = float(ext.OSQP_INFTY)
        q = np.ascontiguousarray(q, dtype=np.float64)
        lower = np.ascontiguousarray(np.maximum(lower, -inf), dtype=np.float64)
        upper = np.ascontiguousarray(np.minimum(upper, inf), dtype=np.float64)
        if self._solver is None or self._shape != Ac.shape:
            self._solver = self._setup(ext, Pc, q, Ac, lower, upper)
            self._shape = Ac.shape
        else:
            self._solver.update_data_vec(q=q, l=lower, u=upper)
            self._solver.update_data_mat(P_x=Pc.data, P_i=None, A_x=Ac.data, A_i=None)
        # (OSQP 1.0's polishing writes "Polishing not needed - no active set detected at
        # optimal point" to Python's standard output, verbose or not: into a trajectory a
        # plan streams there, ``-o -``; it goes nowhere)
        with contextlib.redirect_stdout(_SINK):
            self._solver.solve()
        info = self._solver.info
        status = str(info.status)
        x = np.array(self._solver.solution.x, dtype=float) if status in SOLVED else None
        return QpResult(status, x, int(info.iter))

    def _setup(self, ext, Pc, q, Ac, lower, upper):
        settings = ext.OSQPSettings()
        ext.osqp_set_default_settings(settings)
        settings.verbose = False
        for name, value in self._settings.items():
            if not hasattr(settings, name):
                raise ValueError(f"OSQP has no setting {name!r}")
            setattr(settings, name, value)
        m, n = Ac.shape
        try:
            return ext.OSQPSolver(ext.CSC(Pc), q, ext.CSC(Ac), lower, upper, m, n, settings)
        except (ValueError, RuntimeError) as exc:
            raise SolverError(f"OSQP set-up failed ({m} x {n}): {exc}") from exc

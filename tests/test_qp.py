"""planner.qp: OSQP's core on small dense QPs (set up once per size, then updated)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from planner.qp import DenseQp, dense_csc

TIGHT = {"eps_abs": 1e-9, "eps_rel": 1e-9, "max_iter": 50000, "polishing": True}


def _box_qp(target, lo, hi):
    """min |x - target|^2 s.t. lo <= x <= hi: the answer is target clipped to the box."""
    n = len(target)
    return 2.0 * np.eye(n), -2.0 * np.asarray(target, float), np.eye(n), np.asarray(lo, float), \
        np.asarray(hi, float)


def test_dense_csc_stores_every_entry_and_round_trips():
    rng = np.random.default_rng(0)
    M = rng.normal(size=(5, 4))
    M[1, 2] = 0.0
    A = dense_csc(M)
    assert A.nnz == 20  # the zero is stored: one pattern per size
    np.testing.assert_array_equal(A.toarray(), M)
    S = M[:4, :4] + M[:4, :4].T
    U = dense_csc(S, upper=True)
    assert U.nnz == 10
    np.testing.assert_array_equal(U.toarray(), np.triu(S))


def test_box_qp_solution_is_the_clipped_target():
    res = DenseQp(**TIGHT).solve(*_box_qp([2.0, -3.0, 0.25], [-1, -1, -1], [1, 1, 1]))
    assert res.solved and not res.primal_infeasible
    np.testing.assert_allclose(res.x, [1.0, -1.0, 0.25], atol=1e-6)


def test_equality_constrained_qp_matches_kkt():
    """min x'Qx/2 + c'x s.t. a'x = b: solved by its KKT system."""
    Q = np.array([[4.0, 1.0], [1.0, 3.0]])
    c = np.array([1.0, -2.0])
    a = np.array([[1.0, 1.0]])
    K = np.block([[Q, a.T], [a, np.zeros((1, 1))]])
    x_kkt = np.linalg.solve(K, np.array([-1.0, 2.0, 1.0]))[:2]
    res = DenseQp(**TIGHT).solve(Q, c, a, np.array([1.0]), np.array([1.0]))
    np.testing.assert_allclose(res.x, x_kkt, atol=1e-6)


def test_updated_solver_agrees_with_a_cold_one():
    warm = DenseQp(**TIGHT)
    warm.solve(*_box_qp([0.5, 0.5], [-1, -1], [1, 1]))
    second = _box_qp([3.0, -0.2], [-2, -1], [2, 1])
    np.testing.assert_allclose(warm.solve(*second).x, DenseQp(**TIGHT).solve(*second).x,
                               atol=1e-6)
    # a new size sets the solver up again
    third = _box_qp([3.0, -0.2, 9.0], [-2, -1, 0], [2, 1, 1])
    np.testing.assert_allclose(warm.solve(*third).x, [2.0, -0.2, 1.0], atol=1e-6)


def test_infeasible_problem_is_named_and_has_no_solution():
    # x1 + x2 >= 3 inside the box [-1, 1]^2
    A = np.vstack([np.eye(2), [[1.0, 1.0]]])
    res = DenseQp(**TIGHT).solve(2 * np.eye(2), np.zeros(2), A, np.array([-1, -1, 3.0]),
                                 np.array([1, 1, np.inf]))
    assert res.primal_infeasible and not res.solved and res.x is None


def test_unknown_setting_is_refused():
    with pytest.raises(ValueError, match="no setting 'eps_absolute'"):
        DenseQp(eps_absolute=1e-6).solve(*_box_qp([0.0], [-1], [1]))


def test_catch_planner_imports_without_scipy():
    """SciPy (0.15-0.25 s of start) is imported by the first QP solve, not at start."""
    code = "import sys, planner.catch.plan.api, planner.cli; print('scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "False"


def test_polishing_prints_nothing_into_standard_output(capfd):
    """OSQP 1.0 prints "Polishing not needed ..." with printf when the optimum has no
    active constraint, verbose or not: a catch streamed to standard output (``-o -``,
    35 deg from 0.5 m) carried that line inside its trajectory. The solver's own output
    goes to the null device; what Python wrote before and after stays."""
    qp = DenseQp(eps_abs=1e-9, eps_rel=1e-9, polishing=True)
    print("before", flush=True)
    res = qp.solve(np.eye(2), np.array([-0.1, 0.2]), np.eye(2), -np.ones(2), np.ones(2))
    print("after", flush=True)
    assert res.x == pytest.approx([0.1, -0.2], abs=1e-8)  # (interior: no active set)
    assert capfd.readouterr().out == "before\nafter\n"


def test_catch_streamed_to_standard_output_is_only_the_trajectory():
    out = subprocess.run([sys.executable, "cli.py", "catch", "--angle", "35", "--dist", "0.5",
                          "-o", "-"], capture_output=True, text=True, check=True,
                         cwd=str(__import__("pathlib").Path(__file__).resolve().parents[1])).stdout
    from planner.trajfile import parse_trajectory

    assert "Polishing" not in out
    assert len(parse_trajectory(out).t_s) > 10

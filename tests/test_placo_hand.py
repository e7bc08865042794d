"""The placo solver of a hand built on first use (planner/placo_hand.py)."""

import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _solver_parts(hand) -> set[str]:
    """What ``PlacoHand.build`` sets (placo's objects and what is read from them): the
    names a ``HandIK`` has once built and not before."""
    from planner.ik import HandIK

    built = HandIK(hand)
    before = set(vars(built))
    built.build()
    parts = set(vars(built)) - before
    assert {"robot", "solver", "posture", "stay", "arm_task"} <= parts
    return parts


def test_the_live_start_does_not_load_placo(tmp_path):
    """``catch --live`` set up (then ended by the empty input, exit 2) without placo: its
    palm poses are confirmed by the hand model where the warm start meets the task
    (``HandIK.solve_palm``), and the solver is built only by a solve that iterates."""
    code = ("import sys; from planner.cli import main; "
            "rc = main(['catch', '--live', '--dist', '1.5', '--drag', '-o', sys.argv[1]]); "
            "print(rc, 'placo' in sys.modules, 'planner.ik' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path / "live.csv")], cwd=ROOT,
                       stdin=subprocess.DEVNULL, capture_output=True, text=True, check=False)
    assert r.stdout.split() == ["2", "False", "True"], r.stdout + r.stderr
    assert "0 observations of the ball" in r.stderr


def test_a_solver_built_on_first_use_solves_as_one_built_at_once():
    """The same solves, bit for bit, from a ``HandIK`` whose placo robot is built by its
    first solve and from one built before any (the construction order of the objects is
    the same): a palm pose that needs iterations, then a press."""
    from planner.catch.plan.api import get_planner
    from planner.ik import HandIK, press_target

    pl = get_planner("default")
    h, q = pl.hand, pl.q_rest.copy()
    lazy, eager = HandIK(h), HandIK(h)
    eager.build()
    parts = _solver_parts(h)
    assert not parts & set(vars(lazy))  # nothing of placo yet
    T = h.palm_pose(q)
    point, n = T[:3, 3] + 0.03 * T[:3, 2] + np.array([0.0, 0.05, 0.0]), T[:3, 2]
    a = lazy.solve_palm(point, n, q, q, offset_m=0.03, max_iter=20)
    b = eager.solve_palm(point, n, q, q, offset_m=0.03, max_iter=20)
    assert parts <= set(vars(lazy))
    assert a.iterations == b.iterations > 0
    np.testing.assert_array_equal(a.q, b.q)
    assert a.press_error_m == b.press_error_m
    press = [press_target("index", 60)]
    c, d = (ik.solve(press, a.q, a.q, max_iter=10) for ik in (lazy, eager))
    np.testing.assert_array_equal(c.q, d.q)
    assert (c.iterations, c.press_error_m, c.hover_clearance_m) == (
        d.iterations, d.press_error_m, d.hover_clearance_m)


def test_a_start_that_meets_the_task_builds_no_solver():
    from planner.catch.plan.api import get_planner
    from planner.ik import HandIK

    pl = get_planner("default")
    h, q = pl.hand, pl.q_rest.copy()
    ik = HandIK(h)
    T = h.palm_pose(q)
    res = ik.solve_palm(T[:3, 3] + 0.03 * T[:3, 2], T[:3, 2], q, q, offset_m=0.03)
    assert res.iterations == 0
    assert not _solver_parts(h) & set(vars(ik))


def test_an_unknown_attribute_is_still_an_attribute_error():
    import pytest

    from planner.catch.plan.api import get_planner
    from planner.ik import HandIK

    ik = HandIK(get_planner("default").hand)
    # (a special name, as copy and pickle ask, builds nothing; any other builds the
    # solver, which lacks it)
    assert not hasattr(ik, "__deepcopy__") and "robot" not in vars(ik)
    with pytest.raises(AttributeError, match="no_such"):
        ik.no_such  # noqa: B018

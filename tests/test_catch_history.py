"""A catch plan is a function of its throw: the same throw planned by a planner that has
planned nothing and by one that has planned another throw first gives the same file, byte
for byte. (The contact speeds' OSQP solvers were once kept between plans: their adapted step
size carried over, and 75 deg from 1.0 m was infeasible -- the roll -- on a fresh planner
and feasible after 35 deg from 0.5 m, whose plan also ran the hand's fall.)"""

from __future__ import annotations

from planner.catch.flight.path import get_ball
from planner.catch.plan.api import get_planner, plan_throw, write_plan
from planner.catch.plan.planner import CatchPlanner


def _planner() -> CatchPlanner:
    """A planner of the default hand and mount that has planned nothing."""
    pl = get_planner("default")
    return CatchPlanner(pl.base_hand, pl.mount)


def _bytes(plan, path) -> bytes:
    write_plan(plan, str(path))
    return path.read_bytes()


def test_a_plan_does_not_depend_on_the_plans_before_it(tmp_path):
    ball = get_ball("tennis")
    fresh = plan_throw(75.0, 1.0, 0.0, planner=_planner(), ball=ball)
    pl = _planner()
    before = plan_throw(65.0, 1.0, -0.3, planner=pl, ball=ball)
    # the earlier throw runs the same fallbacks (the rig, the hand's fall) as this one
    # (-0.3 m / 65 deg / 1.0 m since the catch keeps the joints' stop margins: 0 m / 35 deg /
    # 0.5 m, the earlier throw before, is caught palm up now)
    assert any(n.startswith("the hand falls with the ball") for n in before.notes), before.notes
    assert any(n.startswith("the hand falls with the ball") for n in fresh.notes), fresh.notes
    after = plan_throw(75.0, 1.0, 0.0, planner=pl, ball=ball)
    assert after.feasible == fresh.feasible
    assert after.reason_kinds == fresh.reason_kinds
    assert after.notes == fresh.notes
    assert _bytes(after, tmp_path / "after.csv") == _bytes(fresh, tmp_path / "fresh.csv")

"""The palm gives with the ball where closing on it would need more than a motor
(planner.catch.plan.contactqp: contact_speeds(..., give=True); stopping.stop_profile): the ball's
speed into the palm is then no more than its own. No wall-clock assertions."""

from __future__ import annotations

import numpy as np
import pytest

from planner.catch.live.stop import box_qp
from planner.catch.plan.contactqp import ROLL_WEIGHT, contact_qp, contact_speeds


def test_a_palm_that_would_close_on_the_ball_gives_with_it():
    """One joint moving the palm along it and into the ball: the roll term's optimum moves
    it (matching the ball's 2 m/s along the palm, the palm closing at 0.5 x its speed); the
    answer holds it still instead (closing is never better for the pad, giving is worse for
    the roll), and the ball's speed into the palm is its own 6 m/s, not more."""
    J = np.array([[1.0], [0.0], [0.5]])
    n, v = np.array([0.0, 0.0, 1.0]), np.array([2.0, 0.0, -6.0])
    b = np.array([8.0])
    P, c = contact_qp(J, v, n, ROLL_WEIGHT)
    free = box_qp(P, c, -b, b)
    assert float(n @ J @ free) > 0.5  # the weighted optimum closes on the ball
    assert np.allclose(contact_speeds(J, v, b, n, ROLL_WEIGHT), free, atol=1e-6)
    x = contact_speeds(J, v, b, n, ROLL_WEIGHT, give=True)
    assert float(n @ J @ x) <= 1e-6
    assert abs(float(n @ (v - J @ x))) <= abs(float(n @ v)) + 1e-6
    assert x[0] == pytest.approx(0.0, abs=1e-6)


def test_a_giving_palm_never_closes_and_keeps_the_open_optimum():
    """Random problems, ``give``: the palm's speed along its normal is never towards the
    ball, and where the box's optimum gives with the ball it is the answer (to the solvers'
    rounding: OSQP against the exact active-set minimum)."""
    rng = np.random.default_rng(3)
    kept = 0
    for _ in range(300):
        J = rng.normal(size=(3, 3)) * rng.uniform(0.01, 0.5)
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        v = rng.normal(size=3) * 5
        v -= (abs(v @ n) + 1.0) * n if v @ n > 0 else 0.0  # the ball arrives against n
        b = rng.uniform(0.1, 8.0, 3)
        x = contact_speeds(J, v, b, n, ROLL_WEIGHT, give=True)
        assert float(n @ J @ x) <= 1e-6
        assert np.all(np.abs(x) <= b + 1e-12)
        P, c = contact_qp(J, v, n, ROLL_WEIGHT)
        free = box_qp(P, c, -b, b)
        if float(n @ J @ free) < -1e-3:
            kept += 1
            assert np.allclose(x, free, atol=1e-5)
    assert kept > 50


@pytest.mark.parametrize("height, dist", [(0.0, 2.0), (0.3, 2.5)])
def test_the_steep_throw_meets_a_palm_that_gives(pl, height, dist):
    """75 deg from 2 m and on, the arm alone: the stopping motion met the ball 0.5-0.6 m/s
    faster than it flies (the palm turned into it), its pad force beyond the wrist flexion.
    Now the palm recedes along its normal or waits: the relative speed into the palm is no
    more than the ball's."""
    from planner.catch.flight.path import get_ball, predict_throw
    from planner.catch.plan.stopping import plan_stop

    fl = predict_throw(75.0, dist, height, get_ball("tennis"), False)
    C = np.array([dist, 0.0, height])
    r = fl.ball.radius_m
    ready = lambda q: 0.03 + pl.dyn.move_time(pl.q_rest, q)
    _, q_open, stop = plan_stop(pl.dyn, pl.wrist, fl, C, r, pl.q_zero, pl.closing(r),
                                 fl.time_at_x(dist), ready, 0.01, True)
    n = pl.hand.palm_pose(q_open)[:3, 2]
    v_ball = fl.velocity(stop.t_i)
    assert float(n @ stop.v_palm) <= 1e-6
    assert abs(float(n @ stop.v_rel)) <= abs(float(n @ v_ball)) + 1e-6
    assert np.linalg.norm(stop.v_rel) <= np.linalg.norm(v_ball) + 1e-6


def test_a_closing_palm_within_the_motors_keeps_its_roll_match(pl):
    """-0.3 m / 75 deg / 1.5 m: the palm closes on the ball with the pad's load within
    every motor; it keeps the roll term's match (giving, the ball rolls 234 mm off the
    wrist side), and the plan stays feasible."""
    from planner.catch.plan.api import plan_throw

    plan = plan_throw(75.0, 1.5, -0.3, planner=pl)
    assert plan.feasible, plan.reasons

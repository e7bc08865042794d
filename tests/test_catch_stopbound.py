"""The stop bound (``planner.catch.plan.stopbound``): the least motor load of any stop of a
throw, a linear programme over the arm's motions."""

import numpy as np
import pytest

from planner.catch.plan.api import get_ball
from planner.catch.plan.stopbound import (
    BoundGrid,
    cone_tangents,
    least_stop_load,
    motion_of,
    motor_loads,
    solve_program,
    stop_program,
)
from planner.check.ballroll import ROLL_ROOM_M
from planner.check.ballstop import PALM_MU

COARSE = BoundGrid()  # 5 ms steps (at 10 ms the pad cannot stop the ball within a step)


def _intercept(p):
    """The plan ``p``, the hand's pose at its intercept row and the ball's arrival velocity."""
    k = int(np.argmin(np.abs(p.rows.t - p.intercept.t_s)))
    return p, p.rows.q[k].copy(), np.asarray(p.intercept.arrival_velocity, dtype=float)


@pytest.fixture(scope="module")
def steep(facing):
    """0 m / 75 deg / 3.0 m (7.7 m/s): too fast to stop for the planner's stops facing the
    ball (the plan before the palm-up stage: palm up 20 deg it is caught with the stop
    optimised on its rows, docs/history/2026-12-07-catch-roll2.md)."""
    return _intercept(facing(75.0, 3.0))


def _share(P, x):
    """The peak load share of the motion ``x`` (the most loaded arm motor), recomputed from
    its accelerations and forces alone."""
    acc, f = motion_of(P, x)
    return float((np.abs(motor_loads(P.terms, acc, f, P.layout.pre)) / P.terms.cap).max())


def test_the_bound_is_below_every_sampled_stop(pl, steep):
    """A sampled search over the programme's stops (the optimum of 12 random objectives
    over the accelerations and forces, each a stop that keeps every rule): none loads the
    arm's motors less than the bound, and the bound's own motion loads them as much as it
    says."""
    ball = get_ball("tennis")
    _, q, v = steep
    P = stop_program(pl.rig_dyn, q, v, ball.mass_kg, ball.radius_m, COARSE)
    best = solve_program(P)
    assert best.status == 0
    s_min = float(best.x[P.layout.s])
    assert _share(P, best.x) == pytest.approx(s_min, abs=1e-6)
    rng = np.random.default_rng(7)
    V = P.layout
    for _ in range(12):
        c = np.zeros(V.total)
        c[V.a:V.p] = rng.normal(size=V.p - V.a) * 1e-3
        c[V.f:V.u] = rng.normal(size=V.u - V.f)
        res = solve_program(P, c)
        assert res.status == 0
        assert _share(P, res.x) >= s_min - 1e-6


def test_the_bounds_stop_keeps_the_rules(pl, steep):
    """The bound's motion integrated anew (the arm and the ball apart): both at rest at the
    end, the ball on the pad within its give, the palm's half width and the roll room from
    its touch on, the force in the cone's
    pyramid, every joint within its speed and acceleration limits."""
    ball = get_ball("tennis")
    _, q, v = steep
    b = least_stop_load(pl.rig_dyn, q, v, ball.mass_kg, ball.radius_m, COARSE)
    P = stop_program(pl.rig_dyn, q, v, ball.mass_kg, ball.radius_m, COARSE)
    V, T, dt = P.layout, P.terms, COARSE.dt_s
    arm = list(pl.rig_dyn.arm)
    vel = np.vstack([np.zeros(V.k), np.cumsum(b.acc, axis=0) * dt])
    pos = np.vstack([np.zeros(V.k), np.cumsum(vel[:-1] * dt + 0.5 * b.acc * dt * dt, axis=0)])
    pos -= pos[V.pre]
    u, x = v.copy(), np.zeros(3)
    for s, f in enumerate(b.force_n):
        a = f / ball.mass_kg + np.array([0.0, 0.0, -9.81])
        x, u = x + u * dt + 0.5 * a * dt * dt, u + a * dt
        off = x - T.J_target @ pos[V.pre + s + 1]  # the ball from the palm's target
        assert -1e-7 <= -T.n @ off <= pl.hand.pad_give_m + 1e-7
        assert abs(T.x @ off) <= T.half_width_m + 1e-7 and T.y @ off <= ROLL_ROOM_M + 1e-7
    assert np.abs(u).max() < 1e-6 and np.abs(vel[-1]).max() < 1e-6
    fn = b.force_n @ T.n
    assert (fn >= -1e-7).all()
    for t in cone_tangents(T.n):
        assert (np.abs(b.force_n @ t) <= PALM_MU * fn + 1e-6).all()
    assert (np.abs(vel) <= pl.hand.velocity[arm] + 1e-6).all()
    assert (np.abs(b.acc) <= pl.hand.acceleration[arm] + 1e-6).all()
    assert b.torque_nm == pytest.approx(b.share * b.capacity_nm, rel=1e-5)


def test_the_steep_fast_throw_is_not_beyond_the_hand(pl, steep):
    """0 m / 75 deg / 3.0 m: the planner's stops need 3.03 N m of the wrist flexion's
    2.00, yet a stop within every arm motor's capacity is not excluded: the hand's own
    inertia about the flexion takes the ball's push (measured: 0.21 of the capacity at 5 ms
    steps); the arm alone (rig's reach held) needs more."""
    ball = get_ball("tennis")
    p, q, v = steep
    assert not p.feasible
    b = least_stop_load(pl.rig_dyn, q, v, ball.mass_kg, ball.radius_m, COARSE)
    assert b.share < 0.5
    arm = least_stop_load(pl.dyn, q, v, ball.mass_kg, ball.radius_m, COARSE)
    assert arm.share > b.share


def test_the_too_fast_reason_is_judged_by_the_bound(pl, steep):
    """``bounded_reasons``: the tennis ball on 0 m / 75 deg / 3.0 m is the planner's
    shortfall (no stop found), the bound's share of the most loaded motor in the reason;
    a ball 30 times as heavy at the same speed is too fast to stop (a hard limit), the
    least torque any stop needs in the reason, above the motor's capacity."""
    import re

    from planner.catch.plan.reasons import HARD_LIMITS, CatchReason, Reason
    from planner.catch.plan.stopbound import bounded_reasons

    ball = get_ball("tennis")
    _, q, v = steep
    fast = Reason(CatchReason.TOO_FAST_TO_STOP, "too fast to stop (the planner's stops)")
    other = Reason(CatchReason.ROLL, "rolls")
    light = bounded_reasons((other, fast), pl.rig_dyn, q, v, ball.mass_kg, ball.radius_m)
    assert light[0] is other and light[1].kind is CatchReason.NO_STOP
    assert light[1].kind not in HARD_LIMITS
    m = re.search(r"the stop bound: motor\.(\w+) at ([\d.]+) of its ([\d.]+) N m", light[1].detail)
    assert m and float(m.group(2)) <= 1.0 and "the planner's stops" in light[1].detail
    heavy = bounded_reasons((fast,), pl.rig_dyn, q, v, 30 * ball.mass_kg, ball.radius_m)
    assert heavy[0].kind is CatchReason.TOO_FAST_TO_STOP
    m = re.search(r"any stop of the arm needs motor\.(\w+) at ([\d.]+) N m or more > its "
                  r"([\d.]+) N m", heavy[0].detail)
    assert m and float(m.group(2)) > float(m.group(3)) == 2.0, heavy[0].detail

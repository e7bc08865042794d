"""The catch with the rig's reach axis (``planner.catch.plan.intercept.find_intercept_square``,
``CatchPlanner.plan``'s rig fallback): where the arm alone fails, the palm meets the ball
square to the throw (wrist deviation 0) with the reach axis putting it on the ball's path,
and the stopping motion moves the reach too. No wall-clock assertions."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from planner.catch.flight.path import get_ball, predict_throw
from planner.catch.plan.api import plan_throw, write_plan
from planner.catch.plan.arm import palm_target
from planner.catch.plan.intercept import find_intercept_square
from planner.catch.plan.reasons import HARD_LIMITS, CatchReason
from planner.check import check_trajectory
from planner.trajfile import read_trajectory


def test_the_square_intercept_puts_the_palm_on_the_path(pl):
    """65 deg through (1.5, 0, -0.3): the square intercept has the deviation at 0, the reach
    within its travel, the palm target on the ball (the IK's 1 mm) and the palm facing it."""
    ball = get_ball("tennis")
    fl = predict_throw(65.0, 1.5, -0.3, ball, False)
    C = np.array([1.5, 0.0, -0.3])
    ic = find_intercept_square(pl.wrist, fl, C, ball.radius_m, float(fl.time_at_x(1.5)))
    assert ic is not None and ic.reason is None and ic.aligned and ic.dev == 0.0
    h, j = pl.hand, pl.rig
    assert h.lower[j.i_reach] < ic.reach < h.upper[j.i_reach] and ic.reach != 0.0
    q = pl.q_zero.copy()
    q[[j.i_flex, j.i_dev, j.i_rail, j.i_reach]] = ic.theta, ic.dev, ic.rail, ic.reach
    gap = np.linalg.norm(palm_target(h, q, ball.radius_m) - (fl.position(ic.t) - C))
    assert gap < 1e-3
    n, v = h.palm_pose(q)[:3, 2], fl.velocity(ic.t)
    assert math.degrees(math.acos(min(1.0, -(n @ v) / np.linalg.norm(v)))) < 0.5


@pytest.mark.parametrize("throw", [(65.0, 1.5, -0.3), (75.0, 1.5, 0.0), (25.0, 2.5, 0.3)])
def test_throws_the_arm_alone_loses_to_the_roll_are_caught_with_the_reach(pl, tmp_path, throw):
    """Measured (bench/bench_catch_wide.py, the ball-on-palm roll model): with the arm alone
    these roll 45, 3275 and 439 mm towards the wrist; with the reach axis they are feasible,
    ``check`` confirms them and the rows move the reach."""
    p = plan_throw(*throw, planner=pl)
    assert p.feasible, p.reasons
    assert any(n.startswith("the rig's reach axis moves") for n in p.notes)
    out = tmp_path / "c.csv"
    write_plan(p, str(out))
    rep = check_trajectory(str(out))
    assert rep.ok, rep.problems
    i = pl.hand.index["reach"]
    assert np.ptp(read_trajectory(str(out)).q[:, i]) > 0.01


def test_a_plan_of_the_arm_alone_holds_the_reach(pl):
    """A throw the arm alone catches is planned as before: the reach axis stays at 0."""
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    assert p.feasible
    assert np.all(p.rows.q[:, pl.hand.index["reach"]] == 0.0)
    assert not any("reach axis" in n for n in p.notes)


def test_a_steep_fast_throw_names_the_planners_shortfall_and_the_bound(facing):
    """75 deg from 3.0 m arrives at 7.7 m/s: with the arm alone and with the reach axis too,
    the stop searched in coarse and in fine steps and with per-joint ramps, the planner's
    stops need more of the wrist flexion's motor than its 2 N m (the coarse search's:
    3.03 N m), with the force and the torque in the reason; the reach's try is noted. The
    stop bound over every motion of the arm (``planner.catch.plan.stopbound``) does not
    exclude a stop within every motor (measured: 0.21 of the capacity, the
    hand's inertia taking the ball's push): not a hard limit but the planner's shortfall
    (``CatchReason.NO_STOP``), the bound's share in the reason. (75 deg from 2.0 and 2.5 m,
    this test's throws before, are caught: docs/history/2026-12-07-catch-ramps2.md; and this
    one palm up with the stop optimised on its rows, docs/history/2026-12-07-catch-roll2.md:
    its plan facing the ball, every stage before the palm-up one, is what is judged.)"""
    p = facing(75.0, 3.0, 0.0)
    assert not p.feasible and CatchReason.NO_STOP in p.reason_kinds
    assert not set(p.reason_kinds) & HARD_LIMITS
    fast = next(r for r in p.reasons if r.kind is CatchReason.NO_STOP)
    m = re.search(r"([\d.]+) N needs motor\.wrist_flex at ([\d.]+) N m > its gear limit "
                  r"([\d.]+) N m", str(fast))
    assert m and float(m.group(2)) > float(m.group(3)) == 2.0
    b = re.search(r"the stop bound: motor\.\w+ at ([\d.]+) of its ([\d.]+) N m", str(fast))
    assert b and float(b.group(1)) <= 1.0 and float(b.group(2)) == 2.0
    assert any(n.startswith("with the rig's reach axis moving too: ") for n in p.notes)
    assert not any("finer steps" in n for n in p.notes)  # the finer search found nothing


@pytest.mark.parametrize("throw, on_the_reach", [((75.0, 2.0, 0.0), True),
                                                  ((75.0, 2.5, 0.3), True)])
def test_the_stop_searched_in_finer_steps_catches_a_fast_throw(pl, tmp_path, throw,
                                                              on_the_reach):
    """75 deg from 2.0 m (height 0) and from 2.5 m (+0.3 m): with the stop's coarse steps
    (tilts 5 deg, contact shares 0.1) every plan is too fast to stop (the arm alone: 2.03
    and 2.39 N m of the wrist flexion's 2.00); in the finer steps (``FINE_STOP``) the ball is
    stopped within every motor by the reach's square intercept, the plan says so, ``check``
    confirms it. (45 deg from 4.0 m (-0.3 m), caught by the arm alone's finer steps before
    the catch kept the joints' stop margins, is caught by the per-joint ramps on the reach
    now: ``test_catch_ramps``.)"""
    p = plan_throw(*throw, planner=pl)
    assert p.feasible, p.reasons
    note = [n for n in p.notes if n.startswith("the stop searched in finer steps")]
    assert note and "too fast to stop" in note[0]
    assert any(n.startswith("the rig's reach axis moves") for n in p.notes) == on_the_reach
    checked_reach(p, pl, tmp_path)


def test_caught_with_the_reach_in_physics(pl, tmp_path):
    """The reach's catch of 65 deg through (1.5, 0, -0.3) is held in MuJoCo (measured: 47.6 mm
    from the palm centre at the end, the hand falling with the ball; 34 mm before the catch
    kept the joints' stop margins, docs/history/2026-12-07-catch-limits.md)."""
    pytest.importorskip("mujoco")
    from planner.simulate import simulate_trajectory

    out = tmp_path / "c.csv"
    write_plan(plan_throw(65.0, 1.5, -0.3, planner=pl), str(out))
    c = simulate_trajectory(str(out)).catch
    assert c is not None and c.held and c.end_distance_m < 0.0476 + 0.005


def checked_reach(p, pl, tmp_path):
    """The plan written, ``check`` confirming it; its rows and the reach joint's index."""
    out = tmp_path / "c.csv"
    write_plan(p, str(out))
    rep = check_trajectory(str(out))
    assert rep.ok, rep.problems
    return read_trajectory(str(out)), pl.hand.index["reach"]


def test_the_hand_falls_with_the_ball_where_the_reach_alone_lets_it_roll(pl, tmp_path):
    """-0.3 m / 75 deg / 1.0 m: on the reach without the fall the ball rolls off the palm's
    wrist side (the note says so); with the hand falling on the reach axis after the ball
    lands (``planner.catch.plan.drop``) the plan is feasible, ``check`` confirms it, and the
    reach moves down after the intercept within its travel."""
    p = plan_throw(75.0, 1.0, -0.3, planner=pl)
    assert p.feasible, p.reasons
    note = [n for n in p.notes if n.startswith("the hand falls with the ball")]
    assert note and "rolls off the palm's wrist side" in note[0]
    tr, i = checked_reach(p, pl, tmp_path)
    after = tr.t_s > p.intercept.t_s
    assert np.all(tr.q[:, i] >= pl.hand.lower[i]) and np.all(tr.q[:, i] <= pl.hand.upper[i])
    assert tr.q[after, i].min() < tr.q[~after, i][-1] - 0.01  # the hand gives way downwards


def test_the_fall_moves_no_row_up_to_the_landing(pl):
    """``add_drop`` changes the reach only on rows after the first row past the landing
    (``HoldTurn._motors_within`` judges the motors up to the intercept on rows without the fall):
    75 deg from 1.0 m, whose plan falls, its rows with and without the fall."""
    from planner.catch.plan.drop import add_drop

    p = plan_throw(75.0, 1.0, 0.0, planner=pl)
    assert p.feasible, p.reasons
    t, Q, t_i = p.rows.t, p.rows.q, p.intercept.t_s
    flat = Q.copy()
    flat[t > t_i, pl.rig.i_reach] = Q[t <= t_i, pl.rig.i_reach][-1]  # the fall taken out
    out = add_drop(pl.rig_dyn, t, flat, pl.rig.i_reach, t_i, p.flight.velocity(t_i),
                   0.0335, 0.6)
    assert out is not flat  # it falls
    k0 = int(np.flatnonzero(t > t_i)[0])
    assert np.array_equal(out[: k0 + 1], flat[: k0 + 1])
    assert np.any(out[k0 + 1:] != flat[k0 + 1:])


def test_the_fall_keeps_rows_that_roll_less_without_it(pl):
    """``add_drop`` returns the rows unchanged where its fall would not roll the ball less
    (a palm held level: nothing rolls towards the wrist)."""
    from planner.catch.plan.drop import add_drop

    j = pl.rig
    q = pl.q_zero.copy()
    q[j.i_flex] = -1.1  # the palm up, its downhill towards the fingers
    t = np.arange(60) * 0.01
    Q = np.tile(q, (60, 1))
    out = add_drop(pl.rig_dyn, t, Q, j.i_reach, 0.105, np.array([0.0, 0.0, -1.0]), 0.033, 0.6)
    assert out is Q


def test_the_fall_keeps_the_ball_on_the_palm(pl):
    """``allowed_accel``: a level palm at rest under the ball (its force m (a - g) = m g up)
    may fall on a vertical axis at most at g (faster it would leave the ball: the force
    would have to pull), and on a horizontal one (the force's tangential part) at most at
    95 % of mu g either way (the motors' room is wider at the zero pose)."""
    from planner.catch.plan.drop import CONE_SHARE, allowed_accel
    from planner.check.ballstop import PALM_MU

    q = pl.q_zero.copy()
    z = np.zeros(pl.hand.n)
    up = np.array([0.0, 0.0, 1.0])
    b = np.array([0.0, 0.0, 9.81])  # the palm target at rest, less gravity
    lo, hi = allowed_accel(pl.rig_dyn, q, z, pl.rig.i_reach, b, up, up)
    assert lo == pytest.approx(-9.81, abs=1e-9)
    assert hi > 20.0  # up: the motors' room (the carriage's 2 N m at 10 mm moves the hand)
    lo, hi = allowed_accel(pl.rig_dyn, q, z, pl.rig.i_reach, b, np.array([1.0, 0.0, 0.0]), up)
    mu_g = CONE_SHARE * PALM_MU * 9.81
    assert lo == pytest.approx(-mu_g, rel=1e-9) and hi == pytest.approx(mu_g, rel=1e-9)


def test_the_fall_ends_without_leaving_the_ball(pl, tmp_path):
    """75 deg from 1 m is caught with the hand falling on the reach axis; the fall stops by
    the rows' end no harder than the riding ball allows: from 30 ms after the intercept on,
    the palm target never accelerates away from the ball faster than gravity follows it
    (m (a - g) . n >= 0: the contact cannot pull). The fall once stopped within its last row
    (18.7 m/s^2 from 0.187 m/s) and the replay's resting ball left the palm."""
    from planner.check.ball import CONE_TOL_N
    from planner.check.kinematics import Kinematics
    from planner.hand.model import GRAVITY_WORLD

    p = plan_throw(75.0, 1.0, 0.0, planner=pl)
    assert p.feasible, p.reasons
    out = tmp_path / "c.csv"
    write_plan(p, str(out))
    tr = read_trajectory(str(out))
    i = pl.hand.index["reach"]
    assert np.ptp(tr.q[:, i]) > 0.05  # the hand falls on the reach axis
    _, palm = Kinematics(pl.hand, np.array(tr.metadata["T_world_root"])).frames(tr.q)
    r, m = tr.metadata["ball"]["radius"], tr.metadata["ball"]["mass"]
    centre = palm[:, :3, 3] + r * palm[:, :3, 2]
    dt = float(tr.t_s[1] - tr.t_s[0])
    a = (centre[2:] - 2.0 * centre[1:-1] + centre[:-2]) / (dt * dt)
    f_n = m * np.einsum("ij,ij->i", a - GRAVITY_WORLD, palm[1:-1, :3, 2])
    late = tr.t_s[1:-1] > p.intercept.t_s + 0.03
    assert f_n[late].min() >= -CONE_TOL_N


def test_the_steep_short_throw_falls_with_the_ball_on_the_reach(pl, tmp_path):
    """-0.3 m / 65 deg / 1.0 m: the arm alone loses the ball to the roll; on the reach axis,
    with the hand then falling with the ball (``drop.py``), it is feasible, ``check``
    confirms it, the reach within its travel less its stop margins, the hand giving way
    downwards after the intercept, and MuJoCo holds the ball (measured: 44.4 mm from the
    palm centre at the end). (Before the catch kept the joints' stop margins the reach's own
    plan was too fast to stop here and the arm alone met the ball, the hand then falling
    (``CatchPlanner.arm_fall_turn``, 34 mm); no throw of the eight steep short ones tried
    near it takes that path now: docs/history/2026-12-07-catch-limits.md.)"""
    p = plan_throw(65.0, 1.0, -0.3, planner=pl)
    assert p.feasible, p.reasons
    note = [n for n in p.notes if n.startswith("the hand falls with the ball on the reach axis")]
    assert note and "rolls off the palm's wrist side" in note[0]
    tr, i = checked_reach(p, pl, tmp_path)
    before = tr.t_s <= p.intercept.t_s
    assert np.all(tr.q[:, i] >= pl.hand.plan_lower[i] - 1e-6)
    assert np.all(tr.q[:, i] <= pl.hand.plan_upper[i] + 1e-6)
    assert tr.q[~before, i].min() < tr.q[before, i][-1] - 0.01  # the hand gives way downwards
    pytest.importorskip("mujoco")
    from planner.simulate import simulate_trajectory

    c = simulate_trajectory(str(tmp_path / "c.csv")).catch
    assert c is not None and c.held and c.end_distance_m < 0.0444 + 0.005

"""The soft stop with per-joint ramps (``planner.catch.plan.ramps``, ``softstop``): each
arm joint ramps (and recoils) in its own time within its own limits; throws too fast to
stop with one ramp time for every joint are caught (``JOINT_STOPS``, issue 31)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.balls import get_ball
from planner.catch.grasp import motor_torque_matrix
from planner.catch.plan.api import plan_throw, write_plan
from planner.catch.plan.closing import closing_offsets, earliest_close_start
from planner.catch.plan.ramps import joint_ramps, min_jerk_acc, recoil_shares
from planner.catch.plan.softstop import SoftStop
from planner.catch.plan.stopping import STOP_SHARE
from planner.catch.plan.stopstages import (
    JOINT_STOP,
    LOADED_FINGERS_STOP,
    joint_stop_note,
)
from planner.check import check_trajectory
from planner.trajectory import PEAK_VEL

# too fast to stop on main (a2f3801, the coarse search's numbers; the fine one no better):
# 0 m / 15 deg / 3.5 m 86.8 N, motor.wrist_flex at 2.08 N m; -0.3 m / 65 deg / 3.5 m 68.1 N,
# 2.37 N m (and the roll)
# ... and 0 m / 65 deg / 4.0 m (68.1 N, 2.46 N m), too fast to stop after every stage of the
# branch ``ramp`` too (the rows' 2.13 N m), caught where the recoil is judged with the
# fingers closing (``LOADED_FINGERS_STOP``)
# Since the catch keeps every joint its stop margin inside its hard stops
# (``HandModel.within_margins``, docs/history/2026-12-07-catch-limits.md): 0 m / 15 deg /
# 3.5 m is caught by the reach's coarse stop, before these stages; -0.3 m / 45 deg / 4.0 m
# (the arm alone's finer steps before) by every arm joint recoiling on the reach;
# -0.3 m / 65 deg / 3.5 m by the flexion alone recoiling judged with the fingers closing
# (``LOADED_TILT_STOP`` before: no throw here exercises that stage now)
THROWS = {(45.0, 4.0, -0.3): joint_stop_note(JOINT_STOP),
          (65.0, 3.5, -0.3): joint_stop_note(LOADED_FINGERS_STOP),
          (65.0, 4.0, 0.0): joint_stop_note(LOADED_FINGERS_STOP)}


@pytest.fixture(scope="module")
def planned(pl):
    """The throws' plans, each made once (``plan_throw``), by (angle, distance, height)."""
    made = {}

    def plan(key):
        if key not in made:
            made[key] = plan_throw(*key, planner=pl)
        return made[key]
    return plan


@pytest.fixture(scope="module", params=sorted(THROWS))
def caught(planned, request):
    return planned(request.param), THROWS[request.param]


def _ramp_case(pl):
    """The rig at its zero pose: the reach (1 m/s) and the wrist flexion (7 rad/s) ramp in
    towards the ball, the reach's room 0.035 m."""
    dyn = pl.rig_dyn
    arm = list(dyn.arm)
    q = pl.q_zero.copy()
    qd = np.zeros(len(arm))
    qd[arm.index(pl.rig.i_reach)] = -1.0
    qd[arm.index(pl.rig.i_flex)] = -7.0
    room = np.full(len(arm), 1.0)
    room[arm.index(pl.rig.i_reach)] = 0.035
    return dyn, arm, q, qd, room


def test_each_joints_ramp_keeps_its_own_limits(pl):
    """``joint_ramps``: the reach, whose travel over the common ramp would leave its room,
    ramps quicker than the flexion; every joint within its acceleration limit and its room;
    every motor within STOP_SHARE of its capacity at every instant of the overlapping ramps
    (the hand's inverse dynamics with every joint's acceleration at once, sampled every
    0.1 ms, beside the rule's superposition of each joint's)."""
    dyn, arm, q, qd, room = _ramp_case(pl)
    row_s = 0.01
    common = dyn.ramp_time(q, qd)
    c_reach = arm.index(pl.rig.i_reach)
    assert abs(qd[c_reach]) * (row_s + 0.5 * common) > room[c_reach]  # one ramp: out of range
    T = joint_ramps(dyn, q, qd, room, row_s, common, STOP_SHARE)
    assert T is not None
    c_flex = arm.index(pl.rig.i_flex)
    assert T[c_reach] < T[c_flex]
    moving = qd != 0
    assert np.all(PEAK_VEL * np.abs(qd[moving]) / T[moving] <= dyn.a_max[moving] + 1e-9)
    assert np.all(np.abs(qd) * (row_s + 0.5 * T) <= room + 1e-9)
    M = motor_torque_matrix(pl.hand, q)
    limit = STOP_SHARE * dyn.cap
    worst = 0.0
    for t in np.arange(0.0, float(T.max()) + 1e-4, 1e-4):
        a = np.where(moving, qd * min_jerk_acc(t / np.where(moving, T, 1.0))
                     / np.where(moving, T, 1.0), 0.0)
        tau = M @ dyn.joint_torques(q, qd, a)
        worst = max(worst, float(np.max(np.abs(tau)[:4] / limit[:4])))
    assert worst <= 1.0 + 1e-3


def test_per_joint_profile_meets_the_ball_at_every_joints_contact_speed():
    """A profile with per-joint ramps and contact shares: each joint at rest at its own
    start and end, at its contact speed share x qd from one row before the intercept, at
    full speed after the recoil, its offsets at either end ``first_offset`` and
    ``last_offset``; with every joint's ramps equal it is the common profile."""
    z = np.zeros(3)
    qd = np.array([1.0, -4.0, 0.5])
    base = SoftStop(0.0, (0, 1, 2), qd, 0.7, 1.0, 0.01, 0.12, 0.01, 0.02, 0.15, 0.006,
                    z, z, z, np.zeros(4), 1.0)
    per = SoftStop(0.0, (0, 1, 2), qd, 0.7, 1.0, 0.01, 0.12, 0.01, 0.02, 0.15, 0.006,
                   z, z, z, np.zeros(4), 1.0, np.array([0.05, 0.12, 0.08]),
                   np.array([0.06, 0.15, 0.10]), np.array([0.9, 0.7, 0.7]))
    dt = 1e-5
    t = np.arange(per.start_s - 0.01, per.end_s + 0.01, dt)
    sig = per.sigmas(t)
    v = np.diff(sig, axis=0) / dt
    assert np.max(np.abs(np.diff(v, axis=0))) < 1e-2  # no jump in any joint's speed
    assert np.allclose(v[0], 0.0, atol=1e-9) and np.allclose(v[-1], 0.0, atol=1e-9)
    k = int(np.searchsorted(t, per.t_i - 0.005))
    assert v[k] == pytest.approx(per.shares, abs=1e-3)
    k = int(np.searchsorted(t, per.t_i + per.recoil_s + 0.005))
    assert v[k] == pytest.approx(np.ones(3), abs=1e-3)
    assert np.allclose(per.qd_c, per.shares * qd)
    off = per.offset(np.array([-1e3, 1e3]), 3)
    assert off[0] == pytest.approx(per.first_offset) and off[1] == pytest.approx(per.last_offset)
    assert per.ramp_out_of(0) == pytest.approx(0.06)
    same = SoftStop(*[getattr(base, f) for f in base.__dataclass_fields__][:16],
                    np.full(3, 0.12), np.full(3, 0.15))
    tt = np.linspace(0.7, 1.3, 601)
    assert same.offset(tt, 3) == pytest.approx(base.offset(tt, 3), abs=1e-12)
    assert np.array_equal(base.offset(tt, 3), np.outer(base.sigma(tt), qd))


def test_a_too_fast_throw_is_caught_with_per_joint_ramps(caught, tmp_path):
    """-0.3 m / 45 deg / 4.0 m (every joint recoiling), -0.3 m / 65 deg / 3.5 m and 0 m /
    65 deg / 4.0 m (the wrist flexion alone recoiling): feasible with the per-joint stop (the note names the coarse
    search's too fast to stop), ``check`` confirms the written plan."""
    p, expected = caught
    assert p.feasible, p.reasons
    note = p.notes[-1]
    assert note.startswith(expected + ": in the coarse ones ")
    assert "too fast to stop" in note
    assert p.forces.soft is not None and p.forces.soft.per_joint
    out = tmp_path / "c.csv"
    write_plan(p, str(out))
    rep = check_trajectory(str(out))
    assert rep.ok, rep.problems


def test_the_per_joint_catch_is_held_within_every_motor(caught, tmp_path):
    """The same catches replayed in MuJoCo (full contact): held, no motor saturated longer
    than one 10 ms row (to the replay's float sum of its steps: 0 m / 65 deg / 4.0 m
    measured 0.010000000000000009 s of ring_mcp, one row; the wrist flexion's peak 0.97
    of its 2.00 N m)."""
    pytest.importorskip("mujoco")
    from planner.simulate import simulate_trajectory

    out = tmp_path / "c.csv"
    write_plan(caught[0], str(out))
    res = simulate_trajectory(str(out))
    assert res.catch is not None and res.catch.held
    assert all(m.saturated_s <= 0.010 + 1e-9 for m in res.motors)
    flex = next(m for m in res.motors if m.name == "motor.wrist_flex")
    assert flex.ratio <= 1.0


def test_the_recoil_shares_keep_each_joint_within_its_acceleration(pl):
    """``recoil_shares``: every joint's recoil from its contact speed to its full speed
    within its acceleration limit over the recoil's time (the reach, 40 m/s^2, meets the
    ball nearer its full speed than the flexion); with ``loaded_only`` the joints whose own
    motor is within STOP_SHARE meet it at full speed (share 1)."""
    dyn, arm, q, qd_c, _ = _ramp_case(pl)
    recoil_s, share = 0.01, 0.6
    ratio = np.zeros(len(dyn.cap))
    c_flex, c_reach = arm.index(pl.rig.i_flex), arm.index(pl.rig.i_reach)
    qd_c[c_flex] = -2.0  # (1 / 0.6 - 1) 2 rad/s over 10 ms: 133 rad/s^2, within its 294
    M = np.abs(motor_torque_matrix(pl.hand, q)[:, arm])
    ratio[np.argmax(M[:, c_flex])] = 1.2  # the flexion's motor beyond its share
    c = recoil_shares(dyn, q, qd_c, ratio, share, recoil_s, False, STOP_SHARE)
    assert np.all(c >= share) and np.all(c <= 1.0)
    assert np.all((1.0 / c - 1.0) * np.abs(qd_c) <= dyn.a_max * recoil_s + 1e-9)
    assert c[c_flex] == pytest.approx(share) and c[c_reach] > share
    only = recoil_shares(dyn, q, qd_c, ratio, share, recoil_s, True, STOP_SHARE)
    assert only[c_flex] == pytest.approx(share)
    assert np.all(np.delete(only, c_flex) == 1.0)


def test_the_closing_offsets_are_the_rows_closing(pl):
    """``closing_offsets``: the fingers open (no offset) before the closing's earliest
    start, closed (``q_closed``) once it has lasted its duration, the arm never moved by it,
    each finger between the two in between."""
    r = float(get_ball("tennis").radius_m)
    closing = pl.closing(r)
    q_open = pl.q_zero.copy()
    t_i, stop_t = 1.0, 0.006
    s_c = earliest_close_start(closing, t_i, -np.inf, stop_t)
    t = np.array([s_c - 0.01, s_c, s_c + 0.5 * closing.duration_s, s_c + closing.duration_s,
                  s_c + closing.duration_s + 0.05])
    off = closing_offsets(closing, pl.joints.finger_idx, q_open, t, t_i, stop_t)
    fingers = pl.joints.finger_idx
    full = closing.q_closed[fingers] - q_open[fingers]
    assert np.any(full != 0.0)
    assert np.all(off[:2] == 0.0)
    assert off[3:, fingers] == pytest.approx(np.tile(full, (2, 1)), abs=1e-12)
    assert np.all(off[:, list(pl.joints.arm)] == 0.0)
    mid = off[2, fingers]
    assert np.all(np.abs(mid) <= np.abs(full) + 1e-12)
    assert np.all(mid * full >= 0.0)


def test_the_judge_with_the_closing_fingers_is_nearer_the_rows(pl, planned):
    """0 m / 65 deg / 4.0 m as planned (``LOADED_FINGERS_STOP``): its stop judged around the
    intercept with the fingers closing as the rows close them is nearer the rows' own impact
    load (the check's rule on the whole plan) than judged with the fingers open (measured:
    headroom +0.14 closing, -0.23 open, the rows' impact +0.26; the closing under way at the
    intercept moves the fingers' mass and the tendons' levers about the wrist)."""
    p = planned((65.0, 4.0, 0.0))
    assert p.feasible and p.notes[-1].startswith(joint_stop_note(LOADED_FINGERS_STOP))
    stop = p.forces.soft
    q_open = p.poses.q_open.copy()
    q_open[list(stop.arm)] -= stop.first_offset  # the pre-catch pose less the ramp's travel
    r = float(p.flight.ball.radius_m)
    rows = p.forces.contact.impact.headroom
    _, open_h = pl.rig_dyn.judge(stop, q_open, p.flight, r)
    ok, closing_h = pl.rig_dyn.judge(stop, q_open, p.flight, r, pl.closing(r))
    assert ok
    assert closing_h >= 0.0 and rows >= 0.0
    assert abs(closing_h - rows) < abs(open_h - rows)


def test_joint_stops_are_tried_only_within_their_reach():
    """``JOINT_STOPS`` are tried only where the coarse plan's worst motor needs at most
    ``JOINT_STOPS_REACH`` over its limit (beyond, they cost seconds for an infeasible answer):
    ``FINE_STOP`` is tried either way."""
    from types import SimpleNamespace

    from planner.catch.plan.reasons import CatchReason
    from planner.catch.plan.stopstages import (
        FINE_STOP,
        JOINT_STOPS,
        JOINT_STOPS_REACH,
        joint_stop_fallbacks,
    )

    asked = []

    def replan(grid):
        asked.append(grid)
        return SimpleNamespace(feasible=False)

    def coarse(headroom):
        return SimpleNamespace(feasible=False, reasons=(),
                               reason_kinds=frozenset({CatchReason.TOO_FAST_TO_STOP}),
                               forces=SimpleNamespace(stop=SimpleNamespace(headroom=headroom)))

    far = coarse(-JOINT_STOPS_REACH - 0.01)
    assert joint_stop_fallbacks(replan, far) is far and asked == [FINE_STOP]
    asked.clear()
    near = coarse(-JOINT_STOPS_REACH + 0.01)
    assert joint_stop_fallbacks(replan, near) is near and asked == [FINE_STOP, *JOINT_STOPS]

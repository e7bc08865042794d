"""Tests of planner.check on catch trajectories: the ball's flight, the intercept on
the palm, early touches, the grasp and its hold, the stopping force.

The catches are built without the planner (tests/trajbuild.py), but one: a plan of
planner.catch edited to stop the ball over 2 mm.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from planner.check import ball_positions, check_trajectory
from planner.errors import InputError
from planner.trajfile import read_trajectory
from tests.trajbuild import (
    BALL_R,
    SPEED,
    STOP_M,
    T_I,
    catch_file,
    grasp_posture,
    rewrite,
    write_traj,
)

# ---------------------------------------------------------------- the ball


def test_ball_closed_form_and_rk4():
    p0, v0 = np.array([0.0, 0.1, 1.0]), np.array([4.0, -0.5, 3.0])
    t = np.array([0.0, 0.1234, 0.5, 0.9])
    want = p0 + np.outer(t, v0) + 0.5 * np.outer(t**2, [0, 0, -9.81])
    np.testing.assert_allclose(ball_positions(p0, v0, 0.0, t), want, atol=1e-12)
    # RK4 with a vanishing drag tends to the closed form
    np.testing.assert_allclose(ball_positions(p0, v0, 1e-12, t), want, atol=1e-9)
    # and with drag it matches a tight reference integration
    from scipy.integrate import solve_ivp

    k = 0.02

    def f(_, s):
        v = s[3:]
        return np.r_[v, np.array([0, 0, -9.81]) - k * np.linalg.norm(v) * v]

    ref = solve_ivp(f, (0, 0.9), np.r_[p0, v0], t_eval=t, rtol=1e-12, atol=1e-12).y[:3].T
    got = ball_positions(p0, v0, k, t[::-1])[::-1]  # any order of times
    np.testing.assert_allclose(got, ref, atol=1e-9)
    assert np.linalg.norm(got[-1] - want[-1]) > 1e-3  # drag matters


# ---------------------------------------------------------------- the catch


def test_catch_passes(tmp_path, hand):
    r = check_trajectory(catch_file(tmp_path / "c.csv", hand))
    assert r.ok, r.summary()
    c = r.catch
    assert c.intercept_ok and c.intercept_error_m < 1e-5
    assert not c.early_touches and c.grasp_held
    assert c.grasp_time_s <= T_I + 0.150 and {"thumb", "index", "middle"} <= set(c.grasp_fingers)
    assert r.play is None
    d = json.loads(json.dumps(r.to_dict()))
    assert d["catch"]["ok"] is True and d["ok"] is True
    assert "catch at t=0.500 s" in r.summary()


def test_catch_palm_off_by_5cm(tmp_path, hand):
    _q_grasp, _C, n = grasp_posture()
    side = np.cross(n, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    r = check_trajectory(catch_file(tmp_path / "c.csv", hand, offset=0.05 * side))
    assert not r.ok and not r.catch.intercept_ok
    assert r.catch.intercept_error_m == pytest.approx(0.05, abs=1e-5)
    assert any("misses the palm: 50.0 mm" in p for p in r.problems)


def test_catch_early_touch_late_grasp_and_release(tmp_path, hand):
    # closed before the ball arrives: the fingertips are in its way
    r = check_trajectory(catch_file(tmp_path / "a.csv", hand, close_from=0.1))
    assert not r.ok and r.catch.early_touches
    assert all(e.time_s < T_I and e.distance_m < BALL_R for e in r.catch.early_touches)
    # closing too late
    r = check_trajectory(catch_file(tmp_path / "b.csv", hand, close_from=T_I + 0.1))
    assert not r.ok and r.catch.grasp_time_s is None
    assert any("no grasp within 150 ms" in p for p in r.problems)
    # grasped, then let go
    r = check_trajectory(catch_file(tmp_path / "c.csv", hand, hold_to=T_I + 0.2))
    assert not r.ok and r.catch.grasp_time_s is not None and not r.catch.grasp_held
    assert any("grasp lost" in p for p in r.problems)


def test_catch_intercept_outside_and_bad_metadata(tmp_path, hand):
    path = catch_file(tmp_path / "c.csv", hand, t_end=0.3)
    r = check_trajectory(path)
    assert not r.ok and any("outside the trajectory" in p for p in r.problems)

    def drop_radius(ls):
        m = json.loads(ls[0][2:])
        del m["ball"]["radius"]
        return ["# " + json.dumps(m)] + ls[1:]

    with pytest.raises(InputError, match="radius"):
        check_trajectory(rewrite(path, drop_radius))


def test_catch_frame_mount_may_differ(tmp_path, hand):
    """The catch frame's origin is the launch point: the hand may be mounted anywhere."""
    path = catch_file(tmp_path / "c.csv", hand)
    shift = np.array([2.0, 0.0, 1.0])

    def move(ls):
        m = json.loads(ls[0][2:])
        T = np.array(m["T_world_root"])
        T[:3, 3] += shift
        m["T_world_root"] = T.tolist()
        m["ball"]["p0"] = (np.array(m["ball"]["p0"]) + shift).tolist()
        return ["# " + json.dumps(m)] + ls[1:]

    r = check_trajectory(rewrite(path, move))
    assert r.ok, r.summary()
    assert r.catch.ball_at_intercept[0] == pytest.approx(
        check_trajectory(catch_file(tmp_path / "d.csv", hand)).catch.ball_at_intercept[0] + 2.0)


# ---------------------------------------------------------------- the stopping force (issue 15)


def test_catch_stopping_force_judged(tmp_path, hand):
    """The dynamic judgment: the same catch stopped over 2 cm needs 5x the force of 10 cm,
    more than the wrist flexion motor can give; the loads are reported per phase."""
    ok = check_trajectory(catch_file(tmp_path / "c.csv", hand))
    stop, hold = ok.catch.loads
    assert stop.phase == "stop" and hold.phase == "hold"
    assert stop.speed_m_s == pytest.approx(SPEED, rel=1e-3)
    # F = m (v^2 / (2 d) n - g): against the arrival (along -n), and the weight
    n = grasp_posture()[2]
    want = np.linalg.norm(0.2 * (SPEED**2 / (2 * STOP_M) * n + np.array([0.0, 0.0, 9.81])))
    assert stop.force_n == pytest.approx(want, rel=1e-3)
    assert 0.0 < stop.headroom < 1.0 and ok.ok
    tr = read_trajectory(str(tmp_path / "c.csv"))
    meta = dict(tr.metadata, catch={"stop_distance_m": 0.02})
    bad = write_traj(tmp_path / "hard.csv", hand, tr.t_s, tr.q, metadata=meta)
    rep = check_trajectory(bad)
    assert not rep.ok and rep.catch.loads[0].headroom < 0
    assert any(p.startswith("stopping the ball needs") and "motor.wrist_flex" in p
               for p in rep.problems)
    del meta["catch"]
    rep = check_trajectory(write_traj(tmp_path / "none.csv", hand, tr.t_s, tr.q, metadata=meta))
    assert not rep.ok and any("no stopping distance" in p for p in rep.problems)


def test_catch_plan_edited_to_stop_over_2_mm_rejected(tmp_path):
    """Issue 15: the planner's feasible plan (30 deg from 1.5 m) passes; the same rows
    with its metadata edited to stop the ball over 2 mm instead of 2 cm do not."""
    from planner.catch.plan.api import plan_catch

    res = plan_catch(30.0, 1.5, 0.0, "default", str(tmp_path / "c.csv"))
    assert res.feasible
    good = check_trajectory(str(tmp_path / "c.csv"))
    assert good.ok, good.problems
    assert good.catch.loads[0].headroom == pytest.approx(res.plan.forces.stop.headroom, abs=0.03)
    text = (tmp_path / "c.csv").read_text()
    assert text.count('"stop_distance_m": 0.02') == 1
    (tmp_path / "e.csv").write_text(text.replace('"stop_distance_m": 0.02',
                                                 '"stop_distance_m": 0.002'))
    rep = check_trajectory(str(tmp_path / "e.csv"))
    assert not rep.ok
    assert rep.catch.loads[0].force_n > 9 * good.catch.loads[0].force_n
    assert rep.problems == tuple(p for p in rep.problems if p.startswith("stopping the ball")) \
        + ("the end marker claims the catch held; the rows above say otherwise",)


# ---------------------------------------------------------------- every limit of the hand

PLAY_CATEGORIES = ("joint_position", "joint_stop_margin", "joint_velocity", "motor_velocity",
                   "joint_acceleration", "motor_consistency", "coupling", "joint_jerk",
                   "motor_torque", "tendon_tension")


@pytest.fixture(scope="module")
def fresh_catch(tmp_path_factory):
    """A fresh plan of the catch planner (30 deg from 1.5 m): its file's path."""
    from planner.catch.plan.api import plan_catch

    path = tmp_path_factory.mktemp("fresh") / "c.csv"
    assert plan_catch(30.0, 1.5, 0.0, "default", str(path)).feasible
    return path


def _limit(r, category):
    return next(lc for lc in r.limits if lc.category == category)


def _end_info(tr) -> dict:
    return {k: v for k, v in tr.end.items() if k not in ("end", "rows")}


def test_catch_judged_by_every_limit_of_the_hand(fresh_catch):
    """A catch file's rows are judged by every limit category a play's are (the jerk
    bounds and the stop margins of the hand file's [drive] too), in the same order, in
    the report and in its JSON; the planner's fresh plan is within every one."""
    r = check_trajectory(str(fresh_catch))
    assert r.ok, r.summary()
    assert tuple(lc.category for lc in r.limits) == PLAY_CATEGORIES
    d = json.loads(json.dumps(r.to_dict()))
    assert tuple(lc["category"] for lc in d["limits"]) == PLAY_CATEGORIES
    assert all(lc["ok"] for lc in d["limits"])
    assert "joint_jerk" in r.summary() and "joint_stop_margin" in r.summary()


def test_catch_row_beyond_a_jerk_bound_fails(tmp_path, hand, fresh_catch):
    """The fresh plan with one row of index_mcp_abd moved by half its jerk bound x dt^3
    (towards the middle of its range, after the grasp: the hand holding the ball): two third differences at 1.5 x the
    bound (as a play's, ``test_check.test_jerky_row_flagged``), its acceleration within
    its limit: the check fails on the jerk alone."""
    tr = read_trajectory(str(fresh_catch))
    j = hand.index["index_mcp_abd"]
    dt = 1.0 / tr.metadata["rate_hz"]
    k = len(tr.t_s) - 20
    q = tr.q.copy()
    off = 0.5 * hand.jerk[j] * dt ** 3
    q[k, j] += off * np.sign(0.5 * (hand.lower[j] + hand.upper[j]) - q[k, j])  # (away from
    # its stop: the closed hand's abduction may be at its margin)
    r = check_trajectory(write_traj(tmp_path / "j.csv", hand, tr.t_s, q, metadata=tr.metadata,
                                    end_info=_end_info(tr)))
    lc = _limit(r, "joint_jerk")
    assert (lc.name, lc.count, lc.limit) == ("index_mcp_abd", 2, hand.jerk[j])
    assert lc.worst == pytest.approx(3 * off / dt ** 3, rel=1e-3)
    assert [c.category for c in r.limits if not c.ok] == ["joint_jerk"]
    assert not r.ok and any("joint jerk violations" in p for p in r.problems)


def test_catch_rows_inside_a_stop_margin_fail(tmp_path, hand, fresh_catch):
    """The fresh plan's open hand with index_pip on its hard stop (0 rad, the open pose
    before the stop margins) until the closing: within the joint's range, inside its 2 deg
    margin; the check counts those rows."""
    tr = read_trajectory(str(fresh_catch))
    j = hand.index["index_pip"]
    q = tr.q.copy()
    near = q[:, j] < hand.plan_lower[j] + 1e-6  # the open hand's rows (at the margin,
    # to the file's 6 decimals)
    assert near.sum() >= 5
    q[near, j] = 0.0
    q = hand.apply_couplings(q)
    r = check_trajectory(write_traj(tmp_path / "m.csv", hand, tr.t_s, q, metadata=tr.metadata,
                                    end_info=_end_info(tr)))
    lc = _limit(r, "joint_stop_margin")
    assert lc.count == int(near.sum()) and lc.name == "index_pip" and lc.worst == 0.0
    assert _limit(r, "joint_position").ok
    assert not r.ok and any("joint stop margin violations" in p for p in r.problems)

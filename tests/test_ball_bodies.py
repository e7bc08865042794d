"""The fingers' bodies against the ball's flight before it lands (``planner.check.ballbodies``):
one rule of ``check`` and of the catch planner's self-check."""

from __future__ import annotations

import numpy as np

from planner.catch import get_planner, plan_throw, write_plan
from planner.check import check_trajectory
from planner.check.ball import ball_positions
from planner.check.ballbodies import FINE_S, finger_hit, finger_hit_problem
from planner.check.kinematics import Kinematics
from planner.hand.bodies import CAPSULE, Body, collision_bodies
from planner.planfile import read_plan
from tests.trajbuild import T_I, catch_file

R_BALL = 0.0335


def _still(Q, links):
    """Every link at the world origin, whatever the rows."""
    return {n: np.repeat(np.eye(4)[None], len(Q), axis=0) for n in links}


def test_a_ball_through_a_finger_between_two_rows_is_found():
    # a capsule along x at the origin (radius 6 mm) and a ball crossing it along z at
    # 6.95 m/s: at the rows (20 ms apart) the ball's surface is 30 mm above and below the
    # capsule (no touch at any row), between them it passes through it
    cap = Body("f_capsule", "f_link", CAPSULE, (-0.01, 0.0, 0.0), (0.01, 0.0, 0.0), 0.006,
               finger="thumb")
    t = np.array([0.0, 0.02, 0.04])
    Q = np.zeros((3, 1))
    z0 = 0.03 + R_BALL + 0.006

    def ball_at(ts):
        z = z0 - 2.0 * z0 / 0.02 * ts
        return np.stack([np.zeros_like(ts), np.zeros_like(ts), z], axis=1)

    at_rows = np.linalg.norm(ball_at(t[:2]), axis=1) - R_BALL - 0.006
    np.testing.assert_allclose(at_rows, [0.03, 0.03], atol=1e-12)  # the rows see no touch
    hit = finger_hit((cap,), _still, t, Q, 0.04, ball_at, R_BALL)
    assert hit is not None and hit.body == "f_capsule" and hit.finger == "thumb"
    assert hit.gap_m < -0.03  # through its middle
    assert abs(hit.time_s - round(hit.time_s / FINE_S) * FINE_S) < 1e-12
    text = finger_hit_problem(hit)
    assert text is not None and "thumb" in text and "f_capsule" in text
    # a ball that passes 5 mm beside it is no hit
    def beside(ts):
        return ball_at(ts) + np.array([0.0, R_BALL + 0.006 + 0.005, 0.0])

    clear = finger_hit((cap,), _still, t, Q, 0.04, beside, R_BALL)
    assert clear.gap_m > 0.004 and finger_hit_problem(clear) is None
    # the palm's and the arm's bodies are not the fingers'
    assert finger_hit((Body("palm_box", "palm", "box", (0, 0, 0), (0, 0, 0),
                            half_m=(0.1, 0.1, 0.1)),), _still, t, Q, 0.04, ball_at,
                      R_BALL) is None


def test_check_names_a_finger_body_in_the_flight(tmp_path, hand):
    # the fingers closed before the ball arrives: the body rule names the finger too
    r = check_trajectory(catch_file(tmp_path / "a.csv", hand, close_from=0.1))
    assert not r.ok
    assert any(p.startswith("fingers in the way: the ball meets the") for p in r.problems)
    # the good catch: no finger body in the flight
    r = check_trajectory(catch_file(tmp_path / "b.csv", hand, close_from=T_I - 0.12))
    assert r.ok, r.summary()


def test_planned_catch_keeps_the_thumb_out_of_the_flight(tmp_path):
    # -0.3 m / 25 deg / 3.0 m: the thumb's distal segment closing 14 ms before the ball
    # landed met it 2.6 mm deep (the replay then lost the ball): the planner's self-check
    # now applies the rule and waits with the closing
    p = plan_throw(25.0, 3.0, -0.3, planner=get_planner("default"))
    assert p.feasible, p.reasons
    path = str(tmp_path / "c.csv")
    write_plan(p, path)
    r = check_trajectory(path)
    assert r.ok, r.summary()
    plan = read_plan(path)
    meta, tr = plan.trajectory.metadata, plan.trajectory
    b = meta["ball"]
    hit = finger_hit(collision_bodies(plan.hand.spec),
                     Kinematics(plan.hand, plan.T_world_root).link_poses, tr.t_s, tr.q,
                     meta["intercept_t"],
                     lambda ts: ball_positions(b["p0"], b["v0"], b["drag"], ts), b["radius"])
    assert hit is not None and hit.gap_m >= 0.0

"""planner.catch.plan.closing.close_start: the earliest clear start among its candidates,
judged a few at a time, is the one judging them all at once finds."""

from __future__ import annotations

import numpy as np
import pytest

from planner.catch import grasp as gq
from planner.catch.flight.path import get_ball, predict_throw
from planner.catch.live.session import CatchSession
from planner.catch.plan.api import get_planner
from planner.catch.plan.closing import (
    BODY_CLEAR_M,
    N_CAND,
    TIP_GAP_M,
    TOUCH_CLEAR_M,
    body_gaps_m,
    close_start,
    make_closing,
)
from planner.check.criteria import GRASP_MIN_TIPS, GRASP_TOL_M

BALL = get_ball("tennis")


def _all_at_once(hand, flight, C, q_open, closing, t_i, ready, stop_t, r):
    """Every candidate judged together (the definition: no point of a finger's body
    within its radius + ``TOUCH_CLEAR_M`` of the arriving ball's surface)."""
    want = max(ready, t_i + stop_t - closing.u_grasp * closing.duration_s)
    if want >= t_i:
        return want
    speed = float(np.linalg.norm(flight.velocity(t_i)))
    tt = np.arange(max(want, t_i - (closing.reach_m + r) / speed), t_i, 0.001)
    Tinv = np.linalg.inv(hand.palm_pose(q_open))
    b_pc = (flight.position(tt) - C) @ Tinv[:3, :3].T + Tinv[:3, 3]
    cands = np.linspace(want, t_i, N_CAND)
    n_tab = len(closing.u)
    U = np.clip((tt[None, :] - cands[:, None]) / closing.duration_s, 0.0, 1.0)
    k = np.minimum(np.ceil(U * (n_tab - 1)).astype(int), n_tab - 1)
    K, n_f, P, _ = closing.bodies_pc.shape
    pts = closing.bodies_pc.reshape(K, n_f * P, 3)
    d = np.linalg.norm(pts[k] - b_pc[None, :, None, :], axis=-1)
    near = r + TOUCH_CLEAR_M + closing.bodies_r_m.reshape(-1)
    good = np.flatnonzero(~np.any(d < near, axis=(1, 2)))
    return float(cands[good[0]]) if good.size else float(t_i)


@pytest.mark.parametrize("angle,dist,height", [(30.0, 1.5, 0.0), (52.0, 2.3, -0.2),
                                               (22.0, 1.1, 0.15), (45.0, 1.8, 0.1)])
def test_close_start_is_the_earliest_clear_candidate(angle, dist, height):
    pl = get_planner("default")
    cl = pl.closing(BALL.radius_m)
    fl = predict_throw(angle, dist, height, BALL, drag=True)
    s = CatchSession(dist, height, ball=BALL, drag=True, planner=pl)
    rng = np.random.default_rng(2)
    n = 0
    for k in range(1, 40):
        s.observe(k / 100, fl.position(k / 100) + rng.normal(0.0, 0.005, 3))
        if s.pose is None:
            continue
        p = s.pose
        for ready in (s.motion.fingers_open_s if s.motion.moving else k / 100 + 0.2,
                      p.t_i - 0.3, p.t_i - 0.05):
            args = (pl.hand, s.flight, s.C, p.q_open, cl, p.t_i, ready, gq.stop_time(p.v_i, pl.hand.pad_give_m),
                    BALL.radius_m)
            assert close_start(*args) == _all_at_once(*args)
            n += 1
        if s.done:
            break
    assert n > 20


def test_closed_fingers_bodies_clear_of_the_ball():
    """The closed pose keeps every finger's body (the replay's capsules and pad spheres)
    ``BODY_CLEAR_M`` outside the ball on the palm and still grasps it (thumb + 2 tips within
    radius + ``GRASP_TOL_M``); the fingertips' closing (``bodies=False``, the fallback)
    has its tips ``TIP_GAP_M`` out (the index's 4.4 mm further: its abduction and MCP
    flexion at their planning limits, 2 deg inside the hard stops; 1.9 mm further with the
    hard stops as its limits) but the middle and ring pad spheres inside the ball."""
    pl = get_planner("default")
    r = BALL.radius_m
    centre = pl.wrist.pc0 + r * pl.wrist.n0
    cl = pl.closing(r)
    gaps = body_gaps_m(pl.hand, cl.q_closed, centre, r)
    assert np.all(gaps >= BODY_CLEAR_M - 1e-5), gaps
    assert cl.u_grasp is not None and "thumb" in cl.grasp_fingers
    assert np.sum(cl.tip_dist_m <= r + GRASP_TOL_M) >= GRASP_MIN_TIPS
    tips_only = make_closing(pl.hand, pl.ik, pl.joints, pl.wrist, r, bodies=False)
    assert np.allclose(tips_only.tip_dist_m[[0, 2, 3]], r + TIP_GAP_M, atol=0.002)
    assert r + TIP_GAP_M < tips_only.tip_dist_m[1] < r + TIP_GAP_M + 0.005
    i = [pl.hand.index[n] for n in ("index_mcp_abd", "index_mcp_flex")]
    assert np.allclose(tips_only.q_closed[i], pl.hand.upper[i])  # (the planner's limits)
    fingers = pl.hand.fingers
    inside = body_gaps_m(pl.hand, tips_only.q_closed, centre, r)
    assert inside[fingers.index("middle")] < -0.003 and inside[fingers.index("ring")] < -0.003


def test_body_table_is_the_per_configuration_one():
    """The closing's body table, every configuration at once (``FrameChain``), holds the
    points ``FingerBodies.points`` (Pinocchio, one configuration at a time) gives along
    the closing move, in the palm frame, to rounding (measured: within 1.9e-16 m)."""
    from planner.catch.plan.arm import open_from, zero_pose
    from planner.play.fingerbody import FingerBodies
    from planner.trajectory import min_jerk

    pl = get_planner("default")
    h, cl = pl.hand, pl.closing(BALL.radius_m)
    q0 = zero_pose(h)
    q_open = open_from(h, pl.joints, q0, cl.q_closed)
    s = min_jerk(cl.u)[:, None]
    Q = h.apply_couplings(q_open + (cl.q_closed - q_open) * s)
    Tinv = np.linalg.inv(h.palm_pose(q0))
    fb = FingerBodies(h)
    worst = 0.0
    for k in range(len(Q)):
        g = 0
        for f in h.fingers:
            p, rad = fb.points(Q[k], f)
            p = p @ Tinv[:3, :3].T + Tinv[:3, 3]
            a = 0
            for n in fb.shapes[f].n_points:
                worst = max(worst, float(np.abs(cl.bodies_pc[k, g, :n] - p[a:a + n]).max()))
                assert np.all(cl.bodies_pc[k, g, n:] == cl.bodies_pc[k, g, :1])
                assert np.all(cl.bodies_r_m[g, :n] == rad[a:a + n])
                a, g = a + n, g + 1
        assert g == cl.bodies_pc.shape[1]
    assert worst <= 1e-15


@pytest.mark.parametrize("name", ["agh", "default"])
def test_the_open_hand_is_straight_within_the_margins(name):
    """The open hand (``open_from``) keeps every joint within the planner's limits (the
    stop margins inside the hard stops) and each finger's flexions sum to 0 where its first
    flexion joint's range allows: the AGH's end joints, held 2 deg off their stop at
    straight, lean back by their base joints (-2 deg), so a finger points along the palm
    normal as with every flexion at 0 (leaning 2 deg in, its 140 mm end element put the
    tip 4.9 mm into the ball's way: 30 deg / 1.5 m refused, fingers in the way); the
    default hand's MCPs take back the PIP's and DIP's margins. The thumb's first flexion
    joint (CMC) is itself at its margin: it stays there."""
    from planner.catch.plan.arm import open_from, zero_pose

    pl = get_planner(name)
    h = pl.hand
    q0 = zero_pose(h)
    q = open_from(h, pl.joints, q0, pl.closing(BALL.radius_m).q_closed)
    assert np.all(q >= h.lower - 1e-12) and np.all(q <= h.upper + 1e-12)
    flexion = {int(i) for i in pl.joints.flexion_idx}
    for f in h.fingers:
        chain = [h.index[n] for n in h.spec.joints_of(f) if h.index[n] in flexion]
        if f == "thumb" and name == "default":
            assert q[chain[0]] == pytest.approx(h.lower[chain[0]], abs=1e-12)
            continue
        assert q[chain[1:]].sum() > 0.01  # (the margins hold the later joints flexed)
        assert q[chain].sum() == pytest.approx(0.0, abs=1e-12)

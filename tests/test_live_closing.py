"""The live closing's start judged in the frame of the palm on its stopping motion
(``closing.close_start``'s ``stop``), and the physics replay's ball on its flight
(``simulate.replay.launch_velocity``). No wall-clock assertions."""

from __future__ import annotations

import json

import numpy as np
import pytest

from planner.catch import CatchSession, get_planner, plan_throw
from planner.catch.flight.camera import observe_throw
from planner.catch.flight.path import get_ball, predict_throw
from planner.catch.plan import closing as cl
from planner.check import check_trajectory
from planner.trajfile import parse_trajectory


def test_the_moving_palm_between_its_knots(pl):
    """The palm's poses every ``PALM_KNOT_S``, interpolated: the ball in its frame within
    0.5 mm of every instant's own pose, on a planned catch's stopping motion."""
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    stop = p.forces.soft
    assert stop is not None and np.any(stop.qd)
    t_i = p.intercept.t_s
    q_i = np.array([np.interp(t_i, p.rows.t, p.rows.q[:, j]) for j in range(p.rows.q.shape[1])])
    tt = np.arange(t_i - 0.08, t_i, 0.001)
    got = cl.ball_in_palm(pl.hand, p.flight, p.catch_point, q_i, tt, t_i, stop)
    n = len(q_i)
    Q = q_i + stop.offset(tt, n) - stop.offset(np.array([t_i]), n)
    pos = p.flight.position(tt)
    exact = np.array([(pos[k] - (p.catch_point + T[:3, 3])) @ T[:3, :3]
                      for k, T in enumerate(pl.hand.palm_pose(q) for q in Q)])
    assert np.abs(got - exact).max() < 5e-4
    rest = cl.ball_in_palm(pl.hand, p.flight, p.catch_point, q_i, tt, t_i, None)
    assert np.abs(rest - exact).max() > 2e-3  # (the palm does move: the test can fail)


def test_the_moving_palm_is_np_interp_of_its_knots(pl):
    """``ball_in_palm`` on a stopping motion: the palm's pose at its knots (one FK each)
    and ``np.interp`` of each of its 12 elements between them, element by element, bit for
    bit (the knots' times end at the last sample, which takes the last knot's pose)."""
    p = plan_throw(40.0, 2.0, 0.1, planner=pl)
    stop = p.forces.soft
    assert stop is not None and np.any(stop.qd)
    t_i = p.intercept.t_s
    q_i = np.array([np.interp(t_i, p.rows.t, p.rows.q[:, j]) for j in range(p.rows.q.shape[1])])
    n = len(q_i)
    for span_s in (0.0, 0.004, 0.0305, 0.08):
        tt = np.arange(t_i - span_s - 0.001, t_i, 0.001)
        knots = np.linspace(tt[0], tt[-1],
                            max(2, int(np.ceil((tt[-1] - tt[0]) / cl.PALM_KNOT_S)) + 1))
        Q = q_i + stop.offset(knots, n) - stop.offset(np.array([t_i]), n)
        K = np.array([pl.hand.palm_pose(q) for q in Q])
        T = np.stack([np.interp(tt, knots, K[:, i, j]) for i in range(3) for j in range(4)],
                     axis=1).reshape(len(tt), 3, 4)
        want = np.einsum("ti,tij->tj", p.flight.position(tt) - (p.catch_point + T[:, :, 3]),
                         T[:, :, :3])
        got = cl.ball_in_palm(pl.hand, p.flight, p.catch_point, q_i, tt, t_i, stop)
        assert np.array_equal(got, want)


def test_the_live_thumb_waits_for_the_ball(pl):
    """bench_live's throw 6 at 100 Hz / 5 mm (44.3 deg, 2.50 m, -0.11 m; the noise of its
    configuration's seed): with the closing timed on the palm at rest, the thumb's body met
    the true flight 0.7 mm deep 16 ms before the palm (and the replay dropped the ball);
    timed on the moving palm, no finger meets it and the check confirms the catch against
    the true ball."""
    rng = np.random.default_rng(0)
    throws = np.column_stack([rng.uniform(20, 60, 20), rng.uniform(1.0, 2.5, 20),
                              rng.uniform(-0.2, 0.2, 20)])
    ball = get_ball("tennis")
    noise = np.random.default_rng([0, 100, 50])
    for i, (ang, dist, h) in enumerate(throws[:7]):
        fl = predict_throw(ang, dist, h, ball, drag=True)
        s = observe_throw(CatchSession(dist, h, ball=ball, drag=True, rate_hz=100.0,
                                       planner=pl), fl, 0.005, 100.0, noise, until_s=3.0)
    head, _ = s.text.rstrip("\n").rsplit("\n", 1)
    end = dict(parse_trajectory(s.text).end, ball=fl.to_metadata())
    rep = check_trajectory(parse_trajectory(head + "\n# " + json.dumps(end) + "\n"))
    assert not any(x.startswith("fingers in the way") for x in rep.problems), rep.problems
    assert rep.ok and s.outcome == "held"


def test_the_replays_ball_flies_its_flight(tmp_path):
    """MuJoCo's semi-implicit step flies a ball started at ``v0`` 0.5 g dt t below its
    flight (3.5 mm at 0.7 s); started half a step back, the replay's ball (its record one
    step behind: MuJoCo's body positions are the step's start) follows the check's flight
    within 0.2 mm up to the intercept."""
    pytest.importorskip("mujoco")
    from planner.catch import write_plan
    from planner.check.ball import ball_params, ball_positions
    from planner.simulate import run_replay
    from planner.simulate.scene import TIMESTEP_S

    p = plan_throw(30.0, 3.0, 0.0, planner=get_planner("default"))
    path = tmp_path / "c.csv"
    write_plan(p, str(path))
    rp = run_replay(str(path))
    b = ball_params(rp.trajectory.metadata, str(path))
    t = rp.record.t_s
    before = (t > 0) & (t < p.intercept.t_s - 0.02)
    want = ball_positions(b["p0"], b["v0"], b["drag"], t[before] - TIMESTEP_S)
    assert np.abs(rp.record.ball_m[before] - want).max() < 2e-4

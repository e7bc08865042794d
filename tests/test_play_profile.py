"""planner.play.profile: time-optimal straight joint-space moves."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.play.profile import LIMIT_FRACTION, move_time_s, move_times_s, path_caps, straight_move

V = np.array([20.0, 10.5, 2.78])
A = np.array([500.0, 500.0, 40.0])


@pytest.mark.parametrize("dq", [[0.44, 0.0, 0.0], [0.02, -0.01, 0.0], [1.5, 0.2, 0.0],
                                [0.0, 0.0, 0.5], [0.3, -0.3, 0.01]])
def test_ends_limits_and_optimality(dq):
    qa = np.array([0.1, -0.2, 0.3])
    qb = qa + np.array(dq)
    m = straight_move(qa, qb, V, A)
    np.testing.assert_allclose(m.at(0.0)[0], qa, atol=1e-12)
    np.testing.assert_allclose(m.at(m.duration_s)[0], qb, atol=1e-12)
    t = np.linspace(0.0, m.duration_s, 4001)
    q = m.at(t)
    dt = t[1] - t[0]
    vel = np.diff(q, axis=0) / dt
    acc = np.diff(vel, axis=0) / dt
    assert np.all(np.abs(vel) <= V * LIMIT_FRACTION * (1 + 1e-9))
    assert np.all(np.abs(acc) <= A * LIMIT_FRACTION * (1 + 1e-3) + 1e-6)
    # the binding joint alone: its own time-optimal move takes exactly as long
    d = np.abs(np.array(dq))
    own = [move_time_s(LIMIT_FRACTION * v / x, LIMIT_FRACTION * a / x)
           for x, v, a in zip(d, V, A) if x > 0]
    assert m.duration_s == pytest.approx(max(own), rel=1e-12)
    # the path stays on the straight line
    s = (q - qa) @ (qb - qa) / ((qb - qa) @ (qb - qa))
    np.testing.assert_allclose(q, qa + s[:, None] * (qb - qa), atol=1e-12)


def test_triangle_and_trapezoid_times():
    # 0.44 rad at 500 rad/s^2, 20 rad/s: triangle, 2 sqrt(d / a)
    m = straight_move([0.0], [0.44], [20.0], [500.0])
    assert m.duration_s == pytest.approx(2 * math.sqrt(0.44 / (500 * LIMIT_FRACTION)))
    # 0.5 m of rail at 2.78 m/s and 40 m/s^2: reaches the cap, d / v + v / a
    m = straight_move([0.0], [0.5], [2.78], [40.0])
    v, a = 2.78 * LIMIT_FRACTION, 40.0 * LIMIT_FRACTION
    assert m.duration_s == pytest.approx(0.5 / v + v / a)
    # min-jerk at the same peak acceleration takes 1.2 times as long
    t_mj = math.sqrt(10 / math.sqrt(3) * 0.44 / (500 * LIMIT_FRACTION))
    assert t_mj / straight_move([0.0], [0.44], [20.0], [500.0]).duration_s == \
        pytest.approx(math.sqrt(10 / math.sqrt(3)) / 2)


def test_time_at_s_inverts_s():
    for d in (0.01, 0.44, 2.0):
        m = straight_move([0.0], [d], [20.0], [500.0])
        for s in (0.0, 0.05, 0.3, 0.5, 0.77, 0.99, 1.0):
            assert float(m.s(m.time_at_s(s))) == pytest.approx(s, abs=1e-12)


def test_zero_move():
    m = straight_move([0.2, 0.3], [0.2, 0.3], [1.0, 1.0], [1.0, 1.0])
    assert m.duration_s == 0.0
    np.testing.assert_allclose(m.at([0.0, 1.0]), [[0.2, 0.3], [0.2, 0.3]])


def test_caps_are_those_of_the_joints_vectorised():
    """The tightest joint's speed and acceleration caps (worked out joint by joint in
    floats) are bit for bit the vectorised formula's, over random moves of 1-20 joints
    with some joints still."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        n = int(rng.integers(1, 21))
        qa = rng.uniform(-1, 1, n)
        dq = rng.uniform(-1, 1, n) * (rng.random(n) < 0.7)
        v, a = rng.uniform(0.5, 30, n), rng.uniform(5, 800, n)
        m = straight_move(qa, qa + dq, v, a)
        d = np.abs((qa + dq) - qa)
        moving = d > 0
        if not moving.any():
            assert m.duration_s == 0.0
            continue
        assert m.v == float(np.min(LIMIT_FRACTION * v[moving] / d[moving]))
        assert m.a == float(np.min(LIMIT_FRACTION * a[moving] / d[moving]))
        assert m.duration_s == move_time_s(m.v, m.a)


def test_move_times_are_straight_moves_durations_bit_for_bit():
    rng = np.random.default_rng(8)
    v, a = rng.uniform(1.0, 8.0, 4), rng.uniform(20.0, 300.0, 4)
    dq = rng.normal(0.0, 0.3, (500, 4)) * (rng.random((500, 4)) < 0.8)  # (joints not moving)
    dq[0] = 0.0  # (a move of zero length)
    times = move_times_s(dq, v, a)
    assert times[0] == 0.0
    assert times.tolist() == [straight_move(np.zeros(4), d, v, a).duration_s for d in dq]


def test_path_caps_is_the_tightest_joints_min():
    """``path_caps`` (its ``min`` and ``abs`` spelt out) is, bit for bit, the tightest
    joint's caps by ``min`` over the moving joints, None when none moves."""
    rng = np.random.default_rng(3)
    v, a = [2.0, 3.5, 1.25, 4.0], [40.0, 25.0, 60.0, 33.0]
    for _ in range(2000):
        dq = [float(x) for x in rng.choice([0.0, -0.3, 1e-300], 4) * rng.random(4)]
        dq[rng.integers(4)] = float(rng.normal()) if rng.random() < 0.9 else 0.0
        moving = [(abs(d), vj, aj) for d, vj, aj in zip(dq, v, a) if d != 0.0]
        want = None if not moving else (
            min(LIMIT_FRACTION * vj / d for d, vj, _ in moving),
            min(LIMIT_FRACTION * aj / d for d, _, aj in moving))
        assert path_caps(dq, v, a) == want

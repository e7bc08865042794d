"""planner.play.profile: time-optimal jerk-limited straight joint-space moves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import linprog

from planner.play.profile import (
    LIMIT_FRACTION,
    Move,
    bounce_move,
    move_time_s,
    move_times_s,
    path_caps,
    path_s,
    phases,
    straight_move,
)

V = np.array([20.0, 10.5, 2.78])
A = np.array([500.0, 500.0, 40.0])
J = np.array([17182.0, 8333.0, 2667.0])


def _differences(q: np.ndarray, dt: float):
    vel = np.diff(q, axis=0) / dt
    acc = np.diff(vel, axis=0) / dt
    return vel, acc, np.diff(acc, axis=0) / dt


@pytest.mark.parametrize("dq", [[0.44, 0.0, 0.0], [0.02, -0.01, 0.0], [1.5, 0.2, 0.0],
                                [0.0, 0.0, 0.5], [0.3, -0.3, 0.01], [4.0, 0.0, 0.0],
                                [1e-4, 0.0, 0.0]])
def test_ends_limits_and_optimality(dq):
    """Sampled finely, every joint's speed, acceleration and jerk (finite differences)
    stay within LIMIT_FRACTION of its limits, and the binding joint's own move takes
    exactly as long."""
    qa = np.array([0.1, -0.2, 0.3])
    qb = qa + np.array(dq)
    m = straight_move(qa, qb, V, A, J)
    np.testing.assert_allclose(m.at(0.0)[0], qa, atol=1e-12)
    np.testing.assert_allclose(m.at(m.duration_s)[0], qb, atol=1e-12)
    t = np.linspace(0.0, m.duration_s, 1201)  # (finer: rounding noise in the jerk)
    q = m.at(t)
    vel, acc, jerk = _differences(q, t[1] - t[0])
    assert np.all(np.abs(vel) <= V * LIMIT_FRACTION * (1 + 1e-9))
    assert np.all(np.abs(acc) <= A * LIMIT_FRACTION * (1 + 1e-6) + 1e-6)
    assert np.all(np.abs(jerk) <= J * LIMIT_FRACTION * (1 + 1e-3) + 1e-3)
    # the binding joint reaches a cap: the profile is not slower than it must be
    d = np.abs(np.array(dq))
    own = [move_time_s(*(LIMIT_FRACTION * x / dj for x in (v, a, j)))
           for dj, v, a, j in zip(d, V, A, J) if dj > 0]
    assert m.duration_s == pytest.approx(max(own), rel=1e-12)
    # rest to rest: speed and acceleration zero at both ends (moves join smoothly)
    for s_end in (0.0, m.duration_s):
        tt = np.array([s_end - 1e-7, s_end, s_end + 1e-7])
        assert np.all(np.abs(np.diff(m.at(tt), axis=0)) < 1e-12)
    # the path stays on the straight line
    s = (q - qa) @ (qb - qa) / ((qb - qa) @ (qb - qa))
    np.testing.assert_allclose(q, qa + s[:, None] * (qb - qa), atol=1e-12)


def _lp_time(v: float, a: float, j: float, n: int = 120, stop: bool = False) -> float:
    """A brute-force bound on the shortest rest-to-rest unit move (``stop``: from rest to
    a stop at distance 1 with any acceleration there, a bounce's half): piecewise-constant
    jerk on n equal steps (a linear programme: exact integration of each step), bisected
    on the duration until the speed, acceleration and jerk caps admit the distance.
    Every such profile is a feasible continuous one, so this is never below the optimum
    and tends to it as the steps shrink."""

    def feasible(T: float) -> bool:
        h = T / n
        # state after step k: a_k = h sum j, v_k, s_k by exact integration of the cubic
        L = np.tril(np.ones((n, n)))
        Acc = h * L
        Vel = np.zeros((n, n))
        Pos = np.zeros((n, n))
        for k in range(n):  # jerk of step i's contribution at the end of step k (i <= k)
            for i in range(k + 1):
                tau = (k - i) * h  # time from the end of step i to the end of step k
                Vel[k, i] = h * h / 2 + h * tau
                Pos[k, i] = h ** 3 / 6 + h * h / 2 * tau + h * tau * tau / 2
        A_ub = np.vstack([Acc, -Acc, Vel, -Vel])
        b_ub = np.r_[np.full(n, a), np.full(n, a), np.full(n, v), np.full(n, v)]
        A_eq = np.vstack([Acc[-1], Vel[-1], Pos[-1]][stop:])
        res = linprog(np.zeros(n), A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=[0.0, 0.0, 1.0][stop:],
                      bounds=[(-j, j)] * n, method="highs")
        return res.status == 0

    lo, hi = 0.0, 1.0
    while not feasible(hi):
        lo, hi = hi, 2 * hi
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if feasible(mid) else (mid, hi)
    return hi


@pytest.mark.parametrize("caps", [(45.5, 1136.0, 39050.0),  # 0.44 rad of a finger joint
                                  (5.56, 80.0, 5334.0),  # 0.5 m of the rail: cruises
                                  (0.5, 1e3, 1e5),  # speed-bound, short jerk ramps
                                  (5.0, 3.0, 1e5),  # acceleration-bound
                                  (1e3, 1e3, 1e2)])  # jerk-bound throughout
def test_duration_against_brute_force(caps):
    """The double S's duration is the shortest: within 2 % (the steps' coarseness) below
    a brute-force linear programme's, never above it."""
    T = move_time_s(*caps)
    T_lp = _lp_time(*caps)
    assert T <= T_lp * (1 + 1e-6)
    assert T >= T_lp * 0.98


@pytest.mark.parametrize("caps", [(45.5, 1136.0, 39050.0), (5.56, 80.0, 5334.0),
                                  (0.5, 1e3, 1e5), (5.0, 3.0, 1e5), (1e3, 1e3, 1e2)])
def test_unit_profile_reaches_its_binding_caps(caps):
    """Finite differences of the unit profile: within each cap, and at least one cap
    met (to 0.5 %: the samples' spacing)."""
    T, ta, tj = phases(*caps)
    t = np.linspace(0.0, T, 20001)
    s = path_s(t, T, ta, tj)
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0, abs=1e-15)
    assert np.all(np.diff(s) >= 0.0)
    vel, acc, jerk = _differences(s, t[1] - t[0])
    peaks = np.array([np.max(np.abs(x)) for x in (vel, acc, jerk)]) / np.array(caps)
    assert np.all(peaks <= 1 + 1e-3)
    assert np.max(peaks) >= 0.995


def test_jerk_limited_times():
    # 0.44 rad of a finger joint (500 rad/s^2, 17182 rad/s^3): too short to reach the
    # acceleration cap, jerk +j, -j, -j, +j over four equal ramps: 2 j' tj^3 = 1
    j = 17182 * LIMIT_FRACTION / 0.44
    m = straight_move([0.0], [0.44], [20.0], [500.0], [17182.0])
    assert m.duration_s == pytest.approx(4 * (0.5 / j) ** (1 / 3), rel=1e-12)
    assert m.duration_s == 4 * m.tj_s == 2 * m.ta_s
    # 1 rad, the speed cap out of reach: the acceleration cap held between ramps of a / j,
    # T = tj + sqrt(tj^2 + 4 / a') with unit caps a' = a / d, j' = j / d
    a, j = 500 * LIMIT_FRACTION, 17182 * LIMIT_FRACTION
    m = straight_move([0.0], [1.0], [100.0], [500.0], [17182.0])
    tj = a / j
    assert m.duration_s == pytest.approx(tj + math.sqrt(tj * tj + 4 / a), rel=1e-12)
    # the bang-bang (trapezoid) move took 2 sqrt(d / a); jerk costs a / j to 2 a / j more
    t_bang = 2 * math.sqrt(1 / a)
    assert t_bang + tj < m.duration_s < t_bang + 2 * tj
    # 0.5 m of rail at 2.78 m/s, 40 m/s^2, 2667 m/s^3: cruises, d / v + v / a + a / j
    v, a, j = (x * LIMIT_FRACTION / 0.5 for x in (2.78, 40.0, 2667.0))
    m = straight_move([0.0], [0.5], [2.78], [40.0], [2667.0])
    assert m.duration_s == pytest.approx(1 / v + v / a + a / j, rel=1e-12)


def test_time_at_s_inverts_s():
    for d in (1e-4, 0.01, 0.44, 2.0, 10.0):
        m = straight_move([0.0], [d], [20.0], [500.0], [17182.0])
        for s in (0.0, 1e-6, 0.05, 0.3, 0.5, 0.77, 0.99, 1.0):
            t = m.time_at_s(s)
            assert float(m.s(t)) >= s - 1e-15
            assert float(m.s(t)) == pytest.approx(s, abs=1e-12)
            assert t == 0.0 or float(m.s(np.nextafter(t, 0.0))) <= s + 1e-15


def test_zero_move():
    m = straight_move([0.2, 0.3], [0.2, 0.3], [1.0, 1.0], [1.0, 1.0], [1.0, 1.0])
    assert m.duration_s == 0.0
    np.testing.assert_allclose(m.at([0.0, 1.0]), [[0.2, 0.3], [0.2, 0.3]])


def test_path_s_vectorised_over_moves():
    """One time per move (``planner.play.motion`` samples a track's segments at once):
    the same floats as each move's own ``s``."""
    rng = np.random.default_rng(5)
    moves = [straight_move([0.0], [d], [20.0], [500.0], [17182.0])
             for d in rng.uniform(1e-3, 3.0, 50)]
    t = np.array([rng.uniform(-0.01, m.duration_s + 0.01) for m in moves])
    T, ta, tj = (np.array([getattr(m, k) for m in moves]) for k in ("duration_s", "ta_s", "tj_s"))
    got = path_s(t, T, ta, tj)
    assert got.tolist() == [float(m.s(x)) for m, x in zip(moves, t)]
    assert float(path_s(np.array(0.3), 0.0, 0.0, 0.0)) == 1.0  # (a zero move: at its end)
    assert isinstance(moves[0], Move)


def test_caps_are_those_of_the_joints_vectorised():
    """The tightest joint's speed, acceleration and jerk caps (worked out joint by joint
    in floats) are bit for bit the vectorised formula's, over random moves of 1-20
    joints with some joints still; the duration is ``move_time_s`` of them."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        n = int(rng.integers(1, 21))
        qa = rng.uniform(-1, 1, n)
        dq = rng.uniform(-1, 1, n) * (rng.random(n) < 0.7)
        v, a, j = rng.uniform(0.5, 30, n), rng.uniform(5, 800, n), rng.uniform(1e3, 5e4, n)
        m = straight_move(qa, qa + dq, v, a, j)
        d = np.abs((qa + dq) - qa)
        moving = d > 0
        if not moving.any():
            assert m.duration_s == 0.0
            continue
        caps = tuple(float(np.min(LIMIT_FRACTION * x[moving] / d[moving])) for x in (v, a, j))
        assert path_caps((qa + dq - qa).tolist(), v.tolist(), a.tolist(), j.tolist()) == caps
        assert (m.duration_s, m.ta_s, m.tj_s) == phases(*caps)
        assert m.duration_s == move_time_s(*caps)


def test_move_times_are_straight_moves_durations_bit_for_bit():
    rng = np.random.default_rng(8)
    v, a, j = rng.uniform(1.0, 8.0, 4), rng.uniform(20.0, 300.0, 4), rng.uniform(1e3, 3e4, 4)
    dq = rng.normal(0.0, 0.3, (500, 4)) * (rng.random((500, 4)) < 0.8)  # (joints not moving)
    dq[0] = 0.0  # (a move of zero length)
    dq[1] = [1e-6, 0.0, 0.0, 0.0]  # (one too short to reach the acceleration cap)
    times = move_times_s(dq, v, a, j)
    assert times[0] == 0.0
    assert times.tolist() == [straight_move(np.zeros(4), d, v, a, j).duration_s for d in dq]


def test_path_caps_is_the_tightest_joints_min():
    """``path_caps`` (its ``min`` and ``abs`` spelt out) is, bit for bit, the tightest
    joint's caps by ``min`` over the moving joints, None when none moves."""
    rng = np.random.default_rng(3)
    v, a, j = [2.0, 3.5, 1.25, 4.0], [40.0, 25.0, 60.0, 33.0], [2e3, 9e3, 4e3, 5e3]
    for _ in range(2000):
        dq = [float(x) for x in rng.choice([0.0, -0.3, 1e-300], 4) * rng.random(4)]
        dq[rng.integers(4)] = float(rng.normal()) if rng.random() < 0.9 else 0.0
        moving = [(abs(d), vj, aj, jj) for d, vj, aj, jj in zip(dq, v, a, j) if d != 0.0]
        want = None if not moving else tuple(
            min(LIMIT_FRACTION * lim[k] / d for d, *lim in moving) for k in range(3))
        assert path_caps(dq, v, a, j) == want


@pytest.mark.parametrize("dq", [[0.02, -0.01, 0.0], [0.44, 0.0, 0.0], [0.0, 0.0, 0.5],
                                [4.0, 0.0, 0.0], [1e-4, 0.0, 0.0]])
def test_a_bounce_turns_within_the_caps_and_comes_back(dq):
    """A bounce leaves from rest, turns at ``q_a + dq`` halfway, is back at rest at its
    start at its end; sampled finely, every joint's speed, acceleration and jerk stay
    within LIMIT_FRACTION of its limits, and the binding one reaches its cap."""
    qa = np.array([0.1, -0.2, 0.3])
    b = bounce_move(qa, qa + np.array(dq), V, A, J)
    assert b.back and np.array_equal(b.q_end, qa)
    np.testing.assert_allclose(b.at(0.0)[0], qa, atol=1e-15)
    np.testing.assert_allclose(b.at(b.duration_s)[0], qa, atol=1e-15)
    np.testing.assert_allclose(b.at(0.5 * b.duration_s)[0], qa + np.array(dq), atol=1e-15)
    t = np.linspace(0.0, b.duration_s, 2401)
    vel, acc, jerk = _differences(b.at(t), t[1] - t[0])
    d = np.abs(np.array(dq))
    ratios = [np.max(np.abs(x), axis=0) / (lim * LIMIT_FRACTION)
              for x, lim in ((vel, V), (acc, A), (jerk, J))]
    for r in ratios:
        assert np.all(r[d > 0] <= 1.0 + 2e-3)
    assert max(float(np.max(r[d > 0])) for r in ratios) > 0.98  # (a cap reached)
    for s_end in (0.0, b.duration_s):  # (rest at both ends)
        tt = np.array([s_end - 1e-7, s_end, s_end + 1e-7])
        assert np.all(np.abs(np.diff(b.at(tt), axis=0)) < 1e-12)
    # its key crossings: ``time_at_s`` on the way out, the same point as long before the end
    for s in (0.1, 0.5, 0.9):
        t_up = b.time_at_s(s)
        assert float(b.s(t_up)) == pytest.approx(s, abs=1e-12)
        assert float(b.s(b.duration_s - t_up)) == pytest.approx(s, abs=1e-12)


def _pure_jerk_bounce_s(v: float, a: float, j: float) -> float:
    """The duration of the bounce before its braking was held at the cap: the jerk-only
    shape (jerk +1 for 1 ramp, -1 for 1 + sqrt 2, mirrored; its peak speed 1 / (P r), its
    acceleration sqrt 2 / (P r^2) at the turn, its jerk 1 / (P r^3), P its half's length
    in ramps) time-scaled until all three are within the caps."""
    P = 1.0 / 6.0 + (1.0 + math.sqrt(2.0)) / 2.0 + (3.0 + 2.0 * math.sqrt(2.0)) / 2.0 \
        - (7.0 + 5.0 * math.sqrt(2.0)) / 6.0
    ramp = max(1.0 / (P * v), math.sqrt(math.sqrt(2.0) / (P * a)), (1.0 / (P * j)) ** (1 / 3))
    return 2.0 * (2.0 + math.sqrt(2.0)) * ramp


@pytest.mark.parametrize("caps, shorter", [
    ((45.5, 1136.0, 39050.0), 0.06),  # 0.44 rad of a finger joint: acceleration-bound
    ((40.0, 600.0, 60000.0), 0.25),  # acceleration-bound, long jerk-free braking
    ((5.56, 80.0, 5334.0), 0.20),  # 0.5 m of the rail: cruises
    ((5.0, 3.0, 1e5), 0.30),  # acceleration-bound throughout
    ((1e3, 1e3, 1e2), 0.0)])  # jerk-bound throughout: the same shape
def test_a_bounce_is_time_optimal_and_no_longer_than_the_pure_jerk_one(caps, shorter):
    """The bounce's half is the shortest move from rest to a stop at the turn: within 2 %
    (the steps' coarseness) below a brute-force linear programme's, never above it; the
    whole is never longer than the jerk-only shape time-scaled into the same caps, and
    shorter by at least ``shorter`` of it where the acceleration or speed cap binds
    (measured: 0.063, 0.265, 0.211, 0.313; 0 where only the jerk does)."""
    v, a, j = caps
    b = bounce_move(np.zeros(1), np.ones(1), [v / LIMIT_FRACTION], [a / LIMIT_FRACTION],
                    [j / LIMIT_FRACTION])
    half = _lp_time(v, a, j, stop=True)
    assert b.duration_s <= 2.0 * half * (1 + 1e-6)
    assert b.duration_s >= 2.0 * half * 0.98
    old = _pure_jerk_bounce_s(v, a, j)
    assert b.duration_s <= old * (1 + 1e-12)
    assert b.duration_s <= old * (1.0 - shorter) * (1 + 1e-9)
    assert b.peak_speed <= v * (1 + 1e-9) and b.peak_acceleration <= a * (1 + 1e-9)
    assert b.jerk <= j * (1 + 1e-9)

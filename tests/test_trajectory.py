"""Min-jerk phases and their sampler (planner/trajectory.py, the catch planner's motion)."""

import numpy as np
import pytest

from planner.trajectory import (
    LIMIT_MARGIN,
    Phase,
    jerk_duration,
    min_jerk,
    min_jerk_rates,
    phase_duration,
    sample,
)


def _ph(joints, n=4, T=0.1):
    d = np.zeros(n)
    d[list(joints)] = 1.0
    return Phase(d, T)


def test_min_jerk_ends_and_duration_limits():
    assert min_jerk(np.array([0.0, 0.5, 1.0])) == pytest.approx([0.0, 0.5, 1.0])
    dq = np.array([0.5, 0.0])
    T = phase_duration(dq, np.array([2.0, 1.0]), np.array([100.0, 1.0]))
    u = np.linspace(0, 1, 2001)
    s = min_jerk(u)
    v = np.gradient(s, u) * 0.5 / T
    acc = np.gradient(np.gradient(s, u), u) * 0.5 / T**2
    assert np.max(np.abs(v)) <= 2.0 * 1.0001
    assert np.max(np.abs(acc)) <= 100.0 * 1.01


def test_sample_sums_overlapping_phases():
    phases = [_ph([0], n=2, T=0.1), _ph([1], n=2, T=0.1)]
    q = sample(phases, np.array([0.0, 0.05]), np.array([0.0, 0.05, 0.1, 0.15]), np.zeros(2))
    assert q[:, 0] == pytest.approx([0.0, 0.5, 1.0, 1.0])
    assert q[:, 1] == pytest.approx([0.0, 0.0, 0.5, 1.0])



def test_min_jerk_rates_match_finite_differences():
    u = np.linspace(0.0, 1.0, 201)
    v, a = min_jerk_rates(u)
    h = 1e-6
    assert v == pytest.approx((min_jerk(u + h) - min_jerk(u - h)) / (2 * h), abs=1e-4)
    assert a[1:-1] == pytest.approx((min_jerk(u + h)[1:-1] - 2 * min_jerk(u)[1:-1] + min_jerk(u - h)[1:-1]) / h**2,
                                    abs=2e-2)
    assert max(v) == pytest.approx(15.0 / 8.0)
    assert max(np.abs(a)) == pytest.approx(10.0 / np.sqrt(3.0), rel=1e-3)
    v_out, a_out = min_jerk_rates(np.array([-0.5, 1.5]))
    assert np.all(v_out == 0.0) and np.all(a_out == 0.0)


def test_jerk_duration_keeps_a_move_within_its_jerk_bound():
    """A min-jerk move of 0.1 rad on a joint bounded at 25000 rad/s^3 (an abduction's):
    at its ``jerk_duration`` (cbrt(60 x 0.1 / (0.98 x 25000)) = 62.6 ms) the rows' third
    differences at 1000 Hz peak at 0.98 of the bound or less; 20 % shorter they exceed it
    (60 / 0.8^3 = 1.95 x the peak); ``phase_duration`` given the bound is no shorter."""
    dq, j_max = np.array([0.1, 0.0]), np.array([25000.0, 1.0])
    T = jerk_duration(dq, j_max)
    assert T == pytest.approx(np.cbrt(60 * 0.1 / (LIMIT_MARGIN * 25000.0)))
    assert jerk_duration(np.zeros(2), j_max) == 0.0
    v, a = np.array([10.0, 1.0]), np.array([500.0, 1.0])
    assert phase_duration(dq, v, a) < T == phase_duration(dq, v, a, j_max=j_max)

    def peak_jerk(T_s):
        t = np.arange(-0.01, T_s + 0.01, 1e-3)
        q = 0.1 * min_jerk(t / T_s)
        return np.max(np.abs(np.diff(q, 3))) / 1e-9

    assert peak_jerk(T) <= LIMIT_MARGIN * 25000.0 * 1.001
    assert peak_jerk(0.8 * T) > 25000.0

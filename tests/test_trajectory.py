"""Min-jerk phases and their sampler (planner/trajectory.py, the catch planner's motion)."""

import numpy as np
import pytest

from planner.trajectory import Phase, min_jerk, min_jerk_rates, phase_duration, sample


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

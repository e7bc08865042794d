"""The timing QP and the phase sampler (planner/trajectory.py)."""

import numpy as np
import pytest

from planner.trajectory import (
    Phase,
    TimingProblem,
    build_timing,
    min_jerk,
    min_jerk_rates,
    phase_duration,
    sample,
    solve_timing,
)


def _ph(joints, n=4, T=0.1, anchor=0.5, ideal=0.0, weight=0.0, **kw):
    d = np.zeros(n)
    d[list(joints)] = 1.0
    return Phase(d, T, anchor, ideal, weight, **kw)


def test_phases_on_a_common_joint_run_in_order():
    phases = [_ph([0], T=0.2, ideal=1.0, weight=1.0), _ph([0, 1], T=0.1, ideal=1.0, weight=1.0)]
    x = solve_timing(build_timing(phases, 0.0))
    assert x[1] - x[0] >= 0.2 - 1e-9
    # both anchors want 1.0 but must be 0.2 - 0.1 + 0.05 = 0.15 s apart: equal weights
    # split the conflict evenly
    assert x[0] + 0.1 == pytest.approx(1.0 - 0.075, abs=1e-6)
    assert x[1] + 0.05 == pytest.approx(1.0 + 0.075, abs=1e-6)


def test_phases_on_disjoint_joints_overlap():
    phases = [_ph([0], ideal=1.0, weight=1.0), _ph([1], ideal=1.0, weight=1.0)]
    x = solve_timing(build_timing(phases, 0.0))
    assert x == pytest.approx([0.95, 0.95], abs=1e-6)


def test_follows_lag_holds_without_a_common_joint():
    phases = [_ph([0], T=0.2, ideal=1.0, weight=1.0),
              _ph([1], T=0.1, ideal=1.0, weight=1.0, follows=((0, 0.15),))]
    prob = build_timing(phases, 0.0)
    assert prob.after.tolist() == [[0, 1]] and prob.lags.tolist() == [0.15]
    x = solve_timing(prob)
    assert x[1] - x[0] >= 0.15 - 1e-9
    assert x[1] - x[0] < 0.2  # overlaps the end of phase 0


def test_follows_must_point_back():
    with pytest.raises(ValueError, match="not an earlier phase"):
        build_timing([_ph([0], follows=((1, 0.1),)), _ph([1])], 0.0)


def test_earliest_bounds_every_start():
    phases = [_ph([0], ideal=0.0, weight=1.0, earliest_s=0.3), _ph([1], ideal=0.0, weight=1.0)]
    x = solve_timing(build_timing(phases, 0.2))
    assert x[0] >= 0.3 - 1e-12 and x[1] >= 0.2 - 1e-12


def test_no_false_infeasibility_on_chains_of_untimed_phases():
    # a chunk of the planner's (ode_to_joy) on which OSQP's default infeasibility
    # tolerances declared this strictly convex, always feasible QP "dual infeasible"
    d = np.array([0.01, 0.018156, 0.040899, 0.043165, 0.04738, 0.047141, 0.010548, 0.010655,
                  0.037702, 0.050964, 0.078424, 0.025941, 0.04726])
    after = np.array([[0, 1], [1, 2], [3, 4], [4, 5], [6, 7], [7, 8], [9, 10], [10, 11]])
    a = np.full(13, 0.5)
    a[12] = 0.408981
    ideal = np.zeros(13)
    ideal[12] = 0.435
    w = np.zeros(13)
    w[12] = 0.3
    prob = TimingProblem(d, a, ideal, w, np.zeros(13), after, d[after[:, 0]], 0.0)
    x = solve_timing(prob)
    for (p, q), lag in zip(after, prob.lags):
        assert x[q] - x[p] >= lag - 1e-12
    assert x[12] + a[12] * d[12] == pytest.approx(0.435, abs=1e-6)
    assert x[0] == pytest.approx(0.0, abs=1e-6)  # untimed phases start at once


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



def test_blend_shortens_the_lag_to_the_phase_it_names_only():
    p0 = _ph([0], T=0.1)
    p1 = _ph([0], T=0.1, blend_s=0.03, blend_after=0)
    p2 = _ph([0], T=0.1, blend_s=0.03, blend_after=0)  # names a phase that is not its previous one
    prob = build_timing([p0, p1, p2], 0.0)
    lags = {tuple(pq): lag for pq, lag in zip(prob.after.tolist(), prob.lags)}
    assert lags[(0, 1)] == pytest.approx(0.07)
    assert lags[(1, 2)] == pytest.approx(0.1)
    x = solve_timing(prob)
    assert x[1] - x[0] == pytest.approx(0.07, abs=1e-6)
    assert x[2] - x[1] == pytest.approx(0.1, abs=1e-6)


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

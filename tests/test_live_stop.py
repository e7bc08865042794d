"""The live soft stop's pieces (planner.catch.live.stop): the contact QP solved exactly, the
slower motion of a late hand. No wall-clock assertions."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from planner.catch import CatchSession, get_planner
from planner.catch.flight.path import get_ball, predict_throw
from planner.catch.live.stop import (
    LATE_STEPS,
    box_qp,
    column_medians,
    giving_contact_speeds,
    scaled,
)
from planner.catch.plan.contactqp import contact_qp, contact_speeds
from planner.catch.plan.softstop import SoftStop


def test_box_qp_is_the_osqp_minimum():
    """The active-set solution is the QP's minimum: OSQP's objective to rounding, never
    below it by more, and within the bounds."""
    rng = np.random.default_rng(0)
    for _ in range(300):
        J = rng.normal(size=(3, 3)) * rng.uniform(0.01, 0.5)
        v, n = rng.normal(size=3) * 5, rng.normal(size=3)
        b = rng.uniform(0.1, 8.0, 3)
        P, c = contact_qp(J, v, n, 30.0)
        x = box_qp(P, c, -b, b)
        y = contact_speeds(J, v, b, n, 30.0)
        fx, fy = (0.5 * z @ P @ z + c @ z for z in (x, y))
        assert np.all(np.abs(x) <= b + 1e-12)
        assert fx <= fy + 1e-9 * (1.0 + abs(fy))


def test_the_flexion_gives_with_the_ball():
    """The flexion's speed moves the palm target against the palm's normal (or not at all)."""
    rng = np.random.default_rng(1)
    speeds = giving_contact_speeds(1)
    for _ in range(200):
        J = rng.normal(size=(3, 3))
        v, n = rng.normal(size=3) * 5, rng.normal(size=3)
        x = speeds(J, v, np.full(3, 8.0), n, 30.0)
        assert x[1] * float(J[:, 1] @ n) <= 1e-12


def test_a_slower_stop_keeps_its_peak_accelerations():
    """``scaled``: speeds and ramps by the same share, so the ramps' accelerations (hence the
    motors' inertial loads) are no higher; the ramp starts later, nearer the intercept."""
    z = np.zeros(3)
    stop = SoftStop(0.0, (0, 1, 2), np.array([0.1, -7.8, 0.9]), 0.9, 0.5, 0.01, 0.12, 0.01,
                    0.02, 0.14, 0.01, z, z, z, z, 1.0)
    slow = scaled(stop, 0.5)
    t = np.linspace(0.3, 0.8, 5001)
    dt = t[1] - t[0]

    def peak_acc(s):
        return np.abs(np.diff(s.offset(t, 3), 2, axis=0) / dt ** 2).max()

    assert slow.start_s > stop.start_s and slow.t_i == stop.t_i
    assert peak_acc(slow) <= peak_acc(stop) * (1 + 1e-6)


def test_simulate_replays_the_ball_the_check_judges():
    """A live file's ball is its end marker's last estimate for the check and for the
    physics replay alike (``check.ball.judged_source``); a planned file's, its metadata's."""
    from planner.catch import CatchSession, get_planner, plan_catch
    from planner.catch.flight.camera import observe_throw
    from planner.catch.flight.path import get_ball, predict_throw
    from planner.check.ball import judged_source
    from planner.trajfile import parse_trajectory

    ball = get_ball("tennis")
    fl = predict_throw(30.0, 1.5, 0.0, ball, drag=True)
    s = observe_throw(CatchSession(1.5, 0.0, ball=ball, drag=True, planner=get_planner("default")),
                      fl, 0.005, 100.0, np.random.default_rng(0))
    tr = parse_trajectory(s.text)
    src = judged_source(tr, "live.csv")
    assert src["ball"] == tr.end["ball"] and src["intercept_t"] == tr.end["intercept_t"]
    assert src["ball"] != tr.metadata["ball"]
    planned = parse_trajectory(plan_catch(30.0, 1.5, 0.0, "default").text)
    assert judged_source(planned, "planned.csv") is planned.metadata


def _same_stop(a: SoftStop, b: SoftStop) -> bool:
    return all(np.array_equal(getattr(a, f.name), getattr(b, f.name))
               for f in dataclasses.fields(SoftStop))


def test_the_slower_stop_is_the_bisection_of_scaled_stops():
    """``LiveStopper.slower`` bisects in numbers (no stop made at each step): the stop,
    its pre-catch pose and the move's duration are those of the bisection over the
    stops themselves (``scaled``, then ``shifted`` through the pose, ``ready`` against
    their ramps' start) bit for bit, for a moving hand late by a range of times (some
    shares strictly between 0 and 1)."""
    pl, ball = get_planner("default"), get_ball("tennis")
    fl = predict_throw(30.0, 1.5, 0.0, ball, drag=True)
    s = CatchSession(1.5, 0.0, ball=ball, drag=True, planner=pl)
    t = 0.01
    while not (s.motion.moving and s.pose is not None and s.stopper.nominal is not None):
        s.observe(t, fl.position(t))
        t += 0.01
    sp, shares = s.stopper, set()
    base = sp.nominal
    for t_b in np.linspace(t, base.start_s, 12):
        got = copy.copy(sp).slower(s.pose, float(t_b))
        ref = copy.copy(sp)
        lo, hi = 0.0, 1.0
        for _ in range(LATE_STEPS):
            k = 0.5 * (lo + hi)
            ref.stop = scaled(base, k)
            ref.shifted(s.pose)
            lo, hi = (k, hi) if ref.ready(float(t_b)) <= ref.stop.start_s else (lo, k)
        ref.stop = scaled(base, lo)
        ref.shifted(s.pose)
        assert _same_stop(got[0], ref.stop) and np.array_equal(got[1], ref.q_pre)
        assert got[2] == ref.ready(float(t_b)) - float(t_b)
        shares.add(lo)
    assert any(0.0 < k < 1.0 for k in shares) and len(shares) > 2


def test_column_medians_are_np_median():
    """The stop table's prior (``column_medians``) is ``np.median``'s, bit for bit, for
    odd and even counts (the table has up to 15 throws; one is left out where no throw
    passes its catch point)."""
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 14, 15):
        P = rng.normal(size=(n, 5))
        P[rng.integers(0, n, 2), 1] = 0.25  # (ties)
        assert np.array_equal(column_medians(P), np.median(P, axis=0))

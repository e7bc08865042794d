"""The live search's palm tilt at the deviation's limit (``live.search.LiveSearch.next``):
where the table's tilt faces no pose, the palm tilted as far as one does, not the untilted
palm (whose pose differs from the tilted one by the whole tilt: estimates on either side of
the limit moved the arm's target back and forth). No wall-clock assertions."""

from __future__ import annotations

import math

import numpy as np

from planner.catch.flight.path import get_ball, predict_throw
from planner.catch.live.search import TILT_STEPS, LiveSearch
from planner.catch.plan.api import get_planner
from planner.catch.plan.intercept import find_intercept


def test_the_palm_tilts_as_far_as_a_pose_faces():
    pl, ball = get_planner("default"), get_ball("tennis")
    r = ball.radius_m
    fl = predict_throw(54.3, 1.2, 0.15, ball, drag=True)
    C = np.array([1.2, 0.0, 0.15])
    t_c = float(fl.time_at_x(1.2))
    tilt = math.radians(-15.0)
    full = find_intercept(pl.wrist, fl, C, r, t_c, tilt)
    flat = find_intercept(pl.wrist, fl, C, r, t_c, 0.0)
    assert not full.aligned and flat.aligned and flat.reason is None  # (the case)
    s = LiveSearch(pl.wrist, C, r)
    s.tilt = tilt
    ic = s.next(fl, 0.2, flat, flat.t)
    assert ic.reason is None and ic.aligned
    share = ic.misalign / abs(tilt)
    assert 0.0 < share < 1.0 and share * 2 ** TILT_STEPS == round(share * 2 ** TILT_STEPS)
    # the largest share on the bisection's grid that faces a pose: the next one up does not
    up = find_intercept(pl.wrist, fl, C, r, t_c, (share + 2.0 ** -TILT_STEPS) * tilt)
    assert not (up.aligned and up.reason is None)
    assert s.tilt == tilt  # (the table's tilt kept for the next estimate)

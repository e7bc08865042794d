"""The move to the pre-catch pose (``StopDynamics.calm_move_time``): within MOVE_SHARE of
every motor where it is still there before the stop's ramp and the closing's start, else as
fast as STOP_SHARE allows. No wall-clock assertions."""

from __future__ import annotations

import numpy as np
import pytest

from planner.catch.plan.api import plan_throw
from planner.catch.plan.arm import move_time
from planner.catch.plan.stopping import MOVE_SHARE, MOVE_SPARE_S, STOP_SHARE


def _move_peak_share(dyn, q_from, q_to, T):
    """The model's largest motor load over its capacity at the move's peak acceleration
    (``room_time``'s rule: the ends' inertia and gravity)."""
    from planner.trajectory import PEAK_ACC

    dq = q_to - q_from
    worst = 0.0
    for q in (q_from, q_to):
        MH, room = dyn.accel_room(q)
        grav = STOP_SHARE * dyn.cap - room  # |gravity| per motor
        load = grav + np.abs(MH @ dq) * PEAK_ACC / T ** 2
        worst = max(worst, float(np.max(load / dyn.cap)))
    return worst


def test_calm_move_with_time_to_spare(pl):
    """30 deg from 1.5 m: the open hand waits ~0.1 s; the move is the calm one, within
    MOVE_SHARE of every motor, and still there before the closing starts."""
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    assert p.feasible
    tm = p.timing
    dyn = pl.dyn
    q_to = p.poses.q_open
    fast = dyn.move_time(pl.q_rest, q_to)
    assert tm.move_s > fast * 1.05  # slower than the STOP_SHARE move
    assert _move_peak_share(dyn, pl.q_rest, q_to, tm.move_s) <= MOVE_SHARE + 1e-6
    assert tm.move_start_s + tm.move_s <= tm.close_start_s - MOVE_SPARE_S + 1e-9


def test_fast_move_when_no_time(pl):
    """15 deg from 1.5 m: the closing starts before the fast move ends; the move is the
    shortest (``arm.move_time``: the STOP_SHARE one, or longer where the jerk bounds need it:
    here they do, 0.099 s for 0.079 s; a calmer one would delay the closing)."""
    p = plan_throw(15.0, 1.5, 0.0, planner=pl)
    assert p.feasible
    tm = p.timing
    assert tm.move_s == pytest.approx(move_time(pl.dyn, pl.q_rest, p.poses.q_open), abs=1e-12)
    assert tm.move_s > pl.dyn.move_time(pl.q_rest, p.poses.q_open)

"""planner.guard.guard_rows: setpoints outside the joint limits or speeds are refused
(never clamped), the first offender named; rows within them pass."""

from __future__ import annotations

import numpy as np
import pytest

from planner.errors import SolverError
from planner.guard import guard_rows


def _rows(hand, n=4):
    mid = 0.5 * (hand.lower + hand.upper)
    return np.tile(mid, (n, 1))


def test_rows_within_the_limits_pass(hand):
    q = _rows(hand)
    dt = 0.01
    q[1:] += 0.5 * hand.velocity * dt  # half the speed limit, row to row
    q = np.minimum(q, hand.upper)
    guard_rows(hand, q, None, dt)
    guard_rows(hand, q[1:], q[0], dt)
    guard_rows(hand, q[:1], None, dt)  # one row: no speed to check


def test_a_position_outside_is_refused_and_named(hand):
    q = _rows(hand)
    j = 2
    q[3, j] = hand.upper[j] + 1e-6
    with pytest.raises(SolverError, match=f"{hand.joint_names[j]} = .* outside"):
        guard_rows(hand, q, None, 0.01)
    q[:, j] = hand.upper[j] + 1e-10  # within the 1e-9 rad of rounding (every row: no speed)
    guard_rows(hand, q, None, 0.01)


def test_a_speed_over_is_refused_also_from_the_row_before(hand):
    dt = 0.01
    q = _rows(hand, 2)
    j = 1
    prev = q[0].copy()
    prev[j] -= 1.01 * hand.velocity[j] * dt  # the step into the first row is too fast
    with pytest.raises(SolverError, match=f"{hand.joint_names[j]} speed"):
        guard_rows(hand, q, prev, dt)
    guard_rows(hand, q, None, dt)  # (the same rows alone are fine)


def test_a_non_finite_setpoint_is_refused(hand):
    q = _rows(hand)
    q[1, 0] = np.nan
    with pytest.raises(SolverError, match="non-finite"):
        guard_rows(hand, q, None, 0.01)

"""The ball's roll along the palm (``planner.check.ballroll``) and the ball's inertia
(``Ball.inertia_ratio``). No wall-clock assertions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.catch.flight.path import BALLS, Ball
from planner.check.ballroll import roll_factor, roll_towards_wrist_m
from planner.errors import InputError


def _incline(tilt_deg: float, n_rows: int = 31, dt: float = 0.01):
    """Rows of a still palm ``tilt_deg`` from level, its +y (towards the wrist) downhill."""
    th = math.radians(tilt_deg)
    y = np.array([math.cos(th), 0.0, -math.sin(th)])
    z = np.array([math.sin(th), 0.0, math.cos(th)])
    T = np.tile(np.eye(4), (n_rows, 1, 1))
    T[:, :3, 0], T[:, :3, 1], T[:, :3, 2] = np.cross(y, z), y, z
    return np.arange(n_rows) * dt, T


def test_roll_on_a_still_incline_is_the_rolling_ball_law():
    """On a still incline a ball rolls 1/2 k g sin(tilt) t^2, k = 1 / (1 + I / (m R^2)):
    5/7 solid, 3/5 a thin shell, 1/1.61 the tennis ball's thick shell; uphill it stays."""
    t, T = _incline(30.0)
    for ratio, k in ((0.4, 5.0 / 7.0), (2.0 / 3.0, 0.6),
                     (BALLS["tennis"].inertia_ratio, 1.0 / 1.61)):
        assert roll_factor(ratio) == pytest.approx(k)
        got = roll_towards_wrist_m(t, T, 0.0335, 0.0, np.zeros(3), ratio)
        assert got == pytest.approx(0.5 * k * 9.81 * 0.5 * 0.3 ** 2, rel=1e-9)
    t, T = _incline(-10.0)  # downhill into the fingers: the fingers stop it at the target
    assert roll_towards_wrist_m(t, T, 0.0335, 0.0, np.zeros(3), 0.4) == 0.0


def test_roll_keeps_the_share_of_the_landing_speed_along_the_palm():
    """On a level still palm a ball landing at 1 m/s towards the wrist rolls k x 1 m/s."""
    t, T = _incline(0.0)
    v = np.array([1.0, 0.0, -3.0])  # 1 m/s along the palm's +y, 3 m/s into it
    assert roll_towards_wrist_m(t, T, 0.0335, 0.0, v, 0.4) == pytest.approx(5.0 / 7.0 * 0.3)


def test_ball_inertia_is_checked_and_the_tennis_ball_is_a_thick_shell():
    """I / (m R^2) of a uniform shell 33.5 mm outside, 30.3 mm inside: 0.61."""
    R, a = 33.5, 30.3
    shell = 0.4 * (R ** 5 - a ** 5) / (R ** 3 - a ** 3) / R ** 2
    assert BALLS["tennis"].inertia_ratio == pytest.approx(shell, abs=0.005)
    assert Ball("x", 0.05, 0.03, 0.5).inertia_ratio == 0.4  # a solid ball unless said
    for bad in (0.0, 0.7, float("nan")):
        with pytest.raises(InputError):
            Ball("x", 0.05, 0.03, 0.5, bad)

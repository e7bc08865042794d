"""The ball's roll along the palm (``planner.check.ballroll``) and the ball's inertia
(``Ball.inertia_ratio``). No wall-clock assertions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.catch.flight.path import BALLS, Ball
from planner.check.ballpalm import ROLL_STEP_S
from planner.check.ballroll import roll_factor, roll_towards_wrist_m
from planner.check.ballstop import PALM_MU
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
        # (time steps of ROLL_STEP_S, velocity first: 1/2 a t^2 (1 + h / t))
        assert got == pytest.approx(0.5 * k * 9.81 * 0.5 * 0.3 ** 2 * (1 + ROLL_STEP_S / 0.3),
                                    rel=1e-6)
    t, T = _incline(-10.0)  # downhill into the fingers: the fingers stop it at the target
    assert roll_towards_wrist_m(t, T, 0.0335, 0.0, np.zeros(3), 0.4) == pytest.approx(0.0, abs=1e-12)


def test_roll_on_a_steep_palm_slides():
    """Steeper than atan(mu (1 + beta) / beta) (65 deg for the tennis ball on the pad's mu
    0.8) friction cannot keep the ball rolling: it slides at g (sin - mu cos), faster than
    the rolling law's k g sin; below that angle it rolls."""
    beta = BALLS["tennis"].inertia_ratio
    assert math.degrees(math.atan(PALM_MU * (1 + beta) / beta)) == pytest.approx(64.7, abs=0.1)
    th = math.radians(75.0)
    t, T = _incline(75.0)
    got = roll_towards_wrist_m(t, T, 0.0335, 0.0, np.zeros(3), beta)
    slide = 0.5 * 9.81 * (math.sin(th) - PALM_MU * math.cos(th)) * 0.3 ** 2
    assert got == pytest.approx(slide * (1 + ROLL_STEP_S / 0.3), rel=1e-6)
    assert got > 1.2 * 0.5 * roll_factor(beta) * 9.81 * math.sin(th) * 0.3 ** 2


def test_roll_on_a_turning_palm_follows_the_spin():
    """A level palm turning about its x axis under a ball landed at rest on it: the ball
    (no spin at the landing) must take the palm's spin, and friction pushes it along: it
    rolls, where the rolling law of the rows' accelerations alone (the palm target still)
    said it stays."""
    n_rows, dt, rate = 31, 0.01, 4.0  # rad/s about the palm's x, about the palm centre
    t = np.arange(n_rows) * dt
    T = np.tile(np.eye(4), (n_rows, 1, 1))
    for k, tk in enumerate(t):
        a = rate * min(tk, 0.05)  # turns for 50 ms, then still
        c, s_ = math.cos(a), math.sin(a)
        T[k, :3, :3] = [[1, 0, 0], [0, c, -s_], [0, s_, c]]
    got = roll_towards_wrist_m(t, T, 0.0335, 0.0, np.zeros(3), 0.4)
    assert got > 0.005


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

"""The ball rolling along the palm after the pad has stopped it (``docs/history/physics-replay.md``,
"Catch"): nothing on the palm's wrist side stops a ball that rolls there, so the plan must
keep its roll towards the wrist within ``ROLL_ROOM_M`` until the wrist's turn has levelled
the palm. One rule (``roll_problem``) of the catch planner (a plan whose rows let the ball
roll further is infeasible, ``CatchReason.ROLL``) and of the check (such a catch is not
confirmed); the ball's inertia is the plan's ``Ball.inertia_ratio``, a file's
``planner.balls.file_inertia_ratio``.

A ball of mass m, radius R and moment of inertia I = ``Ball.inertia_ratio`` m R^2 rolling
without slipping on a plane that accelerates at a (the palm target's acceleration: its
translation and the turn's centripetal part) moves along the plane at
(g - a) . y / (1 + I / (m R^2)) (5/7 g sin(tilt) for a solid ball on a still incline),
y the plane's direction towards the wrist; it starts with the same share of its speed along
the palm when it lands (a sliding ball's speed once it rolls, without spin at the landing).
"""

from __future__ import annotations

import numpy as np

from planner.check.ballpalm import BallOnPalm
from planner.check.ballstop import PALM_MU

ROLL_ROOM_M = 0.042  # how far the ball may roll from the palm target towards the wrist: there
# it meets the forearm (measured in the replay, 20 deg / 1.0 m at 92f563c: the ball touches
# the forearm's box 42 mm from the palm centre and rides up it, out of the hand)
ROLL_TOL_M = 1e-4  # the check's tolerance on a file's rows (their 1e-6 rad rounding):
# measured, the roll on a written plan's rows is within 0.01 mm of the plan's own on every
# throw of bench_catch.py's wide grid (165 throws)


ROLL_RULE_HANDS = frozenset({"default"})  # the hands on which the rule is measured: a roll
# beyond the room lost the ball in the replay (the default hand, wide grid: 24 of the 26 throws
# the rule refuses). Not on mk5: its forearm is 28 mm from the palm target at 30 deg / 1.5
# m's intercept pose, and that plan's 57 mm of modelled roll is held in physics (71 mm from
# the palm centre): there the roll is reported, not judged, until its own room is measured.


def roll_judged(hand_name: object) -> bool:
    """Whether the roll rule judges catches of the hand named ``hand_name``."""
    return hand_name in ROLL_RULE_HANDS


def roll_factor(inertia_ratio: float) -> float:
    """The share of the tangential force a rolling ball's centre follows: 1 / (1 + I/(m R^2))
    (5/7 for a solid ball, 3/5 for a thin shell)."""
    return 1.0 / (1.0 + float(inertia_ratio))


def roll_path_m(t_s: np.ndarray, palm: np.ndarray, radius_m: float, t_land_s: float,
                v_ball_m_s: np.ndarray, inertia_ratio: float, mu: float = PALM_MU
                ) -> np.ndarray:
    """The ball's roll towards the wrist (m, along the palm's +y from the palm target) at
    every row at times ``t_s`` with palm poses ``palm`` (T, 4, 4), from its landing at
    ``t_land_s`` on the palm target at velocity ``v_ball_m_s`` without spin (the file's
    ball has none): 0 on the rows before the landing.

    The ball (mass m, radius R, I = ``inertia_ratio`` m R^2) on the palm's plane as the rows
    move it, in time steps of ``ROLL_STEP_S`` (``ball_on_palm``): the palm between two rows
    turns at the rows' angular velocity and its centre moves at their speed (as the
    replay's servos follow the joints moving linearly from row to row); the contact
    stops the ball's approach (a non-penetrating impulse, the ball may leave a palm that
    falls away faster than gravity), and friction (Coulomb, ``mu``: the palm pad's rubber)
    brings the contact point to the palm's velocity when it can (the ball rolls; at most
    ``mu`` times the normal impulse: it slides, on a palm steeper than
    atan(mu (1 + I / (m R^2)) / (I / (m R^2))), 65 deg for a tennis ball, or where the palm
    turns fast). So it carries what the rolling ball's law (``roll_factor``) leaves out:
    the palm's turn (the ball's spin must follow it, the centrifugal and the Coriolis
    terms), the slide of a steep palm, and the lift-off of a palm falling away. Nothing
    on the palm holds the ball towards the fingers but the palm target's place (the roll is
    not negative: the palm's cup and the fingers on that side)."""
    out = np.zeros(len(t_s))
    after = np.flatnonzero(t_s > t_land_s)
    if len(after) < 2 or after[0] < 1:
        return out
    k0 = int(after[0])
    ball = BallOnPalm(float(radius_m), float(inertia_ratio), float(mu))
    ball.land(palm, t_s, k0 - 1, float(t_land_s), np.asarray(v_ball_m_s, dtype=float))
    for k in range(k0, len(t_s)):
        out[k] = ball.step_to(palm, t_s, k)
    return out


def roll_towards_wrist_m(t_s: np.ndarray, palm: np.ndarray, radius_m: float, t_land_s: float,
                         v_ball_m_s: np.ndarray, inertia_ratio: float) -> float:
    """The ball's largest roll towards the wrist (m) on the rows (``roll_path_m``)."""
    return float(np.max(roll_path_m(t_s, palm, radius_m, t_land_s, v_ball_m_s,
                                    inertia_ratio), initial=0.0))


def roll_problem(roll_m: float, tol_m: float = 0.0) -> str | None:
    """The rule: the ball's roll towards the wrist ``roll_m`` (``roll_towards_wrist_m``)
    beyond ``ROLL_ROOM_M`` (+ ``tol_m``) loses the ball -- the reason, else None."""
    if roll_m <= ROLL_ROOM_M + tol_m:
        return None
    return (f"the ball rolls off the palm's wrist side: {1000 * roll_m:.0f} mm towards the "
            f"wrist on the rows before the wrist's turn levels the palm, beyond the "
            f"{1000 * ROLL_ROOM_M:g} mm of palm before the forearm")

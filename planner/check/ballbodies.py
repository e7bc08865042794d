"""The ball's flight against the fingers' bodies before it lands on the palm: one rule of
the check (``planner.check.ball``) and of the catch planner's self-check
(``planner.catch.plan.rowcheck``), the same definition.

A ball that touches a finger before the palm is deflected: the palm then meets it
elsewhere or not at all. Measured in the replay (wide grid, -0.3 m / 25 deg / 3.0 m at
2d5a21d): the ball, at 6 m/s, struck the thumb's distal segment (its capsule and its pad)
14 ms before the intercept, lost 0.5 m/s there and slid off the palm, while every
fingertip point stayed outside the ball at every row (10 ms apart: 60 mm of the ball's
flight) -- the point rule at the rows alone missed it.

So the rule judges every finger's collision bodies (``planner.hand.bodies``: the
segments' capsules and the pads' spheres, the shapes the replay collides) against the
ball's centre on a fine time grid (``FINE_S``) over the last ``WINDOW_S`` before the
intercept, the joints moving linearly from row to row (as the replay's servo
references do): a gap below zero is a finger inside the ball.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.hand.bodies import BOX, Body, body_links, place

FINE_S = 1e-3  # the grid's step: the fastest ball of the grid (10 m/s) moves 10 mm in it,
# less than the thinnest finger body's 6 mm radius plus the ball's 33.5 mm
WINDOW_S = 0.25  # how long before the intercept the flight is judged: a 2 m/s ball is
# then 0.5 m away, beyond any finger's reach from the palm (the longest finger ~0.2 m)
LAND_S = 1e-3  # the last instant judged is this long before the intercept: there the ball
# is within a millimetre or two of the palm (at up to 2 m/s towards it) and meets it


@dataclass(frozen=True)
class FingerHit:
    """The least gap (m) between the ball and a finger's body before the intercept, where
    (``time_s``) and which (``body``, its finger ``finger``)."""

    gap_m: float
    time_s: float
    body: str
    finger: str


def finger_bodies(bodies: tuple[Body, ...]) -> tuple[Body, ...]:
    """The fingers' swept bodies (capsules and pad spheres) of a hand's bodies."""
    return tuple(b for b in bodies if b.finger is not None and b.kind != BOX)


def fine_times(t_s: np.ndarray, t_i: float) -> np.ndarray:
    """The instants judged: every ``FINE_S`` from ``WINDOW_S`` before the intercept (not
    before the first row) to ``LAND_S`` before it."""
    lo = max(float(t_s[0]), t_i - WINDOW_S)
    hi = t_i - LAND_S
    if hi <= lo:
        return np.zeros(0)
    n = int(np.floor((hi - lo) / FINE_S + 1e-9)) + 1
    return lo + FINE_S * np.arange(n)


def rows_at(t_s: np.ndarray, Q: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The rows interpolated linearly at ``times`` (held at the ends)."""
    if len(t_s) < 2:
        return np.repeat(Q[:1], len(times), axis=0)
    k = np.clip(np.searchsorted(t_s, times, side="right") - 1, 0, len(t_s) - 2)
    w = np.clip((times - t_s[k]) / (t_s[k + 1] - t_s[k]), 0.0, 1.0)[:, None]
    return (1.0 - w) * Q[k] + w * Q[k + 1]


def finger_hit(bodies: tuple[Body, ...], link_poses: Callable[[np.ndarray, tuple[str, ...]],
               dict[str, np.ndarray]], t_s: np.ndarray, Q: np.ndarray, t_i: float,
               ball_at: Callable[[np.ndarray], np.ndarray], radius_m: float
               ) -> FingerHit | None:
    """The ball's least gap to a finger's body before the intercept at ``t_i`` (None: no
    instant to judge or no finger body). ``link_poses(Q, links)``: the links' world poses
    (T, 4, 4) at joint rows ``Q``; ``ball_at(times)``: the ball's centre (T, 3) in the same
    frame."""
    fb = finger_bodies(bodies)
    times = fine_times(t_s, t_i)
    if not fb or not len(times):
        return None
    placed = place(fb, link_poses(rows_at(t_s, Q, times), body_links(fb)))
    c = ball_at(times)[:, None, :]
    ab = placed.b - placed.a
    L2 = np.maximum(np.einsum("tsi,tsi->ts", ab, ab), 1e-18)
    u = np.clip(np.einsum("tsi,tsi->ts", c - placed.a, ab) / L2, 0.0, 1.0)
    near = placed.a + u[..., None] * ab
    gap = np.linalg.norm(c - near, axis=-1) - placed.radius_m[None, :] - radius_m
    k, s = np.unravel_index(int(np.argmin(gap)), gap.shape)
    b = fb[placed.swept[s]]
    return FingerHit(float(gap[k, s]), float(times[k]), b.name, str(b.finger))


def finger_hit_problem(hit: FingerHit | None, tol_m: float = 0.0) -> str | None:
    """The rule: a finger's body inside the ball before the intercept -- the reason, else
    None."""
    if hit is None or hit.gap_m >= -tol_m:
        return None
    return (f"fingers in the way: the ball meets the {hit.finger}'s body ({hit.body}) "
            f"{-1000 * hit.gap_m:.1f} mm deep at t = {hit.time_s:.3f} s, before the palm")

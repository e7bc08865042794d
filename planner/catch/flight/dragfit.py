"""What a window of observations says about the ball's drag (``catch --live --drag``).

The live fit (``livefit``) flies the ball with its known drag coefficient (``Ball``: the
ball's Cd, area and mass give k); it never fits k. A short window cannot tell k from the
launch state: over 0.25 s a tennis ball's drag moves it ~1 cm, which a 5 mm camera and six
free state numbers absorb. So the session reports what the window can see: k's least
squares with the state free (one Gauss-Newton step from the known k: the positions'
sensitivity to k at the observations, with the per-axis constant and linear parts -- the
state's -- projected out) and its 1-sigma from the residuals; and says the drag it flies is
the ball's known one, with that one's own uncertainty (``KNOWN_REL_SIGMA``), unless the
window sees k to ``SEEN_REL`` of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.catch.flight.path import Ball, Flight

KNOWN_REL_SIGMA = 0.2  # the ball's known k, 1-sigma: its Cd's spread (a tennis ball's
# 0.5-0.65 between new and worn, 10-30 m/s) and the air's density (altitude, temperature)
SEEN_REL = 0.5  # the window sees the drag when its fit's 1-sigma is below this share of k
MIN_OBS = 8  # fewer observations than this: no fit of k is attempted


@dataclass(frozen=True)
class DragEstimate:
    """The drag the session flies (``used_per_m``, the ball's known k, 1-sigma
    ``known_sigma_per_m``) beside the window's own fit (None: too few observations) and
    whether the window sees it (its 1-sigma below ``SEEN_REL`` of the known k)."""

    used_per_m: float
    known_sigma_per_m: float
    fit_per_m: float | None
    fit_sigma_per_m: float | None
    seen: bool

    def to_dict(self) -> dict[str, float | bool | None]:
        return {"used_per_m": self.used_per_m, "known_sigma_per_m": self.known_sigma_per_m,
                "fit_per_m": self.fit_per_m, "fit_sigma_per_m": self.fit_sigma_per_m,
                "seen": self.seen}

    def describe(self) -> str:
        used = (f"drag k {self.used_per_m:.4f} +- {self.known_sigma_per_m:.4f} 1/m (the "
                "ball's known)")
        if self.fit_per_m is None:
            return used + "; too few observations to fit it"
        fit = f"the window's fit {self.fit_per_m:.4f} +- {self.fit_sigma_per_m:.4f} 1/m"
        return used + (f"; {fit}" if self.seen else f"; {fit}: the window cannot see it")


def estimate_drag(ts: np.ndarray, ps: np.ndarray, flight: Flight, ball: Ball) -> DragEstimate:
    """The window ``ts``, ``ps`` against ``flight`` (the fit with the ball's known k)."""
    k0 = float(ball.drag_per_m)
    known = KNOWN_REL_SIGMA * k0
    ts = np.asarray(ts, dtype=float)
    n = len(ts)
    if n < MIN_OBS:
        return DragEstimate(k0, known, None, None, False)
    dk = max(0.05 * k0, 1e-4)
    base = flight.position(ts)
    other = Flight(flight.p0, flight.v0, ball, float(flight.drag_per_m) + dk).position(ts)
    S = (other - base) / dk  # (n, 3): d position / d k, the state fixed
    R = np.asarray(ps, dtype=float) - base
    A = np.column_stack([np.ones(n), ts])  # the state's part, per axis
    proj = A @ np.linalg.solve(A.T @ A, A.T)
    S_p, R_p = S - proj @ S, R - proj @ R
    ss = float(np.sum(S_p * S_p))
    if not ss > 0.0:
        return DragEstimate(k0, known, None, None, False)
    step = float(np.sum(S_p * R_p)) / ss
    dof = max(3 * n - 7, 1)
    rss = float(np.sum((R_p - step * S_p) ** 2))
    sigma = math.sqrt(rss / dof) / math.sqrt(ss)
    k_fit = float(flight.drag_per_m) + step
    return DragEstimate(k0, known, k_fit, sigma, sigma < SEEN_REL * max(k0, 1e-12))

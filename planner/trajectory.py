"""Min-jerk moves between held configurations, within the hand's speed and acceleration
limits (the catch planner's motion).

The motion between two held configurations is a chain of *phases*; each
phase moves every joint from ``q_a`` to ``q_b`` along the quintic
minimum-jerk profile s(u) = 10u^3 - 15u^4 + 6u^5 (zero speed and
acceleration at both ends). Its duration is the shortest that keeps every
joint within its speed and acceleration limit: peak |ds/du| = 15/8 and peak
|d2s/du2| = 10/sqrt(3), so T >= 1.875 |dq|/v_max and T >= sqrt(5.7735 |dq| /
a_max); given the joints' jerk bounds (``planner.hand.drive``) also within them: peak
|d3s/du3| = 60 (at either end), so T >= cbrt(60 |dq| / j_max). Joint position limits hold because every sample is a convex
combination of two configurations inside them; linear couplings hold
because they are linear. Phases on disjoint joints may overlap; their motions add.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PEAK_VEL = 15.0 / 8.0
PEAK_ACC = 10.0 / np.sqrt(3.0)
PEAK_JERK = 60.0  # |d3s/du3| at u = 0 and 1 (60 - 360 u + 360 u^2)
MIN_PHASE_S = 0.010
LIMIT_MARGIN = 0.98  # plan at 98 % of every speed and acceleration limit


def min_jerk(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


def min_jerk_rates(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ds/du and d2s/du2 of the min-jerk profile (0 outside [0, 1])."""
    inside = (u >= 0.0) & (u <= 1.0)
    w = np.where(inside, u * (1.0 - u), 0.0)
    return 30.0 * w * w, np.where(inside, 60.0 * w * (1.0 - 2.0 * u), 0.0)


def phase_duration(dq: np.ndarray, v_max: np.ndarray, a_max: np.ndarray, floor_s: float = MIN_PHASE_S,
                   j_max: np.ndarray | None = None) -> float:
    """Shortest duration (s) of a min-jerk move ``dq`` within speed/acceleration limits
    (and, given ``j_max``, the joints' jerk bounds: ``jerk_duration``)."""
    adq = np.abs(dq)
    t_v = PEAK_VEL * adq / (LIMIT_MARGIN * v_max)
    t_a = np.sqrt(PEAK_ACC * adq / (LIMIT_MARGIN * a_max))
    t_j = 0.0 if j_max is None else jerk_duration(dq, j_max)
    return float(max(floor_s, t_v.max(initial=0.0), t_a.max(initial=0.0), t_j))


def jerk_duration(dq: np.ndarray, j_max: np.ndarray) -> float:
    """Shortest duration (s) of a min-jerk move ``dq`` within the joints' jerk bounds
    ``j_max`` (at ``LIMIT_MARGIN`` of them, as the speeds and accelerations): 0 for no move."""
    t_j = np.cbrt(PEAK_JERK * np.abs(dq) / (LIMIT_MARGIN * np.asarray(j_max, dtype=float)))
    return float(t_j.max(initial=0.0))


@dataclass(frozen=True)
class Phase:
    """A move of some joints by ``delta`` (the others do not move) lasting ``duration_s``."""

    delta: np.ndarray
    duration_s: float

    @property
    def joints(self) -> np.ndarray:
        return np.flatnonzero(np.abs(self.delta) > 0.0)


def sample(phases: list[Phase], starts: np.ndarray, t_s: np.ndarray, q_hold: np.ndarray) -> np.ndarray:
    """Joint positions at times ``t_s``: ``q_hold`` plus every phase's delta times its
    min-jerk progress (0 before the phase, 1 after it)."""
    out = np.tile(q_hold, (len(t_s), 1))
    for ph, x in zip(phases, starts):
        u = (t_s - x) / ph.duration_s
        js = ph.joints
        if js.size:
            out[:, js] += min_jerk(u)[:, None] * ph.delta[js]
    return out

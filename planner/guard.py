"""The last guard before a row reaches the hand: setpoints outside the joint position or
speed limits are refused, never clamped (they protect the hardware, so a planner bug
must stop the plan). One definition, used by every planner that writes rows."""

from __future__ import annotations

import numpy as np

from planner.errors import SolverError
from planner.hand.model import HandModel


def guard_rows(hand: HandModel, q: np.ndarray, prev: np.ndarray | None, dt: float) -> None:
    """Refuse (never clamp) setpoints outside the joint position or speed limits: they
    protect the hardware, so a planner bug must stop the plan, not reach the hand."""
    if not np.all(np.isfinite(q)):
        raise SolverError("planner produced a non-finite setpoint")
    lo, hi = hand.lower - 1e-9, hand.upper + 1e-9
    bad = np.argwhere((q < lo) | (q > hi))
    if bad.size:
        i, j = bad[0]
        raise SolverError(f"planner bug: {hand.joint_names[j]} = {q[i, j]:.6f} outside "
                          f"[{hand.lower[j]:.6f}, {hand.upper[j]:.6f}]", problem=q)
    rows = q if prev is None else np.vstack([prev, q])
    if len(rows) > 1:
        v = np.abs(np.diff(rows, axis=0)) / dt
        over = np.argwhere(v > hand.velocity * (1.0 + 1e-6) + 1e-9)
        if over.size:
            i, j = over[0]
            raise SolverError(f"planner bug: {hand.joint_names[j]} speed {v[i, j]:.4f} above "
                              f"{hand.velocity[j]:.4f}", problem=q)

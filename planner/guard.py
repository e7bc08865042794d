"""The last guard before a row reaches the hand: setpoints outside the joint position or
speed limits are refused, never clamped (they protect the hardware, so a planner bug
must stop the plan). One definition, run by the trajectory writer on every row it is
given (``planner.trajfile.TrajectoryWriter``): no planner calls it apart."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from planner.errors import SolverError

if TYPE_CHECKING:
    from planner.hand.model import HandModel


def guard_rows(hand: HandModel, q: np.ndarray, prev: np.ndarray | None,
               dt: float | np.ndarray) -> None:
    """Refuse (never clamp) setpoints outside the joint position or speed limits: they
    protect the hardware, so a planner bug must stop the plan, not reach the hand.
    ``prev``: the row before ``q``'s first (None: none); ``dt``: the time step, or each
    step's, (steps, 1)."""
    if not np.isfinite(q).all():
        raise SolverError("planner produced a non-finite setpoint")
    out = (q < hand.lower - 1e-9) | (q > hand.upper + 1e-9)
    if out.any():  # (the first offender named; a live session guards a few rows at a time)
        i, j = np.argwhere(out)[0]
        raise SolverError(f"planner bug: {hand.joint_names[j]} = {q[i, j]:.6f} outside "
                          f"[{hand.lower[j]:.6f}, {hand.upper[j]:.6f}]", problem=q)
    rows = q if prev is None else np.concatenate((prev[None, :], q))
    if len(rows) > 1:
        v = np.abs(np.diff(rows, axis=0)) / dt
        over = v > hand.velocity * (1.0 + 1e-6) + 1e-9
        if over.any():
            i, j = np.argwhere(over)[0]
            raise SolverError(f"planner bug: {hand.joint_names[j]} speed {v[i, j]:.4f} above "
                              f"{hand.velocity[j]:.4f}", problem=q)

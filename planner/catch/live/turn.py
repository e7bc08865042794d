"""The live catch's hold: the planned catch's wrist turn (``holdturn.hold_turn``) on the
live rows. Once the grasp is made and the pad has stopped the ball, the wrist turns the
closed hand palm up, its downhill ``HOLD_TILT_DEG`` into the fingers, so that the ball
rolls into the fingers' cage, not off the open wrist side (the roll rule, which the check
applies to live files as to planned ones). The live rows written before the session's end
never change, so the turn starts at the grasp or at the first row not yet written,
whichever is later."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner.catch.plan.holdturn import hold_turn
from planner.catch.plan.stopping import StopDynamics
from planner.trajectory import min_jerk


class LiveTurn(NamedTuple):
    """The wrist's turn on the live rows: the joints' travel, its duration and start."""

    delta: np.ndarray
    duration_s: float
    start_s: float

    @property
    def end_s(self) -> float:
        return self.start_s + self.duration_s

    def offset(self, t_s: np.ndarray) -> np.ndarray:
        """The turn's part of the rows at ``t_s`` (min-jerk; zero before its start)."""
        u = (np.asarray(t_s, dtype=float) - self.start_s) / self.duration_s
        return min_jerk(u)[:, None] * self.delta


def live_turn(dyn: StopDynamics, q_held: np.ndarray, grasp_s: float, first_free_s: float,
              hold: tuple[np.ndarray, float] | None = None) -> LiveTurn | None:
    """The turn from the hand at rest holding the ball (``q_held``), starting at the grasp
    (``grasp_s``) or at the first row not yet written (``first_free_s``); None when the hold
    has no turn (gravity leaves a motor no room, or the palm already faces up). ``hold``:
    ``hold_turn(dyn, q_held)`` when already computed (``HeldTurn``)."""
    delta, T = hold_turn(dyn, q_held) if hold is None else hold
    if T <= 0.0 or not np.any(delta):
        return None
    return LiveTurn(delta, float(T), max(float(grasp_s), float(first_free_s)))


class HeldTurn:
    """``hold_turn`` of the hand's held pose, computed ahead (a warm start): once the stop
    is fixed, the pose the hand will hold the ball in is known before the session ends
    (the arm's move and the stop's travel fixed, the fingers closed), and the turn from it
    (~0.7 ms of CPU, the ending observation's largest step) is computed after an
    observation's rows are written; the end uses it where its held pose is the same, bit
    for bit (otherwise it computes it: the same function of the same pose either way)."""

    def __init__(self, dyn: StopDynamics) -> None:
        self.dyn = dyn
        self.q: bytes | None = None
        self.hold: tuple[np.ndarray, float] | None = None

    def warm(self, q_held: np.ndarray) -> None:
        """Compute the turn of ``q_held`` (unless it is the one kept)."""
        if self.q != q_held.tobytes():
            self.hold = hold_turn(self.dyn, q_held)
            self.q = q_held.tobytes()

    def of(self, q_held: np.ndarray) -> tuple[np.ndarray, float] | None:
        """The kept turn if it is ``q_held``'s (None: not computed ahead)."""
        return self.hold if self.q == q_held.tobytes() else None

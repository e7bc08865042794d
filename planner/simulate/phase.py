"""A catch replayed at another phase of the physics' time step: the same rows, the ball
launched ``dt_s`` further along its own flight.

The replay's contact is near-rigid (``scene.HARD_SOLREF``: a 2 ms time constant, 1 ms
steps), so the ball is first seen touching the palm somewhere within the last step's
travel (up to |v_n| x 1 ms deep, 3.8-6.1 mm on the default grid) and is pushed back out
at about (step / time constant)^2 = 1/4 of that depth per step: its rebound off the palm,
0 to ~0.25 x its normal speed, is set by where in a step it arrives -- by the sub-step
phase of the throw, not by the plan. Replaying one plan at several phases
(``bench/bench_simulate.py --catch-phases``) separates what the plan decides from that
phase (``docs/history/physics-replay.md``, "Catch").
"""

from __future__ import annotations

from dataclasses import replace

from planner.check.ball import STOP_DIFF_S, ball_params, ball_positions
from planner.check.kinematics import GRAVITY
from planner.errors import InputError
from planner.trajfile import Trajectory


def ball_advanced(tr: Trajectory, dt_s: float) -> Trajectory:
    """``tr`` with its ball launched ``dt_s`` (s) further along its flight: at every time
    the ball is where ``tr``'s would be ``dt_s`` later (its launch state taken from the
    check's own flight, ``planner.check.ball.ball_positions``: exact without drag, the
    speed by a second-order difference with it). The rows are unchanged; ``dt_s`` >= 0."""
    if not dt_s >= 0.0:
        raise InputError(f"the ball can only be advanced along its flight (dt_s >= 0), got {dt_s}")
    b = ball_params(tr.metadata, "<trajectory>")
    h = STOP_DIFF_S
    p = ball_positions(b["p0"], b["v0"], b["drag"], [dt_s, dt_s + h, dt_s + 2.0 * h])
    if b["drag"] == 0.0:
        v = b["v0"] + GRAVITY * dt_s
    else:  # a one-sided difference of second order (the flight starts at dt_s = 0)
        v = (4.0 * p[1] - 3.0 * p[0] - p[2]) / (2.0 * h)
    meta = dict(tr.metadata)
    meta["ball"] = {**tr.metadata["ball"], "p0": [float(x) for x in p[0]],
                    "v0": [float(x) for x in v]}
    return replace(tr, metadata=meta)

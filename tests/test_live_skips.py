"""The live session's skip rules (docs/live-catch.md, "Fewer steps per observation"): what
a re-plan no longer computes at every observation, and that the plan is the one computed
in full (the same bytes) or within the rule's stated tolerance. No wall-clock assertions."""

from __future__ import annotations

import numpy as np
import pytest

from planner.catch.flight import get_ball, predict_throw
from planner.catch.plan import get_planner
from planner.catch.session import CatchSession

BALL = get_ball("tennis")


def _session(angle, dist, height, noise_m, rate_hz, seed=0, patch=None):
    """One throw fed to a session one observation at a time; ``patch(session)`` before."""
    fl = predict_throw(angle, dist, height, BALL, drag=True)
    s = CatchSession(dist, height, ball=BALL, drag=True, planner=get_planner("default"))
    if patch is not None:
        patch(s)
    rng = np.random.default_rng(seed)
    for k in range(1, int(1.5 * rate_hz)):
        t = k / rate_hz
        s.observe(t, fl.position(t) + rng.normal(0.0, noise_m, 3))
        if s.done:
            break
    if not s.done:
        s.finish()
    return s


THROWS = [(30.0, 1.5, 0.0, 0.005, 500.0), (45.0, 2.2, 0.15, 0.010, 500.0),
          (22.0, 1.1, -0.1, 0.002, 100.0)]


@pytest.mark.parametrize("throw", THROWS)
def test_closing_time_deferred_is_the_same_plan(throw):
    """The closing's start is computed only when a row or a decision needs it (its
    earliest, ``earliest_close_start``, not beyond this observation's rows): the same file
    as computing it at every re-plan, with fewer ``close_start`` calls."""
    lazy = _session(*throw)

    def every_time(s):  # every re-plan's rows "reach" the closing: computed each time
        s._last_row_s = lambda t_end_s: np.inf

    full = _session(*throw, patch=every_time)
    assert lazy.text == full.text
    assert lazy.closings_computed < full.closings_computed / 3, (
        lazy.closings_computed, full.closings_computed)

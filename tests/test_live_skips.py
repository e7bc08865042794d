"""The live session's skip rules (docs/history/live-catch.md, "Fewer steps per observation"): what
a re-plan no longer computes at every observation, and that the plan is the one computed
in full (the same bytes) or within the rule's stated tolerance. No wall-clock assertions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.catch.flight.camera import observe_throw
from planner.catch.flight.path import get_ball, predict_throw
from planner.catch.live.session import CatchSession
from planner.catch.plan.api import get_planner

BALL = get_ball("tennis")


def _session(angle, dist, height, noise_m, rate_hz, seed=0, patch=None):
    """One throw fed to a session one observation at a time; ``patch(session)`` before."""
    fl = predict_throw(angle, dist, height, BALL, drag=True)
    s = CatchSession(dist, height, ball=BALL, drag=True, planner=get_planner("default"))
    if patch is not None:
        patch(s)
    return observe_throw(s, fl, noise_m, rate_hz, np.random.default_rng(seed), until_s=1.5)


THROWS = [(30.0, 1.5, 0.0, 0.005, 500.0), (45.0, 2.2, 0.15, 0.010, 500.0),
          (22.0, 1.1, -0.1, 0.002, 100.0)]


@pytest.mark.parametrize("throw", THROWS)
def test_closing_time_deferred_is_the_same_plan(throw):
    """The closing's start is computed only when a row or a decision needs it (its
    earliest, ``earliest_close_start``, not beyond this observation's rows): the same file
    as computing it at every re-plan, with fewer ``close_start`` calls."""
    lazy = _session(*throw)

    def every_time(s):  # every re-plan's rows "reach" the closing: computed each time
        s.last_row_s = lambda t_end_s: np.inf

    full = _session(*throw, patch=every_time)
    assert lazy.text == full.text
    assert lazy.closings_computed < full.closings_computed / 3, (
        lazy.closings_computed, full.closings_computed)


def _reach_log(s):
    """Record each re-plan's (observation time, intercept out of reach) in ``s.reach_log``."""
    s.reach_log = []
    inner = s._search.next

    def logged(flight, t_s, prev, t_i):
        ic = inner(flight, t_s, prev, t_i)
        s.reach_log.append((t_s, ic.reason is not None))
        return ic

    s._search.next = logged


def test_out_of_reach_searched_again_every_retry_interval(monkeypatch):
    """While the estimate is out of reach the whole-path search runs once per
    ``REACH_RETRY_S`` of observations, not at each: an estimate that comes back in reach
    is planned at most that much later than searching at every observation, and the throw
    is caught as well."""
    import planner.catch.live.search as sm
    import planner.catch.plan.intercept as ic_mod

    throw = (45.48, 2.22, -0.19, 0.005, 500.0)  # out of reach at its first estimates
    searches = []
    full = ic_mod.find_intercept

    def counted(*a, **k):
        searches.append(1)
        return full(*a, **k)

    monkeypatch.setattr(ic_mod, "find_intercept", counted)
    kept = _session(*throw, seed=1, patch=_reach_log)
    n_kept = len(searches)
    retry_s = sm.REACH_RETRY_S
    monkeypatch.setattr(sm, "REACH_RETRY_S", 0.0)  # searched at every observation
    every = _session(*throw, seed=1, patch=_reach_log)
    n_every = len(searches) - n_kept
    assert any(out for _, out in every.reach_log), "the throw's first estimates are in reach"
    assert n_kept < n_every
    # back in reach for good: the re-plan after the last one out of reach
    back = [s.reach_log[max(i for i, (_, out) in enumerate(s.reach_log) if out) + 1][0]
            for s in (kept, every)]
    assert back[1] <= back[0] <= back[1] + retry_s + 1e-9, back
    assert kept.outcome == every.outcome, (kept.reason, every.reason)  # (held: item 3)


@pytest.mark.parametrize("throw", THROWS)
def test_first_rows_formatted_ahead_are_the_same_file(throw):
    """The rest rows up to the reaction time of each observation before the first fit are
    formatted at that observation (before the file exists) and written with the first
    plan's: the same file as formatting all of them at the first plan."""
    ahead = _session(*throw)
    skipped = []

    def no_ahead(s):
        inner = s._format

        def fmt(t_end_s, t_b=-math.inf, old_seg=None):
            if s.writer is None:  # the observation before the first fit
                skipped.append(t_end_s)
                return None
            return inner(t_end_s, t_b, old_seg)

        s._format = fmt

    full = _session(*throw, patch=no_ahead)
    assert len(skipped) == full.fit.min_obs - 1 and ahead.text == full.text


def test_first_plan_returns_every_row_from_zero():
    """The first plan's observation returns the rows formatted ahead with its own: every
    row from t = 0, as the file holds them; the observation before writes none."""
    fl = predict_throw(30.0, 1.5, 0.0, BALL, drag=True)
    s = CatchSession(1.5, 0.0, ball=BALL, drag=True, planner=get_planner("default"))
    rng = np.random.default_rng(3)
    k, rows, ahead = 0, np.empty((0, 0)), []
    while s.writer is None:
        k += 1
        ahead.append(sum(len(c.t) for c in s._ahead))
        rows = s.observe(k / 100, fl.position(k / 100) + rng.normal(0.0, 0.005, 3))
    # rows 0..0.04 s formatted at the first observation (t + 30 ms), one more at each
    # until 0.08 s, then written with 0.09 and 0.10 (the first fit's t + 30 ms + 10 ms)
    assert ahead == [0, 5, 6, 7, 8, 9], ahead
    assert len(rows) == s.next_row == 11
    np.testing.assert_allclose(rows[:, 0], np.arange(11) * 0.01, atol=1e-9)

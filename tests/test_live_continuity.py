"""A live session's rows continue the rows written (planner.catch.live.stopper's
``ramp_passed``): a stopping motion whose ramp starts before the first row a re-plan can
change is never fixed as it is (the ramp's travel so far would be added to the next row at
once). The case: bench_live's throw that stopped it (tests/data/live_ramp_in_the_past.csv).
No wall-clock assertions."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.catch.flight.path import get_ball
from planner.catch.live.session import CatchSession
from planner.catch.live.stop import moves
from planner.catch.plan.api import get_planner
from planner.catch.plan.results import HELD
from planner.catch.plan.turnahead import rows_within_limits
from planner.check import check_trajectory
from planner.errors import SolverError
from planner.trajfile import parse_trajectory

DATA = Path(__file__).parent / "data" / "live_ramp_in_the_past.csv"
# bench_live's second throw of seed 0 (30.79 deg, with drag) to the catch point:
DIST_M, HEIGHT_M = 1.186424914749346, -0.07125224356962315


def _observations() -> np.ndarray:
    return np.loadtxt(DATA, delimiter=",", skiprows=1)


@pytest.fixture(scope="module")
def ramp_run():
    """The session fed the observations one at a time; per observation whether the stop is
    fixed, its ramp's start and the time of the last row written before it."""
    s = CatchSession(DIST_M, HEIGHT_M, ball=get_ball("tennis"), drag=True, rate_hz=100.0,
                     planner=get_planner("default"))
    steps = []
    for t, x, y, z in _observations():
        before = s.written_to_s
        s.observe(t, (x, y, z))
        sp = s.stopper
        steps.append((sp.fixed, moves(sp.stop), sp.stop.start_s if moves(sp.stop) else None,
                      before))
        if s.done:
            break
    return s, steps


def test_the_session_with_a_first_fit_past_the_ramp_runs_to_its_end(ramp_run):
    """Its first fit (6 observations, 10 mm of noise) puts the intercept 33 ms before the
    launch, the table's ramp 96 ms before it: the session runs on (the guard refused its 9th
    observation's rows at 29 rad/s of wrist flexion, 8 allowed) to the observation that acts
    after the intercept, with its end marker, and every row within every limit of the hand."""
    s, _ = ramp_run
    assert s.done and s.outcome is not None
    tr = parse_trajectory(s.text)
    assert tr.end["catch"] == s.outcome
    assert rows_within_limits(s.pl.hand, tr.t_s, tr.q)
    rep = check_trajectory(tr)
    assert rep.limits and all(lc.ok for lc in rep.limits), [lc for lc in rep.limits if not lc.ok]
    # (10 mm of noise: the palm misses this ball by 17 mm, named as the session's give-up)
    assert s.outcome == HELD or "misses" in s.reason


def test_a_stop_is_fixed_only_with_its_ramp_after_the_rows_written(ramp_run):
    """When the stop becomes fixed, its ramp starts no earlier than the last row written
    before that observation: the rows written never had the ramp's travel, and the new ones
    start it from rest."""
    s, steps = ramp_run
    fixed_at = [k for k, (fixed, *_) in enumerate(steps) if fixed]
    assert fixed_at, "the stop was never fixed"
    _, moving, start_s, written_before = steps[fixed_at[0]]
    assert moving and start_s >= written_before
    # ... while the first fit (its intercept, hence the table's ramp, in the past) left it
    # not fixed: fixed then, it was what the guard refused three observations later
    assert fixed_at[0] > s.fit.min_obs - 1


def test_cli_live_guard_refusal_is_one_line(tmp_path, monkeypatch, capsys):
    """``catch --live`` whose rows the guard refuses: one line on stderr ("failed: planner
    bug ..."), exit 1 (the command line's map: 2 is bad input), no traceback, the file left
    without its end marker."""
    import planner.trajfile as tf
    from planner.cli import main

    def refuse(hand, q, last_q, dt):
        raise SolverError("planner bug: wrist_flex speed 29.1361 above 8.0000")

    monkeypatch.setattr(tf, "guard_rows", refuse)
    monkeypatch.setattr(sys, "stdin", io.StringIO(DATA.read_text()))
    out = tmp_path / "live.csv"
    rc = main(["catch", "--live", "--drag", "--dist", repr(DIST_M), f"--height={HEIGHT_M!r}",
               "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 1
    assert err.splitlines() == ["failed: planner bug: wrist_flex speed 29.1361 above 8.0000"]
    assert '"end": true' not in out.read_text()

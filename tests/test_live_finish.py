"""The live session's last observation (``LiveEnding.finish``): the rows the hardware needs
next (up to the ending observation's reach, as every observation's) are written before the
wrist's turn and the rest of the plan are computed, where no turn can start among them; the
file is the one the whole plan written at once makes. No wall-clock assertions."""

from __future__ import annotations

import numpy as np

import planner.catch.live.ending as live_ending
from planner.catch.flight.path import get_ball, predict_throw
from planner.catch.live.ending import LiveEnding
from planner.catch.live.session import CatchSession
from planner.catch.plan.api import get_planner
from planner.catch.plan.planner import PLAN_BUDGET_S, SIGNAL_S
from planner.trajfile import parse_trajectory

RATE_HZ = 100.0


def _run(monkeypatch, split: bool):
    """A 30 deg / 1.5 m throw seen at 100 Hz with 2 mm noise: the session, the rows each
    observation returned, the ending observation's time, and the rows written when the
    turn was computed (``live_turn`` spied)."""
    ball = get_ball("tennis")
    s = CatchSession(1.5, 0.0, ball=ball, drag=True, planner=get_planner("default"))
    at_turn: list[int] = []
    turn = live_ending.live_turn

    def spy(*a, **k):
        at_turn.append(s.next_row)
        return turn(*a, **k)

    monkeypatch.setattr(live_ending, "live_turn", spy)
    if not split:  # the whole rest of the plan written at once
        finish = LiveEnding.finish
        monkeypatch.setattr(LiveEnding, "finish", lambda self, why, near_s=0.0:
                            finish(self, why))
    fl = predict_throw(30.0, 1.5, 0.0, ball, drag=True)
    rng = np.random.default_rng(3)
    got, t = [], 0.0
    for k in range(1, 300):
        t = k / RATE_HZ
        rows = s.observe(t, fl.position(t) + rng.normal(0.0, 0.002, 3))
        if len(rows):
            got.append(rows)
        if s.done:
            break
    return s, got, t, at_turn


def test_the_ending_rows_are_written_before_the_turn(monkeypatch):
    s, got, t_end, at_turn = _run(monkeypatch, split=True)
    assert s.done and at_turn
    near_s = t_end + SIGNAL_S + PLAN_BUDGET_S + 1.0 / RATE_HZ  # the ending observation's reach
    n_near = int(np.floor(near_s / s.dt + 1e-9)) + 1  # rows up to it
    assert at_turn[0] >= n_near  # written before the turn was computed
    tr = parse_trajectory(s.text)
    file_rows = np.column_stack([tr.t_s, tr.q, tr.q_motor])
    assert np.array_equal(np.concatenate(got), file_rows)  # returned as written, in order


def test_the_file_is_the_same_as_written_at_once(monkeypatch):
    split, _, _, _ = _run(monkeypatch, split=True)
    monkeypatch.undo()
    whole, _, _, at_turn = _run(monkeypatch, split=False)
    assert whole.text == split.text
    assert at_turn[0] < split.next_row  # (the whole plan: nothing written before the turn)


def _session_text(monkeypatch, ahead: bool):
    """The file of ``_run``'s throw, with the wrist's turn computed ahead (``HeldTurn``) or
    only at the end; and whether the end's turn was the one computed ahead."""
    used: list[bool] = []
    turn = live_ending.live_turn

    def spy(*a, **k):
        used.append(len(a) > 4 and a[4] is not None or k.get("hold") is not None)
        return turn(*a, **k)

    monkeypatch.setattr(live_ending, "live_turn", spy)
    if not ahead:
        monkeypatch.setattr(LiveEnding, "warm", lambda self: None)
    s, _, _, _ = _run(monkeypatch, split=True)
    monkeypatch.undo()
    return s.text, used


def test_the_turn_computed_ahead_is_the_same_file(monkeypatch):
    ahead, used = _session_text(monkeypatch, ahead=True)
    at_end, used_at_end = _session_text(monkeypatch, ahead=False)
    assert ahead == at_end
    assert used == [True] and used_at_end == [False]

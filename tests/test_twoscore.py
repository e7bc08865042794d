"""The check's frame F1 of a pair's rows (``planner.play.twoscore``): the score
``plan_two_hands`` keeps its way by is the one ``check`` finds in the file written."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.hand.model import load_hand
from planner.music.midi import load_song
from planner.play.twohands import PairPlanner, plan_two_hands
from tests.test_twohands import meeting_song


def test_frame_f1_is_the_checks_f1_of_the_file_written(tmp_path) -> None:
    pair = PairPlanner(load_hand("default-left"), load_hand("default"))
    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    out = tmp_path / "meet.csv"
    plan = plan_two_hands(song, pair, str(out))
    f1 = pair.scorer.frame_f1(plan.rows, song, 100.0)
    rep = check_trajectory(str(out), song)
    # (the file's rows are rounded to its decimals: the same keys down but at a row or so)
    assert 0.5 < f1 and f1 == pytest.approx(rep.play.f1, abs=2e-3)
    # (both hands' keys count: the right hand held at its first row all song scores less)
    q_left, q_right = plan.rows.q
    still = replace(plan.rows, q=(q_left, np.repeat(q_right[:1], len(q_right), axis=0)))
    assert pair.scorer.frame_f1(still, song, 100.0) < f1 - 0.05  # (0.849 against 0.960)


def test_plans_f1_is_the_frame_f1_of_the_plans_on_one_clock(tmp_path) -> None:
    from planner.play.hands import RIGHT
    from planner.play.stream import plan_song
    from planner.play.twoplan import PlanReads, clock_of, one_clock

    pair = PairPlanner(load_hand("default-left"), load_hand("default"))
    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    plan = plan_two_hands(song, pair, None)
    left, right = plan.plans
    # (another right plan: its part alone, unbounded: another length and way in, so the
    # clock pads the plans otherwise)
    sub = replace(song, notes=tuple(song.notes[i] for i in plan.notes_of[1]), part=None)
    other = plan_song(sub, pair.hands[RIGHT], None, planner=pair.planners[RIGHT])
    reads = PlanReads()
    clocks = []
    for plans in ((left, right), (left, other)):
        want = pair.scorer.frame_f1(one_clock(plans, 100.0), song, 100.0)
        assert pair.scorer.plans_f1(plans, song, 100.0, reads) == want
        assert pair.scorer.plans_f1(plans, song, 100.0, reads) == want  # (its keys kept)
        rows = tuple(len(reads(p).t_s) for p in plans)
        clocks.append(clock_of(plans, rows, 100.0).n - min(rows))
    assert max(clocks) > 0  # (a plan padded on the clock)
    pair.scorer.clear()
    assert pair.scorer.plans_f1((left, other), song, 100.0, reads) == pair.scorer.frame_f1(
        one_clock((left, other), 100.0), song, 100.0)


def test_a_plan_made_again_to_the_same_text_shares_its_twins_rows_and_keys(tmp_path,
                                                                            monkeypatch
                                                                            ) -> None:
    from planner.play import twoscore
    from planner.play.twoplan import PlanReads, held_twin, one_clock

    pair = PairPlanner(load_hand("default-left"), load_hand("default"))
    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    plan = plan_two_hands(song, pair, None)
    left, right = plan.plans
    # (the right hand planned again to the same rows: another plan, the same text; and a
    # plan of other rows: the left's)
    twin = replace(right, planning_s=right.planning_s + 1.0)
    assert twin is not right and twin.text == right.text
    reads = PlanReads()
    tr = reads(right)
    assert reads(twin) is tr and len(reads) == 2  # (read once for both)
    assert reads(left) is not tr
    assert held_twin({id(left): (left, 0)}, twin) is None
    assert held_twin({id(right): (right, 1)}, twin) == (right, 1)
    found = []
    keys = twoscore.body_keys
    monkeypatch.setattr(twoscore, "body_keys", lambda *a: found.append(1) or keys(*a))
    f1 = pair.scorer.plans_f1((left, right), song, 100.0, reads)
    assert len(found) == 2  # (each hand's keys found on its rows)
    assert pair.scorer.plans_f1((left, twin), song, 100.0, reads) == f1
    assert len(found) == 2  # (the twin's keys are its text's: found once)
    found.clear()
    assert f1 == pair.scorer.frame_f1(one_clock((left, twin), 100.0), song, 100.0)
    assert len(found) == 2  # (the same number found anew on both hands' rows)
    found.clear()
    other = replace(right, text=left.text)  # (the right hand with other rows: found anew)
    pair.scorer.plans_f1((left, other), song, 100.0, reads)
    assert len(found) == 1

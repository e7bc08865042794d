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

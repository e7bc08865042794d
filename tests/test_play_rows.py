"""Rows a controller can run (issue 30, item 4): every sample song, planned on the default
hand, has every joint's jerk within its bound and no row within a joint's stop margin,
by the check's categories and by the rows' own third differences."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.check.limits import FILE_QUANTUM, RATE_TOL
from planner.hand.model import load_hand
from planner.music.midi import load_song
from planner.play import Planner, plan_song
from planner.trajfile import read_trajectory

ROOT = Path(__file__).resolve().parents[1]
SONGS = sorted(p.name for p in (ROOT / "songs").glob("*.mid"))


@pytest.fixture(scope="module")
def planner():
    return Planner(load_hand("default"))


def test_there_are_sample_songs():
    assert len(SONGS) >= 7


@pytest.mark.parametrize("name", SONGS)
def test_sample_song_rows_within_jerk_and_off_the_stops(planner, tmp_path, name):
    song, path = ROOT / "songs" / name, tmp_path / "o.csv"
    plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song), strict=False)
    by = {lc.category: lc for lc in rep.limits}
    assert by["joint_jerk"].count == 0 and by["joint_stop_margin"].count == 0, rep.summary()
    assert all(lc.count == 0 for lc in rep.limits), rep.summary()
    # the rows themselves: third differences within the bounds (1 % and the file's
    # rounding), every joint its margin off its stops (to the file's rounding)
    h = planner.hand
    tr = read_trajectory(str(path))
    dt = 1.0 / 100.0
    assert np.allclose(np.diff(tr.t_s), dt)
    jerk = np.abs(np.diff(tr.q, n=3, axis=0)) / dt ** 3
    assert np.all(jerk <= h.jerk * (1 + RATE_TOL) + 4 * FILE_QUANTUM / dt ** 3)
    assert np.all(tr.q >= h.plan_lower - FILE_QUANTUM) and np.all(tr.q <= h.plan_upper + FILE_QUANTUM)
    # moves are jerk-limited, not bang-bang: no joint's jerk above its bound's 0.995
    # (LIMIT_FRACTION) by more than the rounding, and some joint near it
    assert np.max(jerk / h.jerk) > 0.5

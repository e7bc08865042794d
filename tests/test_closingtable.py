"""planner.catch.plan.closingtable: the shipped closed poses are the solver's, bit for bit
(a changed hand, IK or closing fails here until ``scripts/make_closing.py`` is run); the
closing made from a shipped pose is the one made by solving it; a table made with other
parameters is not read."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from planner.balls import BALLS
from planner.catch.plan import closingtable
from planner.catch.plan.api import get_planner
from planner.catch.plan.closing import closed_pose, closing_from, make_closing
from planner.catch.plan.closingtable import key, save, shipped_closed_pose, table_path


@pytest.mark.parametrize("hand", ["default", "mk5"])
@pytest.mark.parametrize("bodies", [True, False])
def test_shipped_poses_are_the_solvers(hand, bodies):
    pl = get_planner(hand)
    for ball in ("tennis", "golf"):
        r = BALLS[ball].radius_m
        shipped = shipped_closed_pose(pl.hand, pl.joints, pl.wrist, r, bodies)
        assert shipped is not None, f"no shipped pose for {hand} / {ball}"
        solved = closed_pose(pl.hand, pl.ik, pl.joints, pl.wrist, r, bodies)
        assert np.array_equal(shipped, solved), np.max(np.abs(shipped - solved))


def test_the_closing_from_a_shipped_pose_is_the_solved_one():
    pl = get_planner("default")
    r = BALLS["tennis"].radius_m
    made = make_closing(pl.hand, pl.ik, pl.joints, pl.wrist, r)
    shipped = closing_from(pl.hand, pl.joints, pl.wrist, r,
                           shipped_closed_pose(pl.hand, pl.joints, pl.wrist, r, True))
    for f in dataclasses.fields(made):
        a, b = getattr(made, f.name), getattr(shipped, f.name)
        if isinstance(a, np.ndarray):
            assert np.array_equal(a, b), f.name
        else:
            assert a == b, f.name
    assert pl.closing(r).q_closed.tobytes() == made.q_closed.tobytes()


def test_a_ball_not_shipped_is_solved():
    pl = get_planner("default")
    assert shipped_closed_pose(pl.hand, pl.joints, pl.wrist, 0.05, True) is None


def test_a_table_of_other_parameters_is_not_read(tmp_path, monkeypatch):
    pl = get_planner("default")
    r = BALLS["tennis"].radius_m
    q = shipped_closed_pose(pl.hand, pl.joints, pl.wrist, r, True)
    path = tmp_path / table_path(pl.hand.urdf_sha256).name
    monkeypatch.setattr(closingtable, "TABLE_DIR", tmp_path)
    save(path, pl.hand, pl.joints, pl.wrist, {key(r, True): q + 0.25})
    got = shipped_closed_pose(pl.hand, pl.joints, pl.wrist, r, True)
    assert np.array_equal(got, q + 0.25)  # (the table at TABLE_DIR is the one read)
    monkeypatch.setattr(closingtable, "VERSION", closingtable.VERSION + 1)
    assert shipped_closed_pose(pl.hand, pl.joints, pl.wrist, r, True) is None

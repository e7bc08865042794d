"""The ball's roll along the palm as a feasibility rule (``planner.check.ballroll``): one
definition in the catch planner, the check and the physics replay's ball. No wall-clock
assertions."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from cli import main as cli_main
from planner.balls import BALLS, file_inertia_ratio, get_ball
from planner.catch.plan.api import plan_throw, write_plan
from planner.catch.plan.reasons import CatchReason
from planner.catch.plan.results import Rows
from planner.check import check_trajectory
from planner.check.ballroll import ROLL_ROOM_M, ROLL_TOL_M, roll_problem
from planner.trajfile import read_trajectory


def _rolled(pl, p) -> float:
    """The planner's model of the roll on the plan's rows."""
    return pl.turn.rolled(p.rows.t, p.rows.q, p.intercept.t_s, p.flight)


def test_the_rule_is_the_room():
    """A roll up to ``ROLL_ROOM_M`` is within the rule; beyond it (plus the check's
    tolerance for a file's rounding) it is the reason, with the roll in mm and the room."""
    assert roll_problem(0.0) is None and roll_problem(ROLL_ROOM_M) is None
    assert roll_problem(ROLL_ROOM_M + 0.5 * ROLL_TOL_M, ROLL_TOL_M) is None
    text = roll_problem(0.1613)
    assert text is not None and "161 mm" in text and "42 mm" in text
    assert roll_problem(ROLL_ROOM_M + 1e-6) is not None


def test_a_steep_short_throw_is_infeasible_for_its_roll(pl, tmp_path, capsys):
    """20 deg from 1.0 m lands on a palm 73 deg from level: the least rolling of the turns
    the wrist's motor gives (under way at 6.7 rad/s) leaves the ball rolling 104 mm towards
    the wrist by the model, beyond the 42 mm room: the plan is infeasible for the roll (it
    was planned and claimed before the rule, and was not held in physics). ``catch`` writes
    it and exits 0 (``--strict``: 1), as for every infeasible catch; ``check`` does not
    confirm it."""
    p = plan_throw(20.0, 1.0, 0.0, planner=pl)
    assert not p.feasible and p.reason_kinds == (CatchReason.ROLL,)
    rolled = _rolled(pl, p)
    assert rolled > 2 * ROLL_ROOM_M
    assert str(p.reasons[0]) == roll_problem(rolled)
    assert p.notes and p.notes[0].startswith("the wrist's turn under way at 6.7 rad/s")
    out = tmp_path / "c.csv"
    argv = ["catch", "--angle", "20", "--dist", "1", "-o", str(out), "--json"]
    assert cli_main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["feasible"] is False and d["reasons"] == [str(p.reasons[0])]
    assert read_trajectory(str(out)).metadata["catch"]["feasible"] is False
    assert cli_main([*argv, "--strict"]) == 1
    rep = check_trajectory(str(out))
    assert not rep.ok and roll_problem(rep.catch.roll_m, ROLL_TOL_M) in rep.problems
    assert rep.catch.roll_m == pytest.approx(rolled, abs=ROLL_TOL_M)


@pytest.mark.parametrize("throw", [(30.0, 1.5), (60.0, 1.0), (15.0, 1.5)])
def test_the_check_confirms_the_planners_feasible_catches(pl, tmp_path, throw):
    """Feasible plans pass the rule in the check as in the planner, with the same roll on the
    written rows: 30 deg / 1.5 m (the turn from the grasp), 60 deg / 1.0 m (the default
    grid's largest roll, 37 mm), 15 deg / 1.5 m (the turn under way when the ball lands)."""
    p = plan_throw(*throw, 0.0, planner=pl)
    assert p.feasible, p.reasons
    path = tmp_path / "c.csv"
    write_plan(p, str(path))
    rep = check_trajectory(str(path))
    assert rep.ok, rep.problems
    assert rep.catch.roll_m == pytest.approx(_rolled(pl, p), abs=ROLL_TOL_M)
    assert rep.catch.roll_m <= ROLL_ROOM_M


def test_the_check_rejects_a_palm_that_does_not_turn(pl, tmp_path):
    """30 deg from 1.5 m edited so that the wrist's flexion stays where it is at the
    intercept (the palm 51 deg from level, not turned up): the check's model lets the ball
    roll beyond the room -- that catch is not confirmed, the same roll as the planner's
    model on the edited rows."""
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    i = pl.joints.i_flex
    Q = p.rows.q.copy()
    k = int(np.searchsorted(p.rows.t, p.intercept.t_s))
    Q[k:, i] = Q[k, i]
    edited = replace(p, rows=Rows(p.rows.t, Q, p.hand.motor_angles(Q)))
    path = tmp_path / "still.csv"
    write_plan(edited, str(path))
    rep = check_trajectory(str(path))
    rolled = _rolled(pl, edited)
    assert rolled > ROLL_ROOM_M
    assert not rep.ok and roll_problem(rep.catch.roll_m, ROLL_TOL_M) in rep.problems
    assert rep.catch.roll_m == pytest.approx(rolled, abs=ROLL_TOL_M)


def test_a_files_ball_has_the_planners_inertia(pl):
    """The file's ``ball`` (spec section 4) has no inertia: the named ball's, when its
    radius and mass are the file's, else the default ball's."""
    for name in ("tennis", "baseball"):
        meta = plan_throw(40.0, 2.0, 0.0, planner=pl, ball=name).metadata()
        assert file_inertia_ratio(meta) == BALLS[name].inertia_ratio
    assert BALLS["baseball"].inertia_ratio == 0.4 and BALLS["tennis"].inertia_ratio == 0.61
    meta = plan_throw(40.0, 2.0, 0.0, planner=pl, ball="baseball").metadata()
    meta["ball"] = {**meta["ball"], "mass": 0.2}  # not the baseball any more
    assert file_inertia_ratio(meta) == get_ball(None).inertia_ratio
    assert file_inertia_ratio({"ball": meta["ball"]}) == get_ball(None).inertia_ratio


def test_the_physics_ball_has_the_planners_inertia(pl, tmp_path):
    """The physics replay's ball: the file's mass, and I = ratio m R^2 (a tennis ball's
    0.61, not MuJoCo's solid sphere's 0.4)."""
    pytest.importorskip("mujoco")
    from planner.simulate import run_replay

    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    path = tmp_path / "c.csv"
    write_plan(p, str(path))
    r = run_replay(str(path))
    m, b = r.scene.model, r.scene.ball_body
    ball = BALLS["tennis"]
    assert m.body_mass[b] == pytest.approx(ball.mass_kg)
    expect = ball.inertia_ratio * ball.mass_kg * ball.radius_m ** 2
    assert np.allclose(m.body_inertia[b], expect, rtol=1e-6)


def test_the_rule_judges_only_the_hands_it_is_measured_on(tmp_path):
    """The room is the default hand's (the replay lost the ball beyond it); on mk5 the
    modelled roll of 30 deg / 1.5 m exceeds it and the plan is held in physics, so mk5's
    roll is reported, not judged: the plan is feasible and ``check`` confirms it."""
    from planner.catch.plan.api import plan_catch
    from planner.check.ballroll import roll_judged

    assert roll_judged("default") and not roll_judged("mk5") and not roll_judged(None)
    out = tmp_path / "m.csv"
    p = plan_catch(30.0, 1.5, 0.0, "mk5", str(out))
    assert p.feasible, p.reasons
    rep = check_trajectory(str(out))
    assert rep.ok, rep.problems
    assert rep.catch.roll_m > ROLL_ROOM_M  # reported: 57 mm

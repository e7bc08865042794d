"""A catch file's claims (spec section 4, version 2) are judged, never obeyed: every catch
rule applies to every file, planned or live; the ball is the metadata's, a live file's last
estimate is a claim judged by the same rules; an infeasible plan says so in its end marker
(issue 31, item 2)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from cli import main as cli_main
from planner.catch import get_planner, plan_throw, write_plan
from planner.catch.plan.results import Rows
from planner.check import check_trajectory
from planner.check.ballroll import ROLL_ROOM_M, ROLL_TOL_M, roll_problem
from planner.errors import InputError
from planner.trajfile import read_trajectory

HELD_CLAIM = "the end marker claims the catch held; the rows above say otherwise"


@pytest.fixture(scope="module")
def still_plan(pl):
    """30 deg from 1.5 m with the wrist's flexion held where it is at the intercept: the
    palm is not turned up and the ball rolls off its wrist side (the planner's model)."""
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    assert p.feasible, p.reasons
    Q = p.rows.q.copy()
    k = int(np.searchsorted(p.rows.t, p.intercept.t_s))
    Q[k:, pl.joints.i_flex] = Q[k, pl.joints.i_flex]
    edited = replace(p, rows=Rows(p.rows.t, Q, p.hand.motor_angles(Q)))
    assert pl.turn.rolled(edited.rows.t, Q, p.intercept.t_s, p.flight) > ROLL_ROOM_M
    return edited


def _split(path) -> tuple[dict, str, dict]:
    lines = path.read_text().splitlines(keepends=True)
    return json.loads(lines[0][2:]), "".join(lines[1:-1]), json.loads(lines[-1][2:])


def _write(path, meta: dict, body: str, end: dict) -> None:
    path.write_text("# " + json.dumps(meta) + "\n" + body + "# " + json.dumps(end) + "\n")


def test_the_forged_live_marker_is_rejected(still_plan, tmp_path):
    """``catch_forged_live_marker.csv`` made afresh: a planned file that fails the roll rule,
    its end marker given the live session's ``ball``, ``intercept_t`` and ``"catch":
    "held"``: still rejected by the roll rule (the marker switches no rule off), and the
    claim named."""
    path = tmp_path / "planned.csv"
    write_plan(still_plan, str(path))
    rep = check_trajectory(str(path))
    rolled = roll_problem(rep.catch.roll_m, ROLL_TOL_M)
    assert rep.catch.roll_m > ROLL_ROOM_M and rolled in rep.problems
    meta, body, end = _split(path)
    assert meta["version"] == 2 and end["catch"] == "held"  # (the edit kept the plan's claim)
    forged = tmp_path / "forged.csv"
    _write(forged, meta, body, dict(end, ball=meta["ball"], intercept_t=meta["intercept_t"]))
    rep2 = check_trajectory(str(forged))
    assert not rep2.ok and rolled in rep2.problems and HELD_CLAIM in rep2.problems
    assert rep2.catch.roll_m == rep.catch.roll_m
    assert cli_main(["check", str(forged)]) == 1


def test_a_planned_files_ball_is_its_metadatas(pl, tmp_path):
    """A planned file whose end marker names another ball (one its rows would meet) is
    judged against the metadata's, and the other ball refused."""
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    path = tmp_path / "c.csv"
    write_plan(p, str(path))
    assert check_trajectory(str(path)).ok
    meta, body, end = _split(path)
    other = dict(meta["ball"], v0=[v * 1.05 for v in meta["ball"]["v0"]])
    _write(path, meta, body, dict(end, ball=other, intercept_t=meta["intercept_t"]))
    rep = check_trajectory(str(path))
    assert not rep.ok
    assert rep.catch.ball_at_intercept == pytest.approx(
        check_trajectory(str(tmp_path / "c.csv")).catch.ball_at_intercept)
    assert any("other than the metadata's" in x for x in rep.problems)


def test_a_live_file_with_a_roll_beyond_the_palm_is_rejected(still_plan, tmp_path):
    """The same rows as a live session's file (``catch.live``, its last estimate in the end
    marker, "held"): the roll rule applies to it as to any file."""
    path = tmp_path / "planned.csv"
    write_plan(still_plan, str(path))
    meta, body, end = _split(path)
    meta["catch"] = {"live": True, "throw": meta["catch"]["throw"],
                     "catch_point": meta["catch"]["catch_point"],
                     "stop_distance_m": meta["catch"]["stop_distance_m"], "observations": 40}
    live = tmp_path / "live.csv"
    _write(live, meta, body, {"end": True, "rows": end["rows"], "catch": "held",
                              "reason": "grasp", "ball": meta["ball"],
                              "intercept_t": meta["intercept_t"]})
    rep = check_trajectory(str(live))
    assert rep.catch.live == {"catch": "held", "reason": "grasp"}
    assert rep.catch.roll_m > ROLL_ROOM_M
    assert roll_problem(rep.catch.roll_m, ROLL_TOL_M) in rep.problems and HELD_CLAIM in rep.problems


def test_a_live_files_last_estimate_is_the_ball_judged(still_plan, tmp_path):
    """A live file's end-marker ball (its last estimate) is what the rows are judged
    against: moved 5 cm, the palm misses it."""
    path = tmp_path / "planned.csv"
    p = plan_throw(30.0, 1.5, 0.0, planner=get_planner("default"))
    write_plan(p, str(path))
    meta, body, end = _split(path)
    meta["catch"] = {"live": True, "stop_distance_m": meta["catch"]["stop_distance_m"]}
    ok = tmp_path / "ok.csv"
    _write(ok, meta, body, {"end": True, "rows": end["rows"], "catch": "held",
                            "ball": meta["ball"], "intercept_t": meta["intercept_t"]})
    assert check_trajectory(str(ok)).ok
    moved = dict(meta["ball"], p0=[meta["ball"]["p0"][0], 0.05, meta["ball"]["p0"][2]])
    bad = tmp_path / "bad.csv"
    _write(bad, meta, body, {"end": True, "rows": end["rows"], "catch": "held",
                             "ball": moved, "intercept_t": meta["intercept_t"]})
    rep = check_trajectory(str(bad))
    assert not rep.ok and rep.catch.intercept_error_m > 0.04


def test_an_infeasible_catch_says_so_in_its_end_marker(tmp_path):
    """20 deg from 1.0 m (the roll rule's): the end marker says ``"catch": "infeasible"``
    with the plan's reasons; exit 0, 1 with ``--strict``; ``check`` names the claim."""
    out = tmp_path / "f.csv"
    argv = ["catch", "--angle", "20", "--dist", "1.0", "-o", str(out)]
    assert cli_main(argv) == 0
    tr = read_trajectory(str(out))
    assert tr.metadata["version"] == 2 and tr.end["catch"] == "infeasible"
    assert tr.end["reason"] == "; ".join(tr.metadata["catch"]["reasons"])
    assert tr.end["reason_kinds"] == ["roll"]
    assert cli_main([*argv, "--strict"]) == 1
    rep = check_trajectory(str(out))
    assert not rep.ok and f"the plan says the catch is infeasible: {tr.end['reason']}" \
        in rep.problems


@pytest.mark.parametrize("end", [{"catch": "maybe"}, {"catch": "held", "reason": 3},
                                 {"ball": {"p0": [0, 0, 0]}, "intercept_t": 0.4},
                                 {"intercept_t": 0.4}])
def test_a_claim_of_the_wrong_type_is_refused(pl, tmp_path, end):
    path = tmp_path / "c.csv"
    write_plan(plan_throw(30.0, 1.5, 0.0, planner=pl), str(path))
    meta, body, old = _split(path)
    _write(path, meta, body, {"end": True, "rows": old["rows"], **end})
    with pytest.raises(InputError):
        check_trajectory(str(path))


def test_versions_read(pl, tmp_path):
    path = tmp_path / "c.csv"
    write_plan(plan_throw(30.0, 1.5, 0.0, planner=pl), str(path))
    meta, body, end = _split(path)
    for v, ok in ((1, True), (2, True), (3, False), (True, False)):
        _write(path, dict(meta, version=v), body, end)
        if ok:
            assert read_trajectory(str(path)).metadata["version"] == v
        else:
            with pytest.raises(InputError):
                read_trajectory(str(path))

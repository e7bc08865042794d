"""``simulate`` of a two-hand file (``planner.simulate.pair``): one scene with both hands,
each colliding with the keys and the other hand; scores per hand and together."""

from __future__ import annotations

import json

import pytest

from planner.simulate import run_replay
from planner.simulate.pairreport import PairSimulateReport
from tests.hardening import run_cli
from tests.pairbuild import notes_of, plan_pair, write_unguarded

pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("simpair")
    return plan_pair(tmp, notes_of([48, 52, 55, 52]), notes_of([72, 76, 79, 84]))


def test_two_hands_apart_in_physics(pair, capsys) -> None:
    """Both hands' notes sound in the one scene, no contact between them; each hand's
    motors and joints named by its prefix."""
    replay = run_replay(str(pair.path), str(pair.song))
    rep = replay.report
    assert isinstance(rep, PairSimulateReport) and rep.ok, rep.summary()
    assert rep.play.notes_hit == rep.play.notes == 8 and not rep.play.wrong_keys
    assert rep.kinematic_f1 == pytest.approx(1.0)
    assert not rep.touches and not replay.record.hand_contacts
    for h, pre in zip(rep.hands, ("left.", "right.")):
        assert h.prefix == pre and h.notes == h.notes_hit == 4 and h.wrong_keys == 0
        assert all(m.name.startswith(f"motor.{pre}") for m in h.motors)
        assert h.tracking[0].name == pre + "rail"
    assert {f.split(".")[0] for e in rep.play.played for f in e.fingers} == {"left", "right"}
    rc, out, _ = run_cli(capsys, "simulate", pair.path, pair.song, "--json")
    d = json.loads(out)
    assert rc == 0 and d["ok"] and [h["prefix"] for h in d["hands"]] == ["left.", "right."]


def test_hands_that_touch_in_physics_collide(pair, tmp_path) -> None:
    """The left hand driven into the right one's place: their geoms touch (a contact
    between the hands, counted and named), the replay fails."""
    ql, qr = (x.copy() for x in pair.q)
    ql[:, 0] = qr[:, 0] - 0.10  # (its carriage 100 mm left of the right one's)
    path = write_unguarded(tmp_path / "touch.csv", pair, ql, qr)
    rep = run_replay(str(path), str(pair.song)).report
    assert not rep.ok and rep.touches
    t = rep.touches[0]
    assert t.left_geom.startswith("left.") and t.right_geom.startswith("right.")
    assert any("contacts between the hands in physics" in p for p in rep.problems)

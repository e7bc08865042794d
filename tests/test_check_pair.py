"""``check`` of a two-hand file (``planner.check.pair``): each hand by its own model, the
keys of both by one rule against the whole song, its claims per hand, and the least
distance between the hands (``planner.check.handgap``)."""

from __future__ import annotations

import json

import coal
import numpy as np
import pytest

from planner.check import check_trajectory
from planner.check.criteria import HANDS_GAP_M
from planner.check.handgap import GapJudge
from planner.check.kinematics import Kinematics
from planner.check.pairreport import PairReport
from planner.hand.bodies import BOX, CAPSULE, body_links, collision_bodies
from planner.hand.model import load_hand
from planner.planfile import read_plan
from tests.hardening import run_cli
from tests.pairbuild import notes_of, plan_pair, write_unguarded

BASS = [48, 50, 52, 53, 55, 53, 52]  # C3..G3: the left hand, around x = -0.2 m
MELODY = [72, 74, 76, 77, 79, 81, 79, 77, 76]  # C5..A5: the right hand, around x = +0.2 m


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pair")
    return plan_pair(tmp, notes_of(BASS, step_s=0.5), notes_of(MELODY, step_s=0.35))


def test_two_hands_apart_play_their_song(pair, capsys) -> None:
    """Two parts planned apart: every note hit by the hand that claims it, no collision;
    the file read as a stream and read whole give the same report."""
    rep = check_trajectory(str(pair.path), str(pair.song))
    assert isinstance(rep, PairReport) and rep.ok, rep.summary()
    assert rep.play.notes == len(BASS) + len(MELODY) and rep.play.notes_hit == rep.play.notes
    assert rep.play.f1 > 0.95 and not rep.play.wrong_presses
    assert {f.split(".")[0] for e in rep.play.played for f in e.fingers} == {"left", "right"}
    for p, r, n in zip(("left.", "right."), rep.hands, (len(BASS), len(MELODY))):
        assert r.play.notes == n == len(pair.by_hand[p]) and r.play.notes_hit == n
        assert r.hand == ("default-left" if p == "left." else "default")
        assert all(lc.ok for lc in r.limits)
    assert rep.gap.ok and rep.gap.least_m > HANDS_GAP_M
    assert rep.gap.left_body.startswith("left.") and rep.gap.right_body.startswith("right.")
    streamed = check_trajectory(str(pair.path), str(pair.song), replay=False)
    assert streamed.to_dict() == rep.to_dict()
    rc, out, _ = run_cli(capsys, "check", pair.path, pair.song, "--json")
    d = json.loads(out)
    assert rc == 0 and d["ok"] and [h["prefix"] for h in d["hands"]] == ["left.", "right."]
    assert d["hands"][0]["play"]["notes"] == len(BASS) and d["gap"]["collisions"] == []
    rc, out, _ = run_cli(capsys, "check", pair.path, pair.song)
    assert rc == 0 and "between the hands: least distance" in out and "hand right. default" in out


def test_hands_that_come_too_close_collide(pair, tmp_path, capsys) -> None:
    """The left hand moved along the rail into the right one's place: collisions
    counted and named (the two bodies, the distance); the check fails."""
    ql, qr = (x.copy() for x in pair.q)
    ql[:, 0] += 0.45  # (its rail: from the bass to the melody's keys)
    path = write_unguarded(tmp_path / "close.csv", pair, ql, qr)
    rep = check_trajectory(str(path), str(pair.song))
    assert not rep.ok and rep.gap.collisions and rep.gap.least_m < HANDS_GAP_M
    c = rep.gap.collisions[0]
    assert c.left_body.startswith("left.") and c.right_body.startswith("right.")
    assert c.rows >= 1 and c.end_s > c.start_s
    assert rep.gap.collision_rows == sum(x.rows for x in rep.gap.collisions)
    assert any("collisions between the hands" in p for p in rep.problems)
    rc, out, err = run_cli(capsys, "check", path, pair.song)
    assert rc == 1 and "collisions between the hands (" in out and not err


def _brute_least(kins, bodies, q_left, q_right) -> float:
    """The least distance between every body of one hand and every body of the other,
    each pair measured (no bound): Coal's distance of the shapes as placed."""
    def shapes(kin, bs, q):
        poses = kin.link_poses(q[None], body_links(bs))
        out = []
        for b in bs:
            T = poses[b.link][0]
            p0, p1 = (T[:3, :3] @ np.asarray(p) + T[:3, 3] for p in (b.p0_m, b.p1_m))
            if b.kind == BOX:
                out.append((coal.Box(*(2 * np.asarray(b.half_m))), T[:3, :3], p0))
            elif b.kind == CAPSULE:
                z = (p1 - p0) / np.linalg.norm(p1 - p0)
                x = np.cross([0.0, 1.0, 0.0] if abs(z[0]) > 0.9 else [1.0, 0.0, 0.0], z)
                x /= np.linalg.norm(x)
                R = np.column_stack([x, np.cross(z, x), z])
                out.append((coal.Capsule(b.radius_m, b.length_m), R, 0.5 * (p0 + p1)))
            else:
                out.append((coal.Sphere(b.radius_m), np.eye(3), p0))
        return out

    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    best = np.inf
    for sa, Ra, pa in shapes(kins[0], bodies[0], q_left):
        for sb, Rb, pb in shapes(kins[1], bodies[1], q_right):
            best = min(best, coal.distance(sa, coal.Transform3s(Ra, pa), sb,
                                           coal.Transform3s(Rb, pb), req, coal.DistanceResult()))
    return best


def test_the_gap_is_the_least_over_every_pair_of_bodies(pair) -> None:
    """Each row's least distance, found behind the bounds, is the least over every pair
    of bodies measured one by one: hands apart, near and overlapping."""
    plan = read_plan(str(pair.path))
    kins = tuple(Kinematics(p.hand, p.T_world_root) for p in plan.hands)
    bodies = tuple(collision_bodies(p.hand.spec) for p in plan.hands)
    ql, qr = pair.q
    rows = np.linspace(0, len(ql) - 1, 5).astype(int)
    for shift in (0.0, 0.3, 0.38, 0.45):
        for k in rows:
            a = ql[k:k + 1].copy()
            a[:, 0] += shift
            judge = GapJudge(kins, bodies, plan.pair.prefixes)
            judge.add(pair.t_s[k:k + 1], a, qr[k:k + 1])
            got = judge.finish(1.0)
            want = _brute_least(kins, bodies, a[0], qr[k])
            assert got.least_m == pytest.approx(want, abs=1e-9), (shift, k)
            assert bool(got.collisions) == (want < HANDS_GAP_M)


def test_hits_only_finds_the_same_collisions(pair) -> None:
    """The planner's confirmation (``hits_only``: a row measured to its first pair under
    the limit, no least distance sought) finds the collisions the exact judge finds:
    the same runs, rows and times, with the left hand swept along the rail into the
    right one and back."""
    plan = read_plan(str(pair.path))
    kins = tuple(Kinematics(p.hand, p.T_world_root) for p in plan.hands)
    bodies = tuple(collision_bodies(p.hand.spec) for p in plan.hands)
    ql, qr = pair.q
    n = len(ql)
    a = ql.copy()
    a[:, 0] += 0.5 * np.sin(np.linspace(0.0, 2.0 * np.pi, n)) ** 2  # (to 0.5 m and back)
    runs = []
    for hits_only in (False, True):
        judge = GapJudge(kins, bodies, plan.pair.prefixes, hits_only=hits_only)
        for b in range(0, n, 97):  # (blocks: a run carried across them)
            judge.add(pair.t_s[b:b + 97], a[b:b + 97], qr[b:b + 97])
        got = judge.finish(float(pair.t_s[-1]) + 0.01)
        runs.append([(c.start_s, c.row, c.end_s, c.rows) for c in got.collisions])
        assert all(c.least_m < HANDS_GAP_M for c in got.collisions)
    assert runs[0] and runs[1] == runs[0]


def test_each_hand_is_held_to_its_own_claims(pair, tmp_path) -> None:
    """A note the end marker gives the right hand that the left one plays: the right
    hand's claim fails (named with the note), the whole song's keys are still right."""
    moved = pair.by_hand["left."][2]
    by_hand = {"left.": [i for i in pair.by_hand["left."] if i != moved],
               "right.": sorted([*pair.by_hand["right."], moved])}
    path = write_unguarded(tmp_path / "claims.csv", pair, *pair.q, end={"by_hand": by_hand})
    rep = check_trajectory(str(path), str(pair.song))
    assert not rep.ok and rep.play.notes_hit == rep.play.notes and not rep.play.claim_mismatches
    left, right = rep.hands
    assert left.ok and not right.ok
    assert [c.note for c in right.play.claim_mismatches] == [moved]
    assert any(p.startswith("right. 1 notes the plan claims otherwise") for p in rep.problems)


def test_a_wrong_key_is_named_with_its_hand(tmp_path) -> None:
    """The left hand plays C3 where the song has B2: a wrong press by a left finger, the
    song's B2 missed; the right hand is not blamed."""
    left = notes_of([48, 52, 55], step_s=0.5)
    heard = notes_of([47, 52, 55], step_s=0.5)
    pf = plan_pair(tmp_path, left, notes_of([72, 76, 79], step_s=0.5), heard_left=heard)
    rep = check_trajectory(str(pf.path), str(pf.song))
    assert not rep.ok
    (w,) = rep.play.wrong_presses
    assert w.pitch == 48 and all(f.startswith("left.") for f in w.fingers)
    assert [m.pitch for m in rep.play.missed] == [47]
    assert rep.hands[1].ok and not rep.hands[0].ok
    assert [c.note for c in rep.hands[0].play.claim_mismatches] == [pf.by_hand["left."][0]]


def test_a_hand_beyond_its_limits_is_named_with_its_prefix(pair, tmp_path) -> None:
    """Limits per hand, by its own model: a left joint past its stop fails as the left's."""
    ql, qr = (x.copy() for x in pair.q)
    j = 5  # (a finger joint: its stop from the left hand's model)
    ql[100:110, j] = load_hand("default-left").upper[j] + 0.05
    path = write_unguarded(tmp_path / "limits.csv", pair, ql, qr)
    rep = check_trajectory(str(path), str(pair.song))
    assert not rep.ok and not rep.hands[0].ok
    assert all(lc.ok for lc in rep.hands[1].limits)
    assert any(p.startswith("left. ") and "joint position violations" in p
               for p in rep.problems)

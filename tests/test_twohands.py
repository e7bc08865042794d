"""Two hands planned together (``planner.play.twohands``, ``play --hands 2``): the rails
never closer than the pair's rail gap on a song that makes the hands meet, the independent
check finding no collision and every claim true; the windows and bounds; the command
line's errors and its one-part file."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.hand.model import load_hand
from planner.music.midi import Note, load_song, write_notes_midi
from planner.play.hands import LEFT, RIGHT, MoveReason
from planner.play.stream import Planner
from planner.play.twohands import PairPlanner, plan_two_hands

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def pair() -> PairPlanner:
    return PairPlanner(load_hand("default-left"), load_hand("default"))


def meeting_song(path: Path) -> Path:
    """The left part climbs from C3 and the right one falls from C6, a note each every
    0.25 s, so that they meet at middle C and pass: a left part on channel 1, a right one
    on channel 0 (two parts: ``hint_hands``)."""
    white = [0, 2, 4, 5, 7, 9, 11]
    up = [48 + 12 * (i // 7) + white[i % 7] for i in range(15)]  # C3 .. C5
    down = [84 - (12 * (i // 7) + [0, 1, 3, 5, 7, 8, 10][i % 7]) for i in range(15)]  # C6 ..
    notes = [Note(p, 0.5 + 0.25 * i, 0.5 + 0.25 * i + 0.2, 80, 1) for i, p in enumerate(up)]
    notes += [Note(p, 0.5 + 0.25 * i, 0.5 + 0.25 * i + 0.2, 80, 0) for i, p in enumerate(down)]
    write_notes_midi(notes, path)
    return path


def test_hands_meet_and_never_collide(pair, tmp_path) -> None:
    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    out = tmp_path / "meet.csv"
    plan = plan_two_hands(song, pair, str(out))
    qL, qR = plan.rows.q
    gap = qR[:, pair.hands[RIGHT].index["rail"]] - qL[:, pair.hands[LEFT].index["rail"]]
    assert gap.min() == pytest.approx(plan.least_rail_gap_m)
    # (row by row the hand planned second keeps the clearance from the first one's bodies
    # as they are: by its farthest reach, or by the places' own reach confirmed with the
    # check's judge, ``planner.play.handclear``; the check below finds no collision)
    first = plan.first
    assert plan.least_rail_gap_m < pair.gap.rail_gap_m  # (nearer than the worst reach)
    assert gap.min() < pair.gap.rail_gap_m + 0.05  # (the hands did meet)
    # (the hands contest keys: both orders and the right hand alone planned, each order
    # with its first hand's room settled too where that takes a note out, the way playing
    # the most frames kept)
    ways = [w for w, _ in plan.tried if not w.endswith(" back")]
    assert [w for w in ways if not w.endswith(" settled")] == [
        "right first", "left first", "right alone"]
    assert all(w.removesuffix(" settled") in ways[:3] for w in ways[3:])
    # (then the best way of the three, the best of all where a settled one plays more, and
    # every way whose hand-back could play more than the most frames yet (``back_ceiling``),
    # with the notes its second hand left out handed back to the first, each at most once;
    # the final ways compared by the check's frame F1, ``by_check``)
    backs = [w for w, _ in plan.tried[len(ways):]]
    assert all(w.endswith(" back") and w.removesuffix(" back") in ways for w in backs)
    assert len(set(backs)) == len(backs) <= len(ways)
    assert max(fr for _, fr in plan.tried) == dict(plan.tried)[plan.way]
    assert plan.way.startswith(first)
    rep = check_trajectory(str(out), song)
    assert rep.gap.collision_rows == 0 and rep.gap.least_m >= 0.010
    assert rep.ok, rep.problems
    # (every note is one hand's, claimed or named; the claims are the check's findings)
    assert sorted(plan.notes_of[0] + plan.notes_of[1]) == list(range(len(song.notes)))
    left_out = {i for i, _ in plan.left_out()}
    assert rep.play.f1 > 0.5 and len(left_out) < len(song.notes) // 2
    assert not set(plan.played_of(LEFT)) & set(plan.played_of(RIGHT))  # (never twice)
    assert set(plan.played_of(LEFT)) | set(plan.played_of(RIGHT)) == (
        set(range(len(song.notes))) - left_out)
    # (a note the hand planned first left out was planned again on the other hand, which
    # either plays it or names why not: in the pass the kept way is, or the one it handed
    # back, ``hand_back`` planning its first hand again)
    if plan.way.endswith(" back"):
        from planner.play.hands import assign_hands
        from planner.play.twohands import plan_pass
        a = assign_hands(song.notes, pair.gap, {s: pair.planners[s].places for s in (LEFT, RIGHT)})
        plan = plan_pass(song, pair, a.one_hand(first) if " alone" in plan.way else a, first,
                         100.0, settled=" settled" in plan.way)
    second_i = 1 if first == LEFT else 0
    handed = [m for m in plan.assignment.moved if m.reason is MoveReason.LEFT_OUT]
    fi = 1 - second_i
    first_out = {plan.planned_of[fi][s.note] for s in plan.plans[fi].verdict.skipped}
    # (every note the first hand left out is the second's now: handed over, or given back
    # to the hand it is written for)
    assert first_out and first_out <= set(plan.notes_of[second_i])
    assert {m.note for m in handed} <= first_out
    for m in plan.assignment.moved:
        if m.reason is MoveReason.LEFT_OUT:
            assert m.note in plan.planned_of[1 - second_i] and m.note in plan.planned_of[second_i]
            assert m.note in plan.notes_of[second_i]


def test_same_song_same_bytes(pair, tmp_path) -> None:
    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    a, b = (plan_two_hands(song, pair).text for _ in range(2))
    assert a == b and a.startswith("#")


def test_inner_edge_never_exceeds_the_pairs_farthest_reach(pair) -> None:
    for side in (LEFT, RIGHT):
        pl = pair.planners[side]
        q = np.array([pl.rest_q, pl.places.idle.tuck(pl.atlas.base)])
        got = pair.edges[side].inner_m(q)
        assert got.shape == (2,) and (got <= pair.reach(side).inner_extent_m + 1e-9).all()
        assert (got > 0.0).all()


def test_narrow_tucks_the_idle_fingers_nearer_the_rail(pair) -> None:
    # (one hand's idle pose, the nearest its natural one, against the pair's narrowed one:
    # the narrowed reaches less far towards the other hand)
    one = Planner(load_hand("default"))
    right = pair.planners[RIGHT]
    assert one.places.idle.fingers == right.places.idle.fingers != ()
    base = one.atlas.base
    q = np.array([one.places.idle.tuck(base), right.places.idle.tuck(base)])
    wide, narrow = pair.edges[RIGHT].inner_m(q)
    assert narrow < wide - 0.02


def run_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), *args], cwd=cwd,
                       capture_output=True, text=True, timeout=900, check=False)
    assert "Traceback" not in r.stderr, r.stderr
    return r


@pytest.mark.parametrize("args,says", [
    (("--hands", "3"), "--hands takes 1, 2 or two hands"),
    (("--hands", "default"), "--hands takes 1, 2 or two hands"),
    (("--hands", "2", "--hand", "default"), "name the pair"),
    (("--hands", "2", "--track", "1"), "every part"),
    (("--hands", "default,default-left"), "a left hand then a right"),
])
def test_cli_bad_hands(tmp_path, args, says) -> None:
    r = run_cli("play", str(ROOT / "songs" / "twinkle.mid"), "-o", "x.csv", *args, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and says in r.stderr, r.stderr
    assert not (tmp_path / "x.csv").exists()


def test_cli_one_part_file_split_by_pitch(tmp_path) -> None:
    # (both hands' notes in one track and channel: cut at the pitch between them)
    notes = [Note(p, 0.5 + 0.5 * i, 0.9 + 0.5 * i, 80) for i in range(8)
             for p in (43 + (i % 3) * 2, 76 + (i % 4))]
    write_notes_midi(notes, tmp_path / "one.mid")
    r = run_cli("play", "one.mid", "--hands", "2", "-o", "one.csv", "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["hint"] == "split" and [h["notes"] for h in d["hands"]] == [8, 8]
    assert d["least_rail_gap_m"] > 0.0 and d["first_hand"] in ("left", "right")
    rep = check_trajectory(str(tmp_path / "one.csv"), load_song(tmp_path / "one.mid",
                                                                every_part=True))
    assert rep.ok and rep.play.f1 > 0.9, rep.problems


def test_hand_back_plans_the_first_hand_again_with_what_the_second_left_out(pair,
                                                                           tmp_path) -> None:
    from planner.play.hands import assign_hands
    from planner.play.twohands import hand_back, plan_pass

    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    places = {s: pair.planners[s].places for s in (LEFT, RIGHT)}
    p = plan_pass(song, pair, assign_hands(song.notes, pair.gap, places), RIGHT, 100.0)
    b = hand_back(song, pair, p, 100.0)
    f, s = 1, 0  # (the right hand first, the left second)
    gone = {p.planned_of[s][k.note] for k in p.plans[s].verdict.skipped}
    assert gone  # (the hands meet: the second hand leaves notes out)
    assert b is not None and b.way == "right first back" and b.first == RIGHT
    assert b.plans[s] is p.plans[s] and b.planned_of[s] == p.planned_of[s]  # (unchanged)
    plays = set(p.planned_of[s]) - gone
    assert set(b.planned_of[f]) == (set(p.planned_of[f]) - plays) | gone
    # (every note one hand's; none played by both)
    assert sorted(b.notes_of[0] + b.notes_of[1]) == list(range(len(song.notes)))
    played = [{b.planned_of[k][i] for i in range(len(b.planned_of[k]))}
              - {b.planned_of[k][x.note] for x in b.plans[k].verdict.skipped} for k in (0, 1)]
    assert not played[0] & played[1]
    assert all(b.assignment.hand[i] == RIGHT for i in b.planned_of[f])


def test_plan_reads_give_each_plan_its_own_rows_and_plan_two_hands_lets_them_go(pair,
                                                                                tmp_path
                                                                                ) -> None:
    from planner.play.twobounds import first_edge
    from planner.play.twoplan import PlanReads, one_clock

    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    plan = plan_two_hands(song, pair)
    assert len(pair.reads) == 0  # (no plan held once the pair is planned)
    reads = PlanReads()
    for p in plan.plans:
        tr = reads(p)
        assert reads(p) is tr  # (read once)
        fresh = p.trajectory
        assert np.array_equal(tr.t_s, fresh.t_s) and np.array_equal(tr.q, fresh.q)
    assert len(reads) == 2
    # (the rows on one clock and the first hand's edge the same with the reads as without)
    with_reads, without = one_clock(plan.plans, 100.0, reads), one_clock(plan.plans, 100.0)
    assert with_reads.song_start_s == without.song_start_s == plan.rows.song_start_s
    for a, b, c in zip(with_reads.q, without.q, plan.rows.q):
        assert np.array_equal(a, b) and np.array_equal(a, c)
    for k, side in enumerate((LEFT, RIGHT)):
        e1 = first_edge(plan.plans[k], pair.hands[side], pair.edges[side], side, reads)
        e2 = first_edge(plan.plans[k], pair.hands[side], pair.edges[side], side)
        assert np.array_equal(e1.t_s, e2.t_s) and np.array_equal(e1.x_m, e2.x_m)
    reads.clear()
    assert len(reads) == 0


def test_by_check_keeps_the_way_the_check_scores_higher_where_frames_tie(pair,
                                                                          tmp_path) -> None:
    """The meeting song: the right-first and left-first ways, each handed back, play the
    same 560 frames of music (the frames' rule keeps the earlier, right first); the
    check's frame F1 of their pairs of rows is 0.9460 against 0.9484, and ``by_check``
    keeps left first. Its score is the check's: the F1 ``check`` finds in the file
    written of the way kept."""
    from planner.play.hands import assign_hands
    from planner.play.twohands import by_check, hand_back, plan_pass
    from planner.play.twoplan import write_two_hands

    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    a = assign_hands(song.notes, pair.gap, {s: pair.planners[s].places for s in (LEFT, RIGHT)})
    backs = [hand_back(song, pair, plan_pass(song, pair, a, s, 100.0), 100.0)
             for s in (RIGHT, LEFT)]
    assert [b.way for b in backs] == ["right first back", "left first back"]
    assert backs[0].played_frames == backs[1].played_frames == 560
    f1 = [pair.scorer.frame_f1(by_check(song, pair, [b], 100.0)[1], song, 100.0)
          for b in backs]
    assert f1[0] == pytest.approx(0.9460, abs=1e-4) and f1[1] == pytest.approx(0.9484, abs=1e-4)
    best, rows = by_check(song, pair, backs, 100.0)
    assert best is backs[1]
    # (the same score as the check's, of the file written)
    plan = plan_two_hands(song, pair)
    out = tmp_path / "meet.csv"
    kept = replace(plan, plans=best.plans, notes_of=best.notes_of, rows=rows,
              planned_of=best.planned_of, assignment=best.assignment, first=best.first,
              way=best.way)
    write_two_hands(kept, song, pair, str(out), 100.0, "")
    assert check_trajectory(str(out), song).play.f1 == pytest.approx(f1[1], abs=2e-3)


def test_the_notes_pressed_softer_are_named_per_hand(pair, tmp_path) -> None:
    """A forte right part (velocity 127: 3 N, which only the index holds at any press) over
    a mezzo-forte left one: the summary's ``softer:`` line and ``--json``'s ``softer`` name
    the right part's notes pressed with less (``summary.softer_notes`` on each hand's own
    plan), none of the left's."""
    from planner.play.force import press_force_n
    from planner.play.twosummary import format_two_summary, softer_of, two_plan_dict

    line = (68, 63, 68, 61, 68, 63, 70, 66, 68, 61)
    notes = [Note(p, 0.5 + 0.25 * k, 0.75 + 0.25 * k, 127, 0) for k, p in enumerate(line)]
    notes += [Note(p, 0.5 + 0.5 * k, 0.9 + 0.5 * k, 64, 1) for k, p in enumerate((48, 52, 55))]
    write_notes_midi(notes, tmp_path / "forte.mid")
    song = load_song(tmp_path / "forte.mid", every_part=True)
    plan = plan_two_hands(song, pair, str(tmp_path / "forte.csv"))
    places_of = {s: p.places for s, p in pair.planners.items()}
    soft = softer_of(song.notes, plan, places_of)
    assert soft and {side for _, side, _ in soft} == {RIGHT}
    assert all(f < press_force_n(song.notes[n].velocity) == 3.0 for n, _, f in soft)
    assert all(song.notes[n].velocity == 127 for n, _, _ in soft)
    text = format_two_summary("forte", song.notes, plan, "forte.csv", places_of=places_of)
    assert f"softer: {len(soft)} notes pressed with" in text
    d = two_plan_dict("forte", song.notes, plan, "forte.csv", 0.0, places_of)
    assert [(x["note"], x["hand"], x["force_n"]) for x in d["softer"]] == soft
    assert "softer" not in format_two_summary("forte", song.notes, plan, "forte.csv")


def test_second_plans_give_back_the_plan_made_from_the_same(
        pair, tmp_path) -> None:
    """``SecondPlans``: the meeting song's right-first pass planned twice within one pair's
    planning, its first hand's plan the same rows (a new object), the second hand's plan
    is the one made the first time, not planned again; its notes or side otherwise, none
    is given; made anew, it is the same plan. ``plan_two_hands`` lets them go when it is
    done. (The same files on the two-hand corpus: the history page.)"""
    from planner.play.hands import assign_hands
    from planner.play.twohands import plan_pass
    from planner.play.twoplan import SecondPlans, same_plan

    song = load_song(meeting_song(tmp_path / "meet.mid"), every_part=True)
    a = assign_hands(song.notes, pair.gap, {s: pair.planners[s].places for s in (LEFT, RIGHT)})
    pair.seconds.clear()
    p = plan_pass(song, pair, a, RIGHT, 100.0)
    assert len(pair.seconds) == 1
    q = plan_pass(song, pair, a, RIGHT, 100.0)
    assert q.plans[1] is not p.plans[1] and same_plan(q.plans[1], p.plans[1])
    assert q.plans[0] is p.plans[0] and len(pair.seconds) == 1  # (given back)
    key = (LEFT, p.planned_of[0], 100.0, "", song.notes)
    assert pair.seconds.get(key, q.plans[1]) is p.plans[0]
    assert pair.seconds.get((RIGHT,) + key[1:], q.plans[1]) is None
    assert pair.seconds.get((LEFT, p.planned_of[0][1:]) + key[2:], q.plans[1]) is None
    assert pair.seconds.get(key[:4] + (song.notes[1:],), q.plans[1]) is None  # (another song)
    assert pair.seconds.get(key, p.plans[0]) is None  # (another first plan)

    class Anew(SecondPlans):  # (every second plan made anew; the hits counted)
        hits = 0

        def get(self, key, first) -> None:
            Anew.hits += super().get(key, first) is not None

    kept = pair.seconds
    try:
        pair.seconds = Anew()
        r = plan_pass(song, pair, a, RIGHT, 100.0)
        s = plan_pass(song, pair, a, RIGHT, 100.0)
    finally:
        pair.seconds = kept
    assert Anew.hits == 1 and s.plans[0] is not r.plans[0]
    # (the plan given back is the plan made anew: the same rows, notes and frames)
    assert same_plan(s.plans[0], p.plans[0]) and s.played_frames == p.played_frames
    assert s.assignment == p.assignment and s.planned_of == p.planned_of
    plan_two_hands(song, pair)
    assert len(pair.seconds) == 0

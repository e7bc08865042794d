"""The second play planner end to end (planner.play.stream), judged by the independent
check: safe on every sample and stress song, honest (its claims are the check's
findings), deterministic; the inputs of issue 14 that made the first planner press a
wrong key are played without one."""

from __future__ import annotations

from pathlib import Path

import pytest

from planner.check import check_trajectory
from planner.hand.model import load_hand
from planner.music.midi import Note, load_song, write_notes_midi
from planner.play import Planner, plan_song
from planner.play.costs import SkipReason

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
SONGS = sorted((ROOT / "songs").glob("*.mid")) + sorted((ROOT / "songs" / "stress").glob("*.mid"))
# frame F1 by check's verdict, the hand's bodies (spec section 2, the rule the plan is
# timed to), measured with this version less 0.01 (by the pad points before check judged
# the bodies: twinkle 0.9693, chords 0.9333, fast 0.7821, fur_elise 0.8970, leaps 0.9599,
# ode_to_joy 0.9456, scale 0.9338, fast_six_keys 0.7714, leaps_legato 0.6297)
# (held keys following the arm into other postures, the follows and presses by the body
# rule: ode_to_joy 0.9913 -> 1.0, scale 0.9751 -> 1.0, fur_elise 0.9584 -> 1.0, fast
# 0.9122 -> 0.9155, fast_six_keys 0.8822 -> 0.9145, chords 0.9537 -> 0.9539, leaps_legato
# 0.6618 -> 0.6604: floors as measured less 0.01)
FLOOR = {"twinkle": 0.99, "ode_to_joy": 0.99, "chords": 0.943, "scale": 0.99,
         "fur_elise": 0.99, "fast": 0.905, "leaps": 0.983, "fast_six_keys": 0.904,
         "leaps_legato": 0.65}
# (issue 30's rows a controller can run, measured less 0.01 on the tree that brought them:
# jerk-limited moves (a ramp of one motor time constant) and 2 deg from every hard stop:
# twinkle 1.0 -> 0.9969, chords 0.9931 -> 0.9823, scale 1.0 -> 0.9740, leaps 0.9928 ->
# 0.9766, fast 1.0 -> 0.8721 (0.9108 without the stop margin: the splay's last 2 deg),
# fast_six_keys -> 0.8943, leaps_legato -> 0.6328: moves around a change of hand position
# take longer)
# (leaps 1.0 -> 0.9928, leaps_legato 0.713 -> 0.640 when the rail's acceleration was capped
# at what the wrist motors hold, 40 -> 23 m/s^2: planner.play.railcap.rail_acceleration_cap)


@pytest.fixture(scope="module")
def planner():
    return Planner(load_hand("default"))


@pytest.fixture(scope="module")
def planned(planner, tmp_path_factory):
    d = tmp_path_factory.mktemp("v2")
    out = {}
    for p in SONGS:
        path = d / f"{p.stem}.csv"
        res = plan_song(load_song(p), planner.hand, str(path), planner=planner)
        out[p.stem] = (path, res, check_trajectory(str(path), str(p), strict=False))
    return out


@pytest.mark.parametrize("name", [p.stem for p in SONGS])
def test_safe_honest_and_above_its_floor(planned, name):
    _path, res, rep = planned[name]
    assert rep.ok, rep.summary()
    assert not rep.play.wrong_presses and not rep.play.key_bed_hits, rep.summary()
    assert all(lc.count == 0 for lc in rep.limits), rep.summary()
    # the summary is the replay: the claims agree with the check, note for note
    assert rep.play.claims and not rep.play.claim_mismatches
    assert {s.note for s in res.verdict.skipped} == {m.note for m in rep.play.missed}
    assert res.verdict.score.f1 == pytest.approx(rep.play.f1, abs=1e-12)
    assert rep.play.f1 >= FLOOR[name], rep.summary()
    assert not rep.play.body_bed_hits, rep.summary()


def test_same_song_same_bytes(planner, tmp_path):
    song = load_song(ROOT / "songs" / "ode_to_joy.mid")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    plan_song(song, planner.hand, str(a), planner=planner)
    plan_song(song, planner.hand, str(b), planner=Planner(planner.hand))
    assert a.read_bytes() == b.read_bytes()


def test_a_note_too_short_to_press_is_left_out_named(planner, tmp_path):
    """shared/repro/short_note_16_ticks.mid: one C4 of 16.7 ms (the first planner struck
    it after it ended: a wrong press, and said 'played')."""
    out = tmp_path / "s.csv"
    res = plan_song(load_song(DATA / "short_note_16_ticks.mid"), planner.hand, str(out),
                    planner=planner)
    (skip,) = res.verdict.skipped
    assert skip.reason is SkipReason.TOO_SHORT and "17 ms" in skip.detail
    rep = check_trajectory(str(out), str(DATA / "short_note_16_ticks.mid"))
    assert rep.ok and not rep.play.wrong_presses and not rep.play.played


def test_music21_test07_has_no_wrong_press(planner, tmp_path):
    """shared/repro/music21_testPrimitive_test07.mid: the first planner's pinky pressed
    G#4, a key the song never has, three times."""
    out = tmp_path / "m.csv"
    song = DATA / "music21_testPrimitive_test07.mid"
    res = plan_song(load_song(song), planner.hand, str(out), planner=planner)
    rep = check_trajectory(str(out), str(song))
    assert rep.ok and not rep.play.wrong_presses, rep.summary()
    assert not any(e.pitch == 68 for e in rep.play.played)
    assert not rep.play.claim_mismatches and res.verdict.played == rep.play.notes_hit


def test_the_trajectory_ends_with_the_song(planner, tmp_path):
    """5 s of music at 40 notes/s: far beyond the hand; the plan leaves most notes out but
    ends with the song plus the hand's return (issue 14: the first planner ran 12.3 s)."""
    notes = [Note(60 + (k % 8), 0.025 * k, 0.025 * k + 0.02, 80) for k in range(200)]
    song = tmp_path / "dense.mid"
    write_notes_midi(notes, song)
    out = tmp_path / "d.csv"
    res = plan_song(load_song(song), planner.hand, str(out), planner=planner)
    rep = check_trajectory(str(out), str(song))
    assert rep.ok and not rep.play.wrong_presses
    assert res.duration_s <= 5.0 + 0.5


def test_a_one_note_song_at_1_hz_is_a_file_the_check_reads(planner, tmp_path):
    """At --rate 1 (the least allowed) a half-second note's plan ends before the second
    row: the file still has a trajectory's two rows, and the check confirms the note the
    planner claims (it once wrote one row, which ``check`` refuses)."""
    song = tmp_path / "one.mid"
    write_notes_midi([Note(60, 0.0, 0.5, 64)], song)
    out = tmp_path / "one.csv"
    res = plan_song(load_song(song), planner.hand, str(out), rate_hz=1.0, planner=planner)
    assert res.rows == 2 and res.verdict.played == 1
    rep = check_trajectory(str(out), str(song))
    assert rep.ok and rep.play.notes_hit == 1 and not rep.play.claim_mismatches, rep.summary()


def test_the_cli_layer_summarises_the_replay_and_exits_by_it(tmp_path, capsys):
    """planner.cli.play (``cli.py play``): the summary line the hardening tests parse,
    every note left out named, --strict exit 1."""
    import re

    from planner.cli import build_parser
    from planner.cli.play import run as play_cli

    def args(song, out, strict=False):
        return build_parser().parse_args(
            ["play", str(song), "-o", str(out)] + (["--strict"] if strict else []))

    assert play_cli(args(ROOT / "songs" / "twinkle.mid", tmp_path / "t.csv")) == 0
    err = capsys.readouterr().err
    assert re.search(r"^twinkle.mid: 14 notes, 14 played, 0 infeasible; \d+ rows", err, re.MULTILINE)
    short = DATA / "short_note_16_ticks.mid"
    assert play_cli(args(short, tmp_path / "s.csv")) == 0
    err = capsys.readouterr().err
    assert "1 notes, 0 played, 1 infeasible" in err and "too_short: 17 ms long" in err
    assert play_cli(args(short, tmp_path / "s.csv", strict=True)) == 1


def test_a_hand_on_a_fixed_mount_plays_what_it_reaches(tmp_path):
    """A hand file with ``[rail] enabled = false``: the atlas has one place for the hand;
    notes out of its reach are named, the rest played, nothing pressed wrongly."""
    from planner.hand.builders import load_hand_spec
    from planner.hand.model import HandModel
    from planner.hand.spec import hands_dir
    from tests.handfiles import DEFAULT_MOUNT, default_text

    # (the reach axis goes with the rail: the mount takes the first play posture's reach)
    text = default_text().replace("enabled = true", "enabled = false").replace(
        'name = "default"', 'name = "norail"').replace(
        DEFAULT_MOUNT, "xyz_m = [0.0, -0.575, 0.05]").replace(
        "reach_m = [-0.175, -0.15, -0.10]", "reach_m = 0.0")
    assert hands_dir().exists()
    p = tmp_path / "norail.toml"
    p.write_text(text, encoding="utf-8")
    hand = HandModel(load_hand_spec(str(p)))
    assert "rail" not in hand.joint_names
    song = ROOT / "songs" / "twinkle.mid"
    res = plan_song(load_song(song), hand, str(tmp_path / "t.csv"))
    rep = check_trajectory(str(tmp_path / "t.csv"), str(song), hand_override=hand)
    assert rep.ok and not rep.play.wrong_presses and all(lc.count == 0 for lc in rep.limits)
    # (one hand position, one posture: 4 of twinkle's 14 notes have a press whose bodies
    # are clear of the other keys from there; 10 by the pad points alone)
    assert res.verdict.played == rep.play.notes_hit >= 4
    assert {s.reason.value for s in res.verdict.skipped} <= {"out_of_reach", "body"}


def test_a_chord_of_twelve_keeps_five_next_to_each_other(planner, tmp_path):
    """Twelve notes at once: the programme tries runs of keys in pitch order, not every
    subset (C(12, 5) and more), keeps what one hand position holds, names the rest."""
    notes = [Note(60 + k, 0.0, 1.0, 80) for k in range(12)]
    song = tmp_path / "cluster.mid"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(tmp_path / "c.csv"), planner=planner)
    assert 1 <= res.verdict.played <= 5
    assert all(s.reason.value == "chord" for s in res.verdict.skipped)
    played = sorted(a.note for a in res.fingering.assignments)
    assert played == list(range(played[0], played[0] + len(played)))  # a run of keys


def test_progress_is_reported_as_the_notes_are_decided(planner, tmp_path):
    """``on_progress(decided, total)``: more than once on a song of several chunks, never
    backwards, ending at every note (the CLI draws its bar on a terminal from it)."""
    seen = []
    song = load_song(ROOT / "songs" / "ode_to_joy.mid")
    plan_song(song, planner.hand, str(tmp_path / "o.csv"), planner=planner,
              on_progress=lambda done, total: seen.append((done, total)))
    assert len(seen) >= 2 and all(t == len(song.notes) for _, t in seen)
    done = [d for d, _ in seen]
    assert done == sorted(done) and done[-1] == len(song.notes)


def test_planning_leaves_no_reference_cycles_and_the_collector_as_it_was():
    """plan_song pauses Python's cyclic collector (planner.play.stream): that is sound
    only if planning makes no reference cycles. A song with chords, held notes, leaps and
    a note out of reach planned with the collector off leaves no unreachable object; the
    collector's state is restored, on or off."""
    import gc

    from planner.hand.model import load_hand
    from planner.music.midi import Note, Song
    from planner.play import Planner, plan_song

    hand = load_hand("default")
    pl = Planner(hand)
    notes = [Note(60 + (k * 7) % 19, 0.15 * k, 0.15 * k + 0.4, 90) for k in range(60)]
    notes += [Note(48, 1.0, 6.0, 60), Note(55, 1.0, 6.0, 60), Note(108, 2.0, 2.5, 80)]
    song = Song(tuple(notes), 9.0, (), "cycles")
    plan_song(song, hand, planner=pl)  # (the caches filled: what stays is not garbage)
    gc.collect()
    gc.disable()
    try:
        plan = plan_song(song, hand, planner=pl)
        assert not gc.isenabled()
        assert gc.collect() == 0
    finally:
        gc.enable()
    assert plan.verdict.played >= 15 and plan.verdict.skipped  # (notes left out, too)
    plan_song(song, hand, planner=pl)
    assert gc.isenabled()

"""``play`` as a user runs it: the file, the options, the command line, and songs of the
kinds that once went wrong, each planned and replayed through the independent check
(planner.check), which shares only the hand model with the planner. The planner's
stages have their own tests (test_play_atlas, _profile, _fingering, _stream)."""

from __future__ import annotations

import random
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.hand.model import load_hand
from planner.music import keyboard as kb
from planner.music.midi import Note, Song, load_song, write_notes_midi
from planner.play import Planner, plan_song
from planner.play.atlas import CLEARANCE_M, TIP_RADIUS_M
from planner.play.costs import SkipReason
from planner.play.highclear import FRONT_CLEAR_Z_M, FRONT_Y_M
from planner.trajfile import read_trajectory

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def planner():
    return Planner(load_hand("default"))


def _plan(planner, notes, tmp_path, name="song", channel=None):
    """Write ``notes`` as a MIDI file, plan it, check it: (plan, check report, csv path);
    ``channel``: read only that channel (every note of it: no part chosen)."""
    song, path = tmp_path / f"{name}.mid", tmp_path / f"{name}.csv"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song, channel=channel), planner.hand, str(path),
                    song_name=song.name, planner=planner)
    return res, check_trajectory(str(path), str(song), strict=False), path


def _safe(rep) -> None:
    assert not rep.play.wrong_presses and not rep.play.key_bed_hits, rep.summary()
    assert all(v.count == 0 for v in rep.limits), rep.summary()
    assert rep.play.claims and not rep.play.claim_mismatches, rep.summary()


def test_at_least_six_sample_songs():
    assert len(list((ROOT / "songs").glob("*.mid"))) >= 6


def test_file_format(planner, tmp_path):
    song = load_song(ROOT / "songs" / "twinkle.mid")
    path = tmp_path / "t.csv"
    res = plan_song(song, planner.hand, str(path), song_name="twinkle.mid", planner=planner)
    tr = read_trajectory(str(path))
    hand = planner.hand
    assert tr.complete and tr.metadata["task"] == "play" and tr.metadata["rate_hz"] == 100.0
    assert tr.metadata["song"] == "twinkle.mid" and tr.metadata["notes"] == len(song.notes)
    assert tr.joint_names == hand.joint_names and tr.motor_names == hand.motor_names
    assert tr.t_s[0] == 0.0 and np.allclose(np.diff(tr.t_s), 0.01, atol=1e-6)
    assert len(tr.t_s) == res.rows
    assert np.allclose(tr.q_motor, hand.motor_angles(tr.q), atol=1e-4)  # the actuator model
    assert tr.end["played"] == res.verdict.played == len(song.notes)


def test_rate_option(planner, tmp_path):
    song = load_song(ROOT / "songs" / "twinkle.mid")
    p = tmp_path / "r.csv"
    plan_song(song, planner.hand, str(p), rate_hz=50.0, planner=planner)
    tr = read_trajectory(str(p))
    assert tr.metadata["rate_hz"] == 50.0 and np.allclose(np.diff(tr.t_s), 0.02, atol=1e-6)
    rep = check_trajectory(str(p), str(ROOT / "songs" / "twinkle.mid"))
    # (by the pad points; the plan is timed to the bodies: 0.957 at 50 Hz, session 37)
    assert rep.play.f1 >= 0.947 and not rep.play.wrong_presses, rep.summary()


TIP_OFF_KEYS_M = 0.03  # a tip this far in front of the keys' front edge is over none of them
# (more than the widest pad's diameter, the thumb's 24 mm)


@pytest.mark.parametrize("name", ["leaps", "scale", "fur_elise"])
def test_tips_clear_the_keys_while_the_arm_travels(planner, tmp_path, name):
    """Whenever the rail moves, every fingertip is above every key top by the atlas's
    clearance (its pad's lowest point over the black keys' tops), or, lying in front of
    the black keys (less the body rule's tolerance), above the white keys' tops by it
    (``planner.play.highclear``'s front rule: only white keys pass under it as the rail
    moves along x), or is holding its key down (a finger that follows its key as the hand
    shifts: inside the key's footprint, the key down, above the key bed), or is in front
    of the keyboard by more than a pad (over no key)."""
    path = tmp_path / f"{name}.csv"
    plan_song(load_song(ROOT / "songs" / f"{name}.mid"), planner.hand, str(path),
              planner=planner)
    _assert_tips_clear_while(planner.hand, read_trajectory(str(path)), "rail")


def test_tips_clear_the_keys_while_the_arm_changes_posture(planner, tmp_path):
    """The same whenever the reach axis moves (a change of play posture: white keys in
    the first posture, black keys in the others, so the hand goes in and out of the
    keyboard): before a move out, a finger's lift is clear by the front rule (its body
    in front of the black keys only goes further out: ``highclear.front_rules``)."""
    pitches = [64, 66, 67, 69, 71, 73, 74, 76, 74, 73, 71, 69, 67, 66, 64, 62, 61, 62, 64]
    notes = [Note(p, 0.25 * i, 0.25 * i + 0.22, 80) for i, p in enumerate(pitches)]
    _, rep, path = _plan(planner, notes, tmp_path)
    _safe(rep)
    tr = read_trajectory(str(path))
    reach = np.diff(tr.q[:, planner.hand.joint_names.index("reach")])
    assert (reach < -1e-7).sum() > 0 and (reach > 1e-7).sum() > 0  # (moves out and in)
    _assert_tips_clear_while(planner.hand, tr, "reach")


def _assert_tips_clear_while(hand, tr, joint: str) -> None:
    """Every row in which ``joint`` (the rail, the reach axis) moves into and out: each
    tip high, in front of the black keys above the white tops, holding its key, or in
    front of the keyboard (``test_tips_clear_the_keys_while_the_arm_travels``)."""
    col = hand.joint_names.index(joint)
    step = np.abs(np.diff(tr.q[:, col])) > 1e-7
    moving = np.flatnonzero(step[:-1] & step[1:]) + 1  # it moves into and out of the row
    assert moving.size > 0
    tips = np.array([hand.tip_positions(q) for q in tr.q[moving]])  # (T, 5, 3)
    high = tips[..., 2] >= kb.BLACK_TOP_Z_M + CLEARANCE_M + TIP_RADIUS_M - 1e-3
    front = (tips[..., 1] + TIP_RADIUS_M <= FRONT_Y_M) \
        & (tips[..., 2] >= FRONT_CLEAR_Z_M + TIP_RADIUS_M - 1e-3)
    high |= front
    for t, f in zip(*np.nonzero(~high)):
        x, y, z = tips[t, f]
        k = kb.key_under(x, y)
        if k is None and y < -TIP_OFF_KEYS_M:  # (in front of the keys, over none: the
            continue  # default hand's thumb, which plays nothing, hangs there)
        assert k is not None, (tr.t_s[moving[t]], hand.fingers[f], z)
        assert k.top_z_m - kb.KEY_BED_DEPTH_M + 1e-4 < z < k.top_z_m - kb.DOWN_DEPTH_M, \
            (tr.t_s[moving[t]], hand.fingers[f], z)


def test_one_hand_position_serves_a_four_finger_tune(planner, tmp_path):
    """Four neighbouring keys, one per long finger (the default hand's thumb presses no
    key: ``test_play_atlas``), in any order: the hand never travels while the song plays
    (only on its way in from rest and back)."""
    pitches = [60, 64, 62, 65, 60, 65, 64, 62, 65, 60, 62]
    res, rep, path = _plan(planner, [Note(p, 0.3 * i, 0.3 * i + 0.25, 80)
                                     for i, p in enumerate(pitches)], tmp_path)
    assert len({a.rail_m for a in res.fingering.assignments}) == 1
    tr = read_trajectory(str(path))
    start = tr.metadata["song_start_s"]
    song = (tr.t_s >= start) & (tr.t_s <= start + 0.3 * (len(pitches) - 1) + 0.25)
    assert np.ptp(tr.q[song, planner.hand.joint_names.index("rail")]) < 1e-9
    _safe(rep)
    # (check by the bodies, the rule the plan is timed to; 0.93 by the pad points, whose
    # crossings come 20 ms after the bodies')
    assert rep.play.f1 >= 0.98, rep.summary()


def test_a_chord_wider_than_the_hand_is_played_in_part(planner, tmp_path):
    """C3-E3-G3 with E5 on top: the triad fits the hand, the four notes do not. The hand
    plays the largest part it can hold and names the note it leaves out; the note after
    it is still played."""
    notes = tuple(Note(p, 0.0, 1.0, 80) for p in (48, 52, 55, 76)) + (Note(60, 1.5, 2.0, 80),)
    res = plan_song(Song(notes, 2.0, (), "t"), planner.hand, str(tmp_path / "w.csv"),
                    planner=planner)
    left = res.verdict.skipped
    assert [(s.note, s.reason) for s in left] == [(3, SkipReason.CHORD)], left
    rep = check_trajectory(str(tmp_path / "w.csv"))
    assert not rep.play.key_bed_hits and all(v.count == 0 for v in rep.limits)


def test_a_note_that_cannot_be_struck_in_time_is_left_out_and_named(planner, tmp_path):
    """Four octaves up and down every 0.15 s: the rail cannot get there in time. The notes
    the hand cannot strike before they are half over are left out and named, and no key
    is down out of its note."""
    notes = [Note(36 if i % 2 else 84, 0.5 + 0.15 * i, 0.6 + 0.15 * i, 80) for i in range(8)]
    res, rep, _ = _plan(planner, notes, tmp_path)
    _safe(rep)
    assert any(s.reason == SkipReason.TOO_LATE for s in res.verdict.skipped), res.verdict
    assert {s.note for s in res.verdict.skipped} == {m.note for m in rep.play.missed}


def _random_walk(seed: int, n: int, tempo_bpm: float, leap_p: float) -> list:
    """A melody wandering over three octaves of C major (seeded: the same notes every run)."""
    rng = random.Random(seed)
    scale, deg, t, out = (0, 2, 4, 5, 7, 9, 11), 14, 0.0, []
    for _ in range(n):
        step = rng.choice([-2, -1, -1, 1, 1, 2]) if rng.random() > leap_p else rng.choice([-7, -5, 5, 7])
        deg = max(0, min(34, deg + step))
        d = 60.0 / tempo_bpm * rng.choice([0.5, 1, 1, 1, 2])
        out.append(Note(48 + 12 * (deg // 7) + scale[deg % 7], t, t + 0.9 * d, rng.randint(50, 110)))
        t += d
    return out


# frame F1 measured with this version (0.958, 0.964, 0.973), less 0.01 (with moves
# bang-bang at the acceleration limits, before issue 30's jerk bounds: 0.984, 0.982, 0.990;
# the plan timed to the bodies, session 37: 0.923 for seed 11, by the pad points). Seeds 3
# and 5 once pressed with a tendon at 101 % of its 40 N (the default middle finger's
# inertia as a descent slows); each finger move is now timed within the tendons' capacity
# (planner.play.tendonload): 0.8996 and 0.8803 by the pad points, less 0.01.
@pytest.mark.parametrize("seed,tempo,leaps,f1", [
    (3, 140, 0.1, 0.889), (5, 240, 0.05, 0.870), (11, 100, 0.4, 0.913)])
def test_random_melodies_are_played_safely(planner, tmp_path, seed, tempo, leaps, f1):
    """Melodies over three octaves at three speeds, with leaps: safe, honest, and played
    as well as this version plays them."""
    _res, rep, _ = _plan(planner, _random_walk(seed, 60, tempo, leaps), tmp_path)
    _safe(rep)
    assert rep.play.f1 >= f1, rep.summary()


def _melody_over_alberti_bass(melody):
    """A right-hand tune in quarter notes over a left-hand Alberti bass in eighths (I-IV-V-I
    in C), both hands' notes in one part: more than one hand can play."""
    chords = [(48, 52, 55), (53, 57, 60), (55, 59, 62), (48, 52, 55)]
    notes = []
    for bar in range(len(melody) // 4):
        t, c = 2.0 * bar, chords[bar % 4]
        for k, p in enumerate((c[0], c[2], c[1], c[2]) * 2):
            notes.append(Note(p, t + 0.25 * k, t + 0.25 * k + 0.225, 60))
        for k in range(4):
            notes.append(Note(melody[4 * bar + k], t + 0.5 * k, t + 0.5 * k + 0.45, 90))
    return sorted(notes, key=lambda n: (n.onset_s, n.pitch))


def test_two_hands_of_notes_give_no_wrong_press(planner, tmp_path):
    """Both hands' parts for one hand: much of it cannot be played; what is played presses
    no key the song does not have, and every note not played is named."""
    melody = [70, 68, 66, 67, 66, 67, 68, 68, 67, 67, 65, 65, 65, 67, 69, 69,
              70, 70, 72, 72, 73, 71, 69, 70, 72, 73, 75, 77, 77, 76, 76, 75]
    notes = _melody_over_alberti_bass(melody)
    res, rep, _ = _plan(planner, notes, tmp_path, channel=0)  # (channel 0: every note)
    _safe(rep)
    by_default = load_song(tmp_path / "song.mid")  # (the right hand's part: the melody)
    assert [n.pitch for n in by_default.notes] == melody and by_default.part.split_pitch
    assert res.verdict.skipped  # (one hand: some of it is named, not played)
    assert {s.note for s in res.verdict.skipped} == {m.note for m in rep.play.missed}


def test_a_trill_faster_than_the_fingers_is_planned_not_refused(planner, tmp_path):
    """C4-D4 at 16 notes per second: planned, within every limit, each note not played
    named."""
    notes = [Note(60 + (i % 2) * 2, i / 16, i / 16 + 0.055, 90) for i in range(48)]
    res, rep, _ = _plan(planner, notes, tmp_path)
    _safe(rep)
    assert rep.play.notes_hit + len(res.verdict.skipped) == len(notes)


def test_a_held_key_the_hand_must_leave_is_let_go_and_named(planner, tmp_path):
    """C3 held 3 s under thirds two octaves up: the hand cannot hold it and reach them, so
    C3 is let go when the thirds begin, and the thirds are played (one of them, E5 at
    1.5 s, down in 47 % of its frames since the rail's acceleration is capped at what the
    wrist motors hold, 23 m/s^2: named missed, like C3)."""
    thirds = ((72, 76), (74, 77), (76, 79), (77, 81), (79, 83))
    notes = [Note(48, 0.0, 3.0, 80)] + [Note(p, 0.5 + 0.5 * k, 0.95 + 0.5 * k, 80)
                                        for k, pair in enumerate(thirds) for p in pair]
    res, rep, _ = _plan(planner, notes, tmp_path)
    _safe(rep)
    bass = next(a for a in res.fingering.assignments if a.note == 0)
    assert bass.release_s == pytest.approx(0.5)
    pressed = [p for p in rep.play.played if p.pitch == 48]
    # (within four rows of the cut: the finger lifts for the arm's move as late as it can
    # be clear above every key when the arm starts (planner.play.highclear), the end of
    # its lift overlapping the move, two rows later than a lift that ended before it; and
    # check's body rule finds C3 down one or two rows past the lift's key crossing, not
    # explained yet: docs/design/play.md, limits; the note sounds on, so no wrong press;
    # and later by the front rule's gains, planner.play.highclear: the index on C3's front
    # is clear that much sooner, the first third's finger descending in front needs the
    # arm still that much later, so the arm starts, and C3 comes up, that much later)
    places = planner.places
    first = next(a for a in res.fingering.assignments if a.note == 1)
    e_bass, e_first = (places.atlases[a.posture].entry(a.finger, notes[a.note].pitch, a.rail_m)
                       for a in (bass, first))
    gain_s = (places.rail_lift_s(e_bass, False) - places.rail_lift_s(e_bass)
              + places.rail_descent_s(e_first, False) - places.rail_descent_s(e_first))
    assert len(pressed) == 1 and pressed[0].end_s <= 0.54 + gain_s + 1e-9
    assert rep.play.notes_hit >= len(notes) - 2
    skipped = [s.note for s in res.verdict.skipped]
    assert skipped[0] == 0 and len(skipped) <= 2  # (C3 down 1/6 of its frames: missed)
    assert {m.note for m in rep.play.missed} == set(skipped)


# frame F1 measured with this version (0.949, 1.0, 1.0), less 0.01
# (jerk-limited moves, issue 30: 0.949, 1.0, 1.0 -> 0.935, 0.881, 0.889; a short move
# bound by jerk takes 4 (d / 2 j)^(1/3), twice the bang-bang time of a repeated key)
# (the plan timed to the bodies, session 37, by the pad points: 0.820, 0.820, 0.774;
# each finger move timed within the tendons' capacity, planner.play.tendonload: the
# middle finger's moves up to 8 % slower, trill_cascade 0.7632)
@pytest.mark.parametrize("name,f1", [("melody_over_held_bass", 0.81), ("trill_sections", 0.81),
                                     ("trill_cascade", 0.753)])
def test_regression_songs(planner, name, f1, tmp_path):
    """Random songs the first planner once did badly on (tests/data/README.md)."""
    song = ROOT / "tests" / "data" / f"{name}.mid"
    path = tmp_path / "o.csv"
    plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song), strict=False)
    _safe(rep)
    assert rep.play.f1 >= f1, rep.summary()


def test_leaps_cannot_reach_the_target_on_this_rail(planner):
    """A bound, not a plan: between two notes the hand must move its rail at least the
    leap less the widest span two fingertips take at one rail position (the atlas's
    extreme places of any two fingers), and the rail cannot do that faster than
    bang-coast-bang at its top acceleration and speed. Even with instant fingers, the
    frames lost to that exceed what 0.98 allows: the issue's target is out of this hand's
    reach for `leaps_legato.mid` (a fact about the hardware and the song, measured here so
    that it fails if either changes)."""
    import itertools

    from planner.play.atlas import SPAN_M, STEP_M

    hand = planner.hand
    n = round(SPAN_M / STEP_M)
    dx = {f: [a.natural_dx[f] + k * STEP_M for a in planner.places.atlases
              for k in range(-n, n + 1)
              if any(a.entry_at(f, pc, k) is not None for pc in range(12))]
          for f in hand.fingers}
    pressing = [f for f in hand.fingers if dx[f]]  # (every play posture's; not the thumb)
    span = max(max(dx[b]) - min(dx[a]) for a in pressing for b in pressing)
    rail = hand.joint_names.index("rail")
    v, acc = hand.velocity[rail], hand.acceleration[rail]

    def t_min(d):  # bang-bang (trapezoid) time over d metres
        return 2.0 * np.sqrt(d / acc) if d <= v * v / acc else d / v + v / acc

    notes = sorted(load_song(ROOT / "songs" / "stress" / "leaps_legato.mid").notes,
                   key=lambda n: n.onset_s)
    lost = 0.0
    for a, b in itertools.pairwise(notes):
        d = max(0.0, abs(kb.key(b.pitch).center_x_m - kb.key(a.pitch).center_x_m) - span)
        lost += max(0.0, t_min(d) - (b.onset_s - a.offset_s)) if d > 0 else 0.0
    recall = 1.0 - lost / sum(n.offset_s - n.onset_s for n in notes)
    f1_bound = 2 * recall / (1 + recall)
    assert 0.9 < f1_bound < 0.98, f1_bound


# ---------------------------------------------------------------------- the command line
def _cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, str(ROOT / "cli.py"), *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300, check=False)


def test_cli_streams_to_stdout():
    r = _cli("play", str(ROOT / "songs" / "scale.mid"), "-o", "-")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith('# {"format": "hand-trajectory"')
    assert lines[-1].startswith('# {"end": true')
    assert "scale.mid: 15 notes, 15 played, 0 infeasible" in r.stderr


def test_cli_bad_midi_exits_2_and_leaves_no_file(tmp_path):
    bad = tmp_path / "bad.mid"
    bad.write_bytes(b"MThd\x00\x00\x00\x06\x00\x01\x00")
    out = tmp_path / "out.csv"
    r = _cli("play", str(bad), "-o", str(out))
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == [bad]


def test_cli_missing_file_and_bad_rate(tmp_path):
    r = _cli("play", str(tmp_path / "none.mid"))
    assert r.returncode == 2 and "Traceback" not in r.stderr
    r = _cli("play", str(ROOT / "songs" / "scale.mid"), "--rate", "0", "-o", str(tmp_path / "x.csv"))
    assert r.returncode == 2 and "rate" in r.stderr and not (tmp_path / "x.csv").exists()


def test_cli_strict_exits_1_on_infeasible(tmp_path):
    song = tmp_path / "wide.mid"
    write_notes_midi([Note(p, 0.0, 1.0, 80) for p in (36, 48, 60, 72, 84)], song)
    r = _cli("play", str(song), "-o", str(tmp_path / "w.csv"), "--strict")
    assert r.returncode == 1
    assert "infeasible: t=0.000 s" in r.stderr
    assert read_trajectory(str(tmp_path / "w.csv")).complete  # the plan is still written
    r = _cli("play", str(song), "-o", str(tmp_path / "w.csv"))
    assert r.returncode == 0


def test_a_forte_line_is_played_as_a_mezzo_forte_one(planner, tmp_path):
    """A line of black and white keys at 0.25 s a note, forte (velocity 127: 3 N, which
    only the index held at any press) and mezzo-forte: the index played the forte line
    alone, an arm move at every note, and left 4 of its 10 notes out (``too_late``, check
    F1 0.61 against 1.00); pressed softer where a pose holds less, the forte line is
    played as the other, every note struck, the same frames down, and the summary names
    the notes pressed softer than asked (none of the mezzo-forte line's)."""
    from planner.play.summary import format_summary, plan_dict, softer_notes

    line = (68, 63, 68, 61, 68, 63, 70, 66, 68, 61)
    got, soft = {}, {}
    for v in (64, 127):
        notes = [Note(p, 0.25 * k, 0.25 * (k + 1), v) for k, p in enumerate(line)]
        res, rep, path = _plan(planner, notes, tmp_path, name=f"line{v}")
        _safe(rep)
        assert not res.verdict.skipped, res.verdict.skipped
        got[v] = rep.play.f1
        soft[v] = softer_notes(notes, res, planner.places)
        text = format_summary("line", notes, res, str(path), places=planner.places)
        assert ("softer: " in text) == bool(soft[v])
        d = plan_dict("line", notes, res, str(path), 0.0, planner.places)
        assert [(x["note"], x["force_n"]) for x in d["softer"]] == soft[v]
    assert got[127] == got[64] > 0.95
    assert soft[64] == [] and soft[127] and all(f < 3.0 for _, f in soft[127])

"""The play pipeline end to end: every sample song is planned and replayed through the
independent check (planner.check), which shares only the hand model with the planner."""

from __future__ import annotations

import itertools
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.hand.model import load_hand
from planner.music.midi import Note, Song, load_song
from planner.play.legacy import Planner, plan_song
from planner.trajfile import read_trajectory

ROOT = Path(__file__).resolve().parents[1]
SONGS = sorted(p.stem for p in (ROOT / "songs").glob("*.mid"))
# Regression floors: frame F1 measured on each sample song today (see the issue note),
# less about 0.005; the target, 0.98, is asserted for every one of them.
F1_FLOOR = {"twinkle": 0.985, "ode_to_joy": 0.98, "chords": 0.985, "scale": 0.98,
            "fur_elise": 0.985, "fast": 0.99, "leaps": 0.985}
# Songs beyond this hand (songs/stress/README.md): floors only, measured today less 0.01
STRESS = ["fast_six_keys", "leaps_legato"]
STRESS_FLOOR = {"fast_six_keys": 0.94, "leaps_legato": 0.75}


@pytest.fixture(scope="module")
def planner():
    return Planner(load_hand("default"))


@pytest.fixture(scope="module")
def planned(planner, tmp_path_factory):
    out = {}
    d = tmp_path_factory.mktemp("play")
    for name in SONGS:
        path = d / f"{name}.csv"
        res = plan_song(load_song(ROOT / "songs" / f"{name}.mid"), planner.hand, str(path),
                        song_name=f"{name}.mid", planner=planner)
        out[name] = (path, res, check_trajectory(str(path), str(ROOT / "songs" / f"{name}.mid")))
    return out


def test_at_least_six_sample_songs():
    assert len(SONGS) >= 6


@pytest.mark.parametrize("name", SONGS)
def test_song_stays_inside_every_limit(planned, name):
    _, _, rep = planned[name]
    bad = [lim for lim in rep.limits if lim.count]
    assert bad == [], rep.summary()


@pytest.mark.parametrize("name", SONGS)
def test_song_never_pushes_through_a_key_bed(planned, name):
    _, _, rep = planned[name]
    assert len(rep.play.key_bed_hits) == 0, rep.summary()


@pytest.mark.parametrize("name", SONGS)
def test_song_presses_no_wrong_key(planned, name):
    _, _, rep = planned[name]
    assert len(rep.play.wrong_presses) == 0, rep.summary()


@pytest.mark.parametrize("name", SONGS)
def test_song_is_played_mostly_right(planned, name):
    """Floors below the target that hold today: precision (no key pressed that should not
    sound), that most notes are hit, and the frame F1 measured today."""
    _, res, rep = planned[name]
    assert rep.play.precision >= 0.95, rep.summary()
    assert rep.play.notes_hit >= 0.7 * len(res.notes), rep.summary()
    assert rep.play.f1 >= F1_FLOOR.get(name, 0.9), rep.summary()


def _surface_under(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Resting top (m) of the key whose footprint holds each point (x, y); -inf off the keys."""
    from planner.music import keyboard as kb

    kt = kb.key_table()
    inside = ((kt["x_min"] <= x[:, None]) & (x[:, None] <= kt["x_max"])
              & (kt["y_min"] <= y[:, None]) & (y[:, None] <= kt["y_max"]))
    top = np.where(inside, kt["top_z"][None, :], -np.inf)
    return top.max(axis=1)


@pytest.mark.parametrize("name", ["leaps", "scale", "fur_elise"])
def test_tips_clear_the_keys_while_the_arm_travels(planned, name):
    """Whenever the rail moves, every fingertip is at least TRAVEL_CLEARANCE_M above the
    top of the key under it (exact footprints: the planner's own test is more cautious),
    or inside the part of a key no other key overhangs, TRAVEL_INFLATE_M from its sides:
    a finger leaving the key it has let go of may still be in it as the arm starts, and
    a finger holding its key while the arm moves (``shift``) is in it, above the key bed
    (whether a key sounds that should not is the song check's business)."""
    from planner.ik import exposed_range_x
    from planner.music import keyboard as kb
    from planner.play.legacy import TRAVEL_CLEARANCE_M, TRAVEL_INFLATE_M

    path, res, _ = planned[name]
    tr = read_trajectory(str(path))
    hand = load_hand("default")
    rail = hand.joint_names.index("rail")
    step = np.abs(np.diff(tr.q[:, rail])) > 1e-7
    moving = np.flatnonzero(step[:-1] & step[1:]) + 1  # the rail moves into and out of the row
    assert res.travels >= 1 and moving.size > 0
    tips = np.array([hand.tip_positions(q) for q in tr.q[moving]])  # (T, 5, 3)
    x, y, z = (tips[..., i].ravel() for i in range(3))
    clearance = z - _surface_under(x, y)
    inside = np.zeros(len(x), dtype=bool)
    for i in np.flatnonzero(clearance < TRAVEL_CLEARANCE_M - 1e-4):
        k = kb.key_under(x[i], y[i])
        if k is not None:
            lo, hi = exposed_range_x(k.pitch)
            inside[i] = lo + TRAVEL_INFLATE_M - 1e-6 <= x[i] <= hi - TRAVEL_INFLATE_M + 1e-6
    assert clearance[~inside].min() >= TRAVEL_CLEARANCE_M - 1e-4, clearance[~inside].min()
    assert clearance.min() >= -kb.KEY_BED_DEPTH_M + 1e-4  # (and never through a key bed)


def test_one_hand_position_serves_a_five_finger_tune(planner, tmp_path):
    """Five neighbouring keys, one per finger, in any order: the hand never travels (its
    position is chosen by IK to serve every note the fingering keeps there)."""
    from planner.music.midi import write_notes_midi

    pitches = [60, 64, 62, 67, 65, 60, 67, 64, 62, 65, 60]
    notes = [Note(p, 0.3 * i, 0.3 * i + 0.25, 80) for i, p in enumerate(pitches)]
    song, path = tmp_path / "five.mid", tmp_path / "five.csv"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(path), planner=planner)
    assert res.travels == 0 and res.shifts == 0
    rep = check_trajectory(str(path), str(song))
    assert rep.play.f1 >= 0.98 and not rep.play.wrong_presses, rep.summary()
    assert not rep.play.key_bed_hits and all(v.count == 0 for v in rep.limits)


@pytest.mark.parametrize("name", SONGS)
def test_song_frame_f1_reaches_target(planned, name):
    _, _, rep = planned[name]
    assert rep.play.f1 >= 0.98 and not rep.play.wrong_presses, rep.summary()


@pytest.fixture(scope="module")
def stressed(planner, tmp_path_factory):
    out = {}
    d = tmp_path_factory.mktemp("stress")
    for name in STRESS:
        song = ROOT / "songs" / "stress" / f"{name}.mid"
        path = d / f"{name}.csv"
        res = plan_song(load_song(song), planner.hand, str(path), song_name=f"{name}.mid", planner=planner)
        out[name] = (res, check_trajectory(str(path), str(song)))
    return out


@pytest.mark.parametrize("name", STRESS)
def test_a_song_beyond_the_hand_is_planned_safely_and_named(stressed, name):
    """Beyond the hand, the plan is still safe (no wrong key, no key bed, every limit) and
    honest: every note the check finds missed is one the summary names, with a reason."""
    res, rep = stressed[name]
    assert not rep.play.wrong_presses and not rep.play.key_bed_hits, rep.summary()
    assert all(v.count == 0 for v in rep.limits), rep.summary()
    assert rep.play.f1 >= STRESS_FLOOR[name], rep.summary()
    named = {i for i, n in enumerate(res.notes) if n.reason}
    assert named == {m.note for m in rep.play.missed}, rep.summary()
    assert rep.play.claims and not rep.play.claim_mismatches


@pytest.mark.parametrize("name", SONGS)
def test_reported_notes_match_the_song(planned, name):
    _, res, _ = planned[name]
    song = load_song(ROOT / "songs" / f"{name}.mid")
    assert len(res.notes) == len(song.notes)
    assert all(n.finger is not None or n.reason for n in res.notes)


def test_same_input_same_bytes(planner, tmp_path):
    song = load_song(ROOT / "songs" / "fur_elise.mid")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    plan_song(song, planner.hand, str(a), song_name="x.mid", planner=planner)
    plan_song(song, planner.hand, str(b), song_name="x.mid", planner=Planner(load_hand("default")))
    assert a.read_bytes() == b.read_bytes()


def test_file_format(planned):
    path, res, _ = planned["twinkle"]
    tr = read_trajectory(str(path))
    hand = load_hand("default")
    assert tr.complete and tr.metadata["task"] == "play" and tr.metadata["rate_hz"] == 100.0
    assert tr.joint_names == hand.joint_names and tr.motor_names == hand.motor_names
    assert tr.t_s[0] == 0.0 and np.allclose(np.diff(tr.t_s), 0.01, atol=1e-6)
    assert len(tr.t_s) == res.rows
    # motors follow the actuator model
    assert np.allclose(tr.q_motor, hand.motor_angles(tr.q), atol=1e-4)


def test_rate_option(planner, tmp_path):
    song = load_song(ROOT / "songs" / "twinkle.mid")
    p = tmp_path / "r.csv"
    plan_song(song, planner.hand, str(p), rate_hz=50.0, planner=planner)
    tr = read_trajectory(str(p))
    assert tr.metadata["rate_hz"] == 50.0 and np.allclose(np.diff(tr.t_s), 0.02, atol=1e-6)


def test_infeasible_note_is_named_and_rest_is_planned(planner, tmp_path):
    # a 5-note chord spanning two octaves cannot be held by one hand
    notes = tuple(Note(p, 0.5, 1.5, 80) for p in (48, 55, 60, 67, 72)) + (Note(64, 2.0, 2.5, 80),)
    res = plan_song(Song(notes, 2.5, (), "t"), planner.hand, str(tmp_path / "c.csv"), planner=planner)
    bad = [n for n in res.notes if n.reason]
    assert bad and all("wider than the hand" in n.reason or "reach" in n.reason for n in bad)
    assert res.notes[-1].reason is None  # the last note is still played
    rep = check_trajectory(str(tmp_path / "c.csv"))
    assert all(v.count == 0 for v in rep.limits)


def _cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, str(ROOT / "cli.py"), *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300, check=False)


def test_cli_streams_to_stdout():
    r = _cli("play", str(ROOT / "songs" / "scale.mid"), "-o", "-")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith('# {"format": "hand-trajectory"')
    assert lines[-1].startswith('# {"end": true')
    assert "scale.mid: 15 notes" in r.stderr


def test_cli_bad_midi_exits_2_and_leaves_no_file(tmp_path):
    bad = tmp_path / "bad.mid"
    bad.write_bytes(b"MThd\x00\x00\x00\x06\x00\x01\x00")
    out = tmp_path / "out.csv"
    r = _cli("play", str(bad), "-o", str(out))
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert not out.exists() and not list(tmp_path.glob(".out.csv*"))


def test_cli_missing_file_and_bad_rate(tmp_path):
    r = _cli("play", str(tmp_path / "none.mid"))
    assert r.returncode == 2 and "Traceback" not in r.stderr
    r = _cli("play", str(ROOT / "songs" / "scale.mid"), "--rate", "0", "-o", str(tmp_path / "x.csv"))
    assert r.returncode == 2 and "rate" in r.stderr and not (tmp_path / "x.csv").exists()


def test_cli_strict_exits_1_on_infeasible(tmp_path):
    from planner.music.midi import write_notes_midi

    song = tmp_path / "wide.mid"
    write_notes_midi([Note(p, 0.0, 1.0, 80) for p in (36, 48, 60, 72, 84)], song)
    r = _cli("play", str(song), "-o", str(tmp_path / "w.csv"), "--strict")
    assert r.returncode == 1
    assert "infeasible" in r.stderr
    assert (tmp_path / "w.csv").exists()  # the plan is still written


def test_leaps_cannot_reach_the_target_on_this_rail(planner):
    """A bound, not a plan: between two notes the hand must move its rail at least the
    leap less the widest span two fingertips can take (each at its sideways reach), and
    the rail cannot do that faster than bang-bang at its top acceleration and speed.
    Even with instant fingers, the frames lost to that exceed what 0.98 allows: the
    issue's target is out of this hand's reach for `leaps_legato.mid` (a fact about the hardware
    and the song, measured here so that it fails if either changes)."""
    from planner.music import keyboard as kb

    r = planner.reach
    span = max(r.offset_m[b] + r.reach_m[b] - (r.offset_m[a] - r.reach_m[a])
               for a in r.offset_m for b in r.offset_m)
    v, acc = r.rail_speed_m_s, r.rail_accel_m_s2

    def t_min(d):  # bang-bang (trapezoid) time over d metres
        return 2.0 * np.sqrt(d / acc) if d <= v * v / acc else d / v + v / acc

    notes = sorted(load_song(ROOT / "songs" / "stress" / "leaps_legato.mid").notes, key=lambda n: n.onset_s)
    lost = 0.0
    for a, b in itertools.pairwise(notes):
        d = max(0.0, abs(kb.key(b.pitch).center_x_m - kb.key(a.pitch).center_x_m) - span)
        lost += max(0.0, t_min(d) - (b.onset_s - a.offset_s)) if d > 0 else 0.0
    recall = 1.0 - lost / sum(n.offset_s - n.onset_s for n in notes)
    f1_bound = 2 * recall / (1 + recall)
    assert 0.9 < f1_bound < 0.98, f1_bound


def test_parts_are_cut_only_where_every_key_is_up():
    from planner.play.legacy import FIRST_PART_NOTES, PART_NOTES, _parts
    from planner.targets import MOVE_S

    legato = [Note(60 + i % 5, 0.1 * i, 0.1 * i + 0.1, 80) for i in range(3 * PART_NOTES)]
    assert [len(p) for p in _parts(legato)] == [len(legato)]  # no pause: one part
    paused = [Note(n.pitch, n.onset_s + (0.2 if i >= PART_NOTES + 7 else 0.0),
                   n.offset_s + (0.2 if i >= PART_NOTES + 7 else 0.0), 80) for i, n in enumerate(legato)]
    parts = _parts(paused)
    assert [len(p) for p in parts] == [PART_NOTES + 7, 2 * PART_NOTES - 7]
    for a, b in itertools.pairwise(parts):
        assert min(paused[i].onset_s for i in b) - max(paused[i].offset_s for i in a) >= MOVE_S
    # the first part is cut sooner (its fingering is all the first rows wait for)
    early = [Note(n.pitch, n.onset_s + (0.2 if i >= FIRST_PART_NOTES + 3 else 0.0),
                  n.offset_s + (0.2 if i >= FIRST_PART_NOTES + 3 else 0.0), 80) for i, n in enumerate(legato)]
    assert [len(p) for p in _parts(early)] == [FIRST_PART_NOTES + 3, len(legato) - FIRST_PART_NOTES - 3]


def test_a_song_planned_in_parts_is_played_as_well(planner, tmp_path, monkeypatch):
    """Twinkle three times over, 0.5 s apart, planned in parts of (at least) 14 notes: the
    parts join on one timeline and the check finds the song played as well as in one go."""
    import planner.play.legacy as play_mod
    from planner.music.midi import write_notes_midi

    base = load_song(ROOT / "songs" / "twinkle.mid").notes
    span = max(n.offset_s for n in base) + 0.5
    notes = [Note(n.pitch, n.onset_s + k * span, n.offset_s + k * span, n.velocity)
             for k in range(3) for n in base]
    song = tmp_path / "three.mid"
    write_notes_midi(notes, song)
    monkeypatch.setattr(play_mod, "PART_NOTES", 14)
    monkeypatch.setattr(play_mod, "FIRST_PART_NOTES", 14)
    assert len(play_mod._parts(notes)) == 3
    path = tmp_path / "three.csv"
    res = plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    assert len(res.notes) == 42 and not res.infeasible
    assert rep.play.f1 >= F1_FLOOR["twinkle"] and not rep.play.key_bed_hits, rep.summary()
    assert all(v.count == 0 for v in rep.limits)


def test_cutting_the_plan_into_chunks_costs_no_time(planner, tmp_path, monkeypatch):
    """Rows go out chunk by chunk (a cut at a release when every key is up); the next
    chunk's motions start no sooner than the cut, so a cut must come early enough for
    the next press. Short legato notes (25 ms apart) planned with a cut at every release
    play as well as with no cut at all (found on a random melody: a press held back by
    the first cut ended its note late, a key down where none should be)."""
    import planner.play.legacy as play_mod
    from planner.music.midi import write_notes_midi

    pitches = [74, 72, 76, 77, 74, 76, 77, 79, 77, 76, 74, 72]
    notes = [Note(p, 0.25 * i, 0.25 * i + (0.1125 if i % 2 else 0.225), 90) for i, p in enumerate(pitches)]
    song = tmp_path / "short.mid"
    write_notes_midi(notes, song)
    f1 = {}
    for chunk in (1, 10_000):
        monkeypatch.setattr(play_mod, "FIRST_CHUNK_PHASES", chunk)
        monkeypatch.setattr(play_mod, "CHUNK_PHASES", chunk)
        path = tmp_path / f"short{chunk}.csv"
        plan_song(load_song(song), planner.hand, str(path), planner=planner)
        rep = check_trajectory(str(path), str(song))
        assert len(rep.play.wrong_presses) == 0 and not rep.play.key_bed_hits, rep.summary()
        f1[chunk] = rep.play.f1
    assert f1[1] >= f1[10_000] - 0.005, f1


def test_a_chord_wider_than_the_hand_is_played_in_part(planner, tmp_path):
    """C3-E3-G3 with E5 on top: the triad fits the hand, the four notes do not. The hand
    plays the largest part it can hold and names the note it leaves out; the notes
    after it are still played (a held key no longer makes every later note unplayable)."""
    notes = tuple(Note(p, 0.0, 1.0, 80) for p in (48, 52, 55, 76)) + (Note(60, 1.5, 2.0, 80),)
    res = plan_song(Song(notes, 2.0, (), "t"), planner.hand, str(tmp_path / "w.csv"), planner=planner)
    left = [n for n in res.notes if n.reason]
    assert len(left) == 1 and "left out" in left[0].reason and "wider than the hand" in left[0].reason
    assert {n.pitch for n in res.notes if not n.reason} == {48, 52, 55, 76, 60} - {left[0].pitch}
    rep = check_trajectory(str(tmp_path / "w.csv"))
    assert not rep.play.key_bed_hits and all(v.count == 0 for v in rep.limits)


def _random_walk(seed: int, n: int, tempo_bpm: float, leap_p: float) -> list:
    """A melody wandering over three octaves of C major (seeded: the same notes every run)."""
    import random

    rng = random.Random(seed)
    scale, deg, t, out = (0, 2, 4, 5, 7, 9, 11), 14, 0.0, []
    for _ in range(n):
        step = rng.choice([-2, -1, -1, 1, 1, 2]) if rng.random() > leap_p else rng.choice([-7, -5, 5, 7])
        deg = max(0, min(34, deg + step))
        d = 60.0 / tempo_bpm * rng.choice([0.5, 1, 1, 1, 2])
        out.append(Note(48 + 12 * (deg // 7) + scale[deg % 7], t, t + 0.9 * d, rng.randint(50, 110)))
        t += d
    return out


@pytest.mark.parametrize("seed,tempo,leaps", [(3, 140, 0.1), (5, 240, 0.05), (11, 100, 0.4)])
def test_random_melodies_never_push_through_a_key(planner, tmp_path, seed, tempo, leaps):
    """Melodies like the ones that once drove a finger across keys it could not clear,
    or left a thumb resting in them: no key-bed hit, no limit broken, most notes played,
    hardly a key down out of its note."""
    from planner.music.midi import write_notes_midi

    song, path = tmp_path / "walk.mid", tmp_path / "walk.csv"
    write_notes_midi(_random_walk(seed, 60, tempo, leaps), song)
    res = plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    assert not rep.play.key_bed_hits, rep.summary()
    assert all(v.count == 0 for v in rep.limits), rep.summary()
    # (notes the fingers cannot strike before they are half over are left out, and named)
    assert len(res.infeasible) <= 15 and rep.play.f1 >= 0.7, rep.summary()
    assert rep.play.precision >= 0.99, rep.summary()


def test_a_note_that_cannot_be_struck_in_time_is_left_out_and_named(planner, tmp_path):
    """Four octaves up and down every 0.15 s: the rail cannot get there in time. The notes
    the hand cannot strike before they are half over are left out and named (by the
    fingering, or by the timing when it finds them too late), and no key is down out of
    its note."""
    from planner.music.midi import write_notes_midi

    notes = [Note(36 if i % 2 else 84, 0.5 + 0.15 * i, 0.6 + 0.15 * i, 80) for i in range(8)]
    song, path = tmp_path / "tr.mid", tmp_path / "tr.csv"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    late = [n for n in res.notes if n.reason and ("too late" in n.reason or "left out" in n.reason)]
    assert late and not rep.play.wrong_presses, rep.summary()


def test_blended_motions_stay_within_every_limit_at_any_overlap(planner, tmp_path, monkeypatch):
    """A finger's motion may start before its previous one ends (``Phase.blend_s``): the
    two add up in the overlap, which the timing QP may make anything up to blend_s. The
    sum is checked here on a fine grid of overlaps and times, independently of how the
    planner checked it, and the tip over the keys is left to the song check."""
    from planner.play import legacy as P
    from planner.trajectory import min_jerk_rates

    pairs = []
    orig = P._Timeline._move

    def move(self, *a, **kw):
        n = len(self.phases)
        orig(self, *a, **kw)
        if len(self.phases) > n and self.phases[-1][0].blend_s > 0.0:
            ph = self.phases[-1][0]
            prev = self.phases[ph.blend_after - self.offset][0]
            pairs.append((prev, ph))

    monkeypatch.setattr(P._Timeline, "_move", move)
    hand = planner.hand
    for name in ("twinkle", "fur_elise"):
        plan_song(load_song(ROOT / "songs" / f"{name}.mid"), hand, str(tmp_path / f"{name}.csv"), planner=planner)
    assert len(pairs) > 10  # the songs use it
    for prev, ph in pairs:
        assert ph.blend_s <= min(prev.duration_s - prev.blend_s, ph.duration_s) + 1e-12
        for o in np.linspace(0.0, ph.blend_s, 25):
            t = np.linspace(prev.duration_s - o, prev.duration_s, 200)
            v1, a1 = min_jerk_rates(t / prev.duration_s)
            v2, a2 = min_jerk_rates((t - prev.duration_s + o) / ph.duration_s)
            v = np.abs(np.outer(v1 / prev.duration_s, prev.delta) + np.outer(v2 / ph.duration_s, ph.delta))
            a = np.abs(np.outer(a1 / prev.duration_s**2, prev.delta) + np.outer(a2 / ph.duration_s**2, ph.delta))
            assert np.all(v <= hand.velocity * (1 + 1e-3)), (o, v.max(axis=0))
            assert np.all(a <= hand.acceleration * (1 + 1e-3)), (o, a.max(axis=0))


def test_a_finger_path_found_clear_is_clear_all_along(planner):
    """``_finger_path_clear`` samples a finger's straight joint-space move densely enough:
    whenever it finds a move clear, the move sampled 400 times is clear too (within 1 mm
    of the same rule). A long crossing once dipped onto a black key between 7 samples."""
    from planner.ik import surfaces_under
    from planner.play.legacy import GRAZE_M, TRAVEL_INFLATE_M, _Timeline

    hand = planner.hand
    q0 = planner.posture_at(0.1)
    tl = _Timeline(planner, hand, q0, None, 0.01)
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(400):
        f = hand.fingers[rng.integers(len(hand.fingers))]
        js = hand.joint_slice(f)
        qa, qb = q0.copy(), q0.copy()
        qa[js] = hand.lower[js] + rng.random(len(js)) * (hand.upper[js] - hand.lower[js])
        qb[js] = hand.lower[js] + rng.random(len(js)) * (hand.upper[js] - hand.lower[js])
        qa, qb = hand.apply_couplings(qa), hand.apply_couplings(qb)
        if not tl._finger_path_clear(qa, qb, f):
            continue
        checked += 1
        k = hand.fingers.index(f)
        tips = np.array([hand.tip_positions(hand.apply_couplings(qa + u * (qb - qa)))[k]
                         for u in np.linspace(0.0, 1.0, 400)[1:-1]])
        gap = tips[:, 2] - (surfaces_under(tips[:, 0], tips[:, 1], TRAVEL_INFLATE_M) - GRAZE_M)
        assert gap.min() >= -0.001, (f, gap.min())
    assert checked >= 50


def test_a_chord_the_hand_cannot_hold_here_is_played_from_the_bottom(planner, tmp_path):
    """C3-E3-G3 with E4 on top at t = 0: the fingering's reach model allows it, the
    whole-hand IK does not. The hand takes the lowest three and names the top one; no
    finger lands on a key it was not given (a finger whose IK had not converged once
    pressed F3 here for G3)."""
    from planner.music.midi import write_notes_midi

    notes = [Note(48, 0.0, 0.9, 70), Note(52, 0.0, 0.9, 70), Note(55, 0.0, 0.9, 70),
             Note(64, 0.0, 0.45, 95), Note(65, 0.5, 0.95, 63)]
    song, path = tmp_path / "wide.mid", tmp_path / "wide.csv"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    assert len(rep.play.wrong_presses) == 0 and not rep.play.key_bed_hits, rep.summary()
    why = {r.pitch: r.reason for r in res.infeasible}
    assert why[64].startswith("chord wider than the hand"), why
    assert {48, 52, 55} <= {p["pitch"] if isinstance(p, dict) else p.pitch for p in rep.play.played}


def test_a_note_whose_key_cannot_be_up_by_its_end_is_left_out():
    """A press the timing QP can only put down late pushes its release late too: a key
    still down in the first frame after its note would be a wrong press, so the note is
    left out (named), its press and release merged into one motion over the key."""
    from planner.play.legacy import _drop_hopeless
    from planner.trajectory import Phase

    dt = 0.01
    notes = [Note(60, 0.0, 0.2, 80)]
    d = np.array([-1.0, 0.0])

    def case(release_start):
        phases = [Phase(d, 0.1, 0.5, 0.0, 1.0), Phase(-d, 0.1, 0.5, 0.195, 0.3)]
        meta = [(phases[0], "press", 0), (phases[1], "release", 0)]
        reasons = {}
        dropped = _drop_hopeless(phases, meta, np.array([0.0, release_start]), notes, reasons, dt, np.ones(2), np.ones(2))
        return dropped, phases, reasons

    dropped, phases, reasons = case(0.1)  # up at 0.15: in time
    assert not dropped and not reasons
    dropped, phases, reasons = case(0.16)  # up at 0.21: down in the frame at 0.20
    assert dropped and reasons[0].startswith("too late")
    assert np.allclose(phases[0].delta, 0.0) and phases[0].weight == 0.0


def test_a_key_let_go_of_is_up_on_time_though_the_arm_moves_on(planner, tmp_path):
    """The arm may start while a finger is still on its way up out of the key it let go
    of, but only once that key is up: moving sooner (the wrist lowering the finger) once
    kept C5 down into the first frame after its note (a random melody's first bars)."""
    from planner.music.midi import write_notes_midi

    tune = [(71, 0.0, 0.225), (72, 0.25, 0.3625), (69, 0.375, 0.6), (72, 0.625, 1.075),
            (76, 1.125, 1.2375), (77, 1.25, 1.475), (79, 1.5, 1.95), (77, 2.0, 2.225),
            (76, 2.25, 2.3625), (74, 2.375, 2.6)]
    song, path = tmp_path / "tune.mid", tmp_path / "tune.csv"
    write_notes_midi([Note(p, a, b, 80) for p, a, b in tune], song)
    plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    assert len(rep.play.wrong_presses) == 0 and not rep.play.key_bed_hits, rep.summary()
    assert rep.play.f1 >= 0.95, rep.summary()


REPEATED_DESCENT = [66] * 7 + [61] * 3 + [56] * 2 + [51] * 2 + [46] + [41] * 3 + [46, 51, 49] + [44] * 9 + [46] \
    + [41] * 7 + [43] * 3 + [41] * 7  # a random song of repeated notes (seed 1 of the session's generator)


def test_a_finger_curled_in_front_of_the_keys_rides_along_when_the_hand_travels(planner, tmp_path):
    """Repeated notes stepping down by fourths, 0.15 s long every 0.2146 s: a change of
    hand position where a finger must go from curled in front of the keys to reaching
    over them dipped into a key on its straight way down at every lift height, and the
    hand fell back on raising the wrist (0.35 s): six notes were left out, too late (F1
    0.893). The finger now rides along lifted and finds its own way there once the arm
    stops (F1 0.929; its way over the keys, 0.24 s, still costs the note after it)."""
    from planner.music.midi import write_notes_midi

    step = 0.21458333333333332
    notes = [Note(p, k * step, k * step + 0.15, 90) for k, p in enumerate(REPEATED_DESCENT)]
    song, path = tmp_path / "descent.mid", tmp_path / "descent.csv"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    assert len(rep.play.wrong_presses) == 0 and not rep.play.key_bed_hits, rep.summary()
    # the planner leaves 3 out; since its summary is its own replay (issue 14), the two it
    # strikes for 20 % and 27 % of their frames count as not played too (they had been
    # called played, and the check found them missed)
    assert len(res.infeasible) <= 5 and rep.play.f1 >= 0.92, (res.infeasible, rep.summary())
    assert {n.index for n in res.infeasible} == {m.note for m in rep.play.missed}


def test_the_hand_moves_while_a_key_is_held_when_the_next_note_needs_it(planned, planner):
    """Fur Elise: B (middle) then, 21 ms after it, D with the pinky, which the hand
    position cannot reach. Travelling between them (every key up) cost 90 ms of music;
    now the arm moves while the middle still holds B, the middle following it on its
    key. The independent check sees the rail move inside one unbroken key-down
    interval, and the song in time."""
    path, res, rep = planned["fur_elise"]
    assert res.shifts >= 1
    assert len(rep.play.wrong_presses) == 0 and not rep.play.key_bed_hits, rep.summary()
    assert rep.play.f1 >= 0.98, rep.summary()
    tr = read_trajectory(str(path))
    rail = tr.q[:, planner.hand.joint_names.index("rail")]
    moving = tr.t_s[1:][np.abs(np.diff(rail)) > 1e-6]
    held = [p for p in rep.play.played if any(p.start_s < t < p.end_s - 0.01 for t in moving)]
    assert held, "the rail never moved while a key was down"


def test_a_new_hand_position_is_found_from_a_twisted_wrist(planner):
    """The IK for a new hand position starts from where the hand is, so that it moves
    least, and keeps the wrist near where it is; a wrist twisted far by earlier positions
    (here 0.51 rad flexed, 0.44 rad deviated: the hand as a random melody left it) left no
    shape with the thumb on B5 that it could use, the hand stayed, and the notes after
    failed one by one (F1 0.945 -> 0.870). The search now tries again from the natural
    hand at that rail."""
    from planner.play.legacy import _best_position, _Timeline
    from planner.targets import Press, PressInterval

    q = np.array([0.23498978529523593, 0.5088737420656119, -0.43598831115609304, 1.0471975511965976,
                  0.49493363971558685, 1.3962634015954636, -0.3490658503988659, -0.2623448959888377,
                  1.1523150257018826, 0.7685941221431557, -0.261799387799, -0.22780999200490537,
                  1.3200292158472278, 0.880459486970101, -0.17511747579145281, -0.2389022691153197,
                  1.1975173131590298, 0.7987440478770729, -0.21489263567380296, -0.20066169386292246,
                  0.6297923080349153, 0.4200714694592885])
    tl = _Timeline(planner, planner.hand, q, None, 0.01)
    rail = 0.3591976406704055
    notes = [(83, "thumb"), (84, "index"), (86, "middle"), (88, "ring"), (89, "ring"), (91, "pinky")]
    presses = [Press(f, p, 1.0, i, 80) for i, (p, f) in enumerate(notes)]
    events = [(0.43 * i, 1, pr.pitch, PressInterval(0.43 * i, 0.43 * i + 0.39, pr)) for i, pr in enumerate(presses)]
    seg, covered = _best_position(planner, tl, events, presses[:1], 0.0, rail,
                                  {pr.note_index: rail for pr in presses}, {})
    assert seg is not None and covered >= 1
    assert planner.press_q("thumb", 83, seg)[1].converged


def test_walking_thirds_are_fingered_as_the_hand_can_hold_them(planner, tmp_path):
    """Thirds walking down to C#4-E4: the lateral reach model lets thumb and middle take
    that one, but with the thumb on a black key the index between them cannot clear the
    keys; the fingering asks the whole-hand IK (``Planner.pair_ok``) and every third is
    played (the top note of C#4-E4 was left out as a 'chord wider than the hand')."""
    from planner.music.midi import write_notes_midi

    thirds = [(65, 69), (63, 66), (61, 64), (63, 66), (64, 67)]
    notes = [Note(p, 0.6 * i, 0.6 * i + 0.54, 80) for i, pair in enumerate(thirds) for p in pair]
    song = tmp_path / "thirds.mid"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(tmp_path / "t.csv"), planner=planner)
    assert [(n.pitch, n.reason) for n in res.notes if n.reason] == []
    assert not planner.pair_ok("thumb", 61, "middle", 64)
    rep = check_trajectory(str(tmp_path / "t.csv"), str(song))
    assert rep.play.notes_hit == len(notes) and not rep.play.wrong_presses


def test_pair_ok_ignores_argument_order_and_octave(planner):
    for f1, p1, f2, p2 in [("thumb", 61, "middle", 64), ("index", 60, "pinky", 72),
                           ("thumb", 48, "pinky", 60), ("ring", 66, "pinky", 70)]:
        ok = planner.pair_ok(f1, p1, f2, p2)
        assert planner.pair_ok(f2, p2, f1, p1) == ok
        assert planner.pair_ok(f1, p1 + 12, f2, p2 + 12) == ok
        assert planner.pair_ok(f1, p1 - 24, f2, p2 - 24) == ok
    assert planner.pair_ok("index", 60, "index", 60) and not planner.pair_ok("index", 60, "index", 62)
    assert planner.pair_ok("thumb", 60, "pinky", 67)  # a fifth: the hand's natural span
    assert not planner.pair_ok("thumb", 60, "index", 84)  # two octaves


def test_the_shipped_pair_table_is_the_planners_own():
    """``planner/tables`` holds ``Planner.pair_table`` for the default hand's URDF (it
    saves the time of working its answers out); the file must be for today's URDF and
    agree with the IK, re-asked here on a sample of its entries, the 'no's included
    (after a change of the hand or the IK: ``python scripts/make_pair_table.py``)."""
    import json

    from planner.play.legacy import pair_table_path

    hand = load_hand("default")
    path = pair_table_path(hand.urdf_sha256)
    assert path.exists(), "run python scripts/make_pair_table.py"
    data = json.loads(path.read_text())
    assert data["urdf_sha256"] == hand.urdf_sha256
    entries = [(k, iv, c) for k, row in sorted(data["pairs"].items())
               for iv, c in enumerate(row, start=data["first_interval"]) if c != "-"]
    assert len(entries) > 1000
    fresh = Planner(hand)
    assert len(fresh._pairs) == len(entries)  # (loaded)
    fresh._pairs.clear()
    no = [e for e in entries if e[2] == "0"]
    yes = [e for e in entries if e[2] == "1"]
    assert no and yes
    for k, iv, c in no[:: max(1, len(no) // 12)] + yes[:: max(1, len(yes) // 12)]:
        f1, f2, pc = k.split()
        assert fresh.pair_ok(f1, 60 + int(pc), f2, 60 + int(pc) + iv) == (c == "1"), (k, iv)
    # and the fingers' ranges at one hand position, loaded, are the IK's own
    assert fresh.reach.range_m == data["range_m"]
    assert fresh._finger_ranges(hand.tip_positions(fresh.rest)) == data["range_m"]


def test_a_press_from_high_waits_for_a_clear_way_down(planner):
    """After a leap the pinky, high above E5, may start its press while the rail still
    moves, but only so late (``_press_lag`` with the path checked) that its tip, sampled
    every 0.5 ms until it touches, stays TRAVEL_CLEARANCE_M above every key it passes
    over (its own key's top over the part of E5 no other key overhangs); 5 ms sooner it
    would not, and the check makes it wait longer than the touch rule alone."""
    from planner.ik import exposed_range_x, press_target, surfaces_under
    from planner.music import keyboard as kb
    from planner.play.legacy import (
        HIGH_M,
        PRESS_LAG_STEP_S,
        TRAVEL_CLEARANCE_M,
        TRAVEL_INFLATE_M,
        _key_crossing,
        _Timeline,
    )
    from planner.trajectory import min_jerk, phase_duration

    hand = planner.hand
    rail = hand.index["rail"]
    seg = planner.anchor([press_target("pinky", 76)], 0.146, None)
    assert seg is not None
    tl = _Timeline(planner, hand, planner.bases[seg], seg, 0.01)
    q_above = tl._with_finger("pinky", planner.above_q("pinky", 76, seg, HIGH_M))
    q_press = tl._with_finger("pinky", planner.press_q("pinky", 76, seg)[0], q_above)
    T = phase_duration(q_press - q_above, hand.velocity, hand.acceleration)
    d_arm = np.zeros(hand.n)
    d_arm[rail] = 0.25  # the rail arriving from 25 cm to the left
    T_arm = phase_duration(d_arm, hand.velocity, hand.acceleration)
    lag = tl._press_lag("pinky", 76, q_above, q_press, T, d_arm, T_arm, path=True)
    assert lag > tl._press_lag("pinky", 76, q_above, q_press, T, d_arm, T_arm)
    assert lag < T_arm  # (it does start before the rail has stopped)
    touch = _key_crossing(hand, q_above, q_press, "pinky", 76, depth_m=-TRAVEL_CLEARANCE_M)
    lo, hi = exposed_range_x(76)
    k = hand.fingers.index("pinky")

    def clearance(start):
        tau = np.arange(start, min(start + touch * T, T_arm), 0.0005)
        Q = (q_above - (1.0 - min_jerk(tau / T_arm))[:, None] * d_arm
             + min_jerk((tau - start) / T)[:, None] * (q_press - q_above))
        tips = np.array([hand.tip_positions(q)[k] for q in hand.apply_couplings(Q)])
        under = surfaces_under(tips[:, 0], tips[:, 1], TRAVEL_INFLATE_M)
        under = np.where((lo <= tips[:, 0]) & (tips[:, 0] <= hi), kb.key(76).top_z_m, under)
        return float(np.min(tips[:, 2] - under))

    assert clearance(lag) >= TRAVEL_CLEARANCE_M - 2e-4
    assert clearance(lag - PRESS_LAG_STEP_S) < TRAVEL_CLEARANCE_M


def test_a_held_key_the_hand_must_leave_is_let_go_and_named(planner, tmp_path):
    """C3 held 3 s under thirds two octaves up: the fingering lets C3 go early (the hand
    cannot hold it and reach them), the plan lifts it then, the thirds are all played,
    and the summary names the cut ("cut short", with how much)."""
    from planner.fingering import CUT_LEAD_S
    from planner.music.midi import write_notes_midi
    from planner.play.legacy import format_summary

    thirds = ((72, 76), (74, 77), (76, 79), (77, 81), (79, 83))
    notes = [Note(48, 0.0, 3.0, 80)] + [Note(p, 0.5 + 0.5 * k, 0.95 + 0.5 * k, 80)
                                        for k, pair in enumerate(thirds) for p in pair]
    song = tmp_path / "cut.mid"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(tmp_path / "c.csv"), planner=planner)
    # let go after 7 % of its frames, C3 is not played (the check's rule): named as cut
    assert [(n.index, n.reason[:10]) for n in res.infeasible] == [(0, "cut short:")]
    assert res.cut == [(0, pytest.approx(3.0 - 0.5 + CUT_LEAD_S))]
    assert "cut short: t=0.000 s C3 let go 2.56 s early" in format_summary("cut.mid", res, 3.0, "c.csv")
    rep = check_trajectory(str(tmp_path / "c.csv"), str(song))
    bass = [p for p in rep.play.played if p.pitch == 48]
    assert len(bass) == 1 and bass[0].end_s <= 0.5 - CUT_LEAD_S + 0.02
    assert rep.play.notes_hit == len(notes) - 1 and not rep.play.wrong_presses


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
    """Both hands' parts for one hand: most of it cannot be played, and what is played
    presses no key the song does not have. A note the timing could not strike in time
    was left out even where the hand moved while its key was to be held (``shift``):
    its finger then swept over the black keys beside it at key height (four wrong
    presses); it is now left out only if that way is clear (``sweep_clear``), else kept
    late (its key was up a frame after its end). Now the hand no longer moves while a key
    is held when the timing already puts that key down late, and a note left out there
    may also have its finger follow the arm above its key: no wrong press at all."""
    from planner.music.midi import write_notes_midi

    melody = [70, 68, 66, 67, 66, 67, 68, 68, 67, 67, 65, 65, 65, 67, 69, 69,
              70, 70, 72, 72, 73, 71, 69, 70, 72, 73, 75, 77, 77, 76, 76, 75]
    song = tmp_path / "two_hands.mid"
    write_notes_midi(_melody_over_alberti_bass(melody), song)
    res = plan_song(load_song(song), planner.hand, str(tmp_path / "t.csv"), planner=planner)
    assert len(res.infeasible) > 0  # (one hand: much of it is named infeasible)
    rep = check_trajectory(str(tmp_path / "t.csv"), str(song))
    assert not rep.play.key_bed_hits and not [lim for lim in rep.limits if lim.count]
    assert not rep.play.wrong_presses, rep.play.wrong_presses


def test_a_trill_faster_than_the_fingers_is_planned_not_refused(planner, tmp_path):
    """C4-D4 at 16 notes per second: the timing QP of its first part did not reach its
    1e-9 tolerance in 20000 iterations (twice) and the whole plan failed (exit 1, no
    file). It is solved to 1e-6 then (the start times are made exactly feasible after):
    the plan is written, keeps every limit, and names each note it does not play."""
    from planner.music.midi import write_notes_midi

    notes = [Note(60 + (i % 2) * 2, i / 16, i / 16 + 0.055, 90) for i in range(48)]
    song, path = tmp_path / "trill.mid", tmp_path / "trill.csv"
    write_notes_midi(notes, song)
    res = plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    assert not rep.play.wrong_presses and not rep.play.key_bed_hits
    assert not [lim for lim in rep.limits if lim.count]
    named = {n.index for n in res.infeasible}
    assert rep.play.notes_hit + len(named) >= len(notes)


def test_the_planner_does_not_need_the_fingerings_rail_exact(planner, tmp_path, monkeypatch):
    """A trill of thumb and index on C5-D5 with the fingering's rail 50 mm off: the
    whole-hand IK finds a hand position for the whole trill anyway and plays it from
    there, instead of moving the hand for every note."""
    import dataclasses as dc

    import planner.play.legacy as play_mod
    from planner.music.midi import write_notes_midi

    notes = [Note(72 + 2 * (i % 2), 0.25 * i, 0.25 * i + 0.2, 80) for i in range(16)]
    song = tmp_path / "trill.mid"
    write_notes_midi(notes, song)
    orig = play_mod.assign_fingers

    def off(notes_, reach, pair_ok=None):
        a, bad = orig(notes_, reach, pair_ok)
        return [dc.replace(x, rail_m=x.rail_m + 0.05) for x in a], bad

    monkeypatch.setattr(play_mod, "assign_fingers", off)
    path = tmp_path / "t.csv"
    res = plan_song(load_song(song), planner.hand, str(path), planner=Planner(planner.hand))
    rep = check_trajectory(str(path), str(song))
    assert res.travels <= 1 and not res.infeasible, [(n.onset_s, n.pitch, n.reason) for n in res.infeasible]
    assert rep.play.f1 >= 0.98 and not rep.play.wrong_presses, rep.summary()


@pytest.mark.parametrize("name,f1", [("melody_over_held_bass", 0.90), ("trill_sections", 0.96)])
def test_regression_songs(planner, name, f1, tmp_path):
    """Random songs the planner once did badly on (tests/data/README.md): the fingering's
    per-finger range at one hand position (melody_over_held_bass: 0.846 before it); a
    hand position sought at a rail fitted to the window's keys when none at the
    fingering's rail serves more than the notes struck (trill_sections: 0.46 without)."""
    song = ROOT / "tests" / "data" / f"{name}.mid"
    path = tmp_path / "o.csv"
    plan_song(load_song(song), planner.hand, str(path), planner=planner)
    rep = check_trajectory(str(path), str(song))
    assert not rep.play.wrong_presses and not rep.play.key_bed_hits, rep.summary()
    assert all(v.count == 0 for v in rep.limits), rep.summary()
    assert rep.play.f1 >= f1, rep.summary()


def test_finger_ranges_are_measured_by_ik(planner):
    """Each finger's range at one hand position (the arm still): from the hand on white
    keys, every finger reaches the white key next to its own (so the range is more than
    one key's pitch), and no more than the probe's limit on each side; the thumb, pressing
    with its side, has the least."""
    from planner.music import keyboard as kb
    from planner.play.legacy import RANGE_MAX_M

    r = planner.reach.range_m
    assert set(r) == set(planner.hand.fingers)
    assert all(kb.WHITE_PITCH_M < v <= 2 * RANGE_MAX_M for v in r.values()), r
    assert r["thumb"] == min(r.values()), r


def test_notes_the_timing_cannot_strike_in_time_are_left_out_to_the_last(planner, tmp_path, monkeypatch):
    """A trill whose notes the timing cannot all strike in time (with the fingering's
    change of hand position costed lower, as a variant of the planner might): each note
    left out lets the timing move the next one later, and another may become hopeless.
    The rounds of leaving out go on until none is left (after three, a late note was
    kept and its key came up 2 frames after its end)."""
    import planner.fingering as fg

    monkeypatch.setattr(fg, "REPOSITION_OVERHEAD_S", 0.10)
    song = ROOT / "tests" / "data" / "trill_cascade.mid"
    path = tmp_path / "o.csv"
    res = plan_song(load_song(song), planner.hand, str(path), planner=Planner(planner.hand))
    rep = check_trajectory(str(path), str(song))
    assert any(n.reason and n.reason.startswith("too late") for n in res.notes)
    assert not rep.play.wrong_presses and not rep.play.key_bed_hits, rep.summary()
    assert all(v.count == 0 for v in rep.limits), rep.summary()

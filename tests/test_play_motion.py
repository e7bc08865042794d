"""The motion's tracks (planner/play/motion.py): a joint group's segments sampled at the
rows' times."""

from __future__ import annotations

import numpy as np

from planner.play.motion import _Track
from planner.play.profile import bounce_move, straight_move


def _reference(track: _Track, t_s: np.ndarray, q_start: np.ndarray) -> np.ndarray:
    """Row by row: before every segment, where the track starts; in a segment, its move;
    after it (until the next), where it ended."""
    out = []
    for t in t_s:
        running = [s for s in track.segments if s.t0_s <= t]
        if not running:
            out.append(q_start)
            continue
        s = running[-1]
        out.append(s.move.at(t - s.t0_s)[0] if t < s.t1_s else s.move.q_end)
    return np.array(out).reshape(len(t_s), len(q_start))


def test_a_track_sampled_at_once_is_its_segments_row_by_row():
    rng = np.random.default_rng(1)
    for _ in range(200):
        q0 = rng.normal(size=3)
        track, t, q = _Track(q0.copy()), rng.uniform(0.0, 0.5), q0
        for _ in range(rng.integers(0, 8)):
            qb = q + 0.3 * rng.normal(size=3)
            limits = (np.full(3, 3.0), np.full(3, 50.0), np.full(3, 2000.0))
            if rng.uniform() < 0.3:  # (a repeat's bounce: out and back where it was)
                t = track.add(t + rng.uniform(0.0, 0.3), bounce_move(q, qb, *limits))
                continue
            t = track.add(t + rng.uniform(0.0, 0.3), straight_move(q, qb, *limits))
            q = qb
        t_s = np.sort(rng.uniform(0.0, 3.0, size=rng.integers(1, 300)))
        assert np.array_equal(track.at(t_s, q0), _reference(track, t_s, q0))
        # (and in pieces, as the rows are written: each piece from where the last ended)
        cut = len(t_s) // 2
        both = np.vstack([track.at(t_s[:cut], q0), track.at(t_s[cut:], q0)])
        assert np.array_equal(both, _reference(track, t_s, q0))


def test_a_repeated_key_comes_up_by_the_end_of_the_note_before():
    """pretty-midi's example file (tests/data/round3), 195-197 s of its track 0: the
    pinky presses G4 for 71 ms and again 130 ms later. Its press ends 31 ms before the
    first note's end, and the short lift to the repeat height crosses the key-down depth
    39 ms into it (the lift to crossing height: 30 ms): lifted so, the key came up one
    row late, a wrong press. The repeat now lifts that way only when its key is up in
    time; otherwise by crossing height. No wrong press, every claim confirmed."""
    from pathlib import Path

    from planner.check import check_trajectory
    from planner.hand.model import load_hand
    from planner.music.midi import Note, Song, load_song
    from planner.play import Planner, plan_song

    path = Path(__file__).parent / "data" / "round3" / "prettymidi_example.mid"
    song = load_song(path, track=0)
    notes = tuple(Note(n.pitch, round(n.onset_s - 194.5, 9), round(n.offset_s - 194.5, 9),
                       n.velocity) for n in song.notes if 195.0 <= n.onset_s < 197.0)
    window = Song(notes, max(n.offset_s for n in notes), source="window.mid")
    pl = Planner(load_hand("default"))
    plan = plan_song(window, pl.hand, None, planner=pl)
    rep = check_trajectory(plan.trajectory, window)
    assert len(notes) == 66
    assert not rep.play.wrong_presses and not plan.verdict.score.wrong_presses, rep.summary()
    assert rep.ok and not rep.play.claim_mismatches


def test_the_idle_thumb_enters_no_key_in_any_posture():
    """The default hand's thumb presses no key; natural, it hangs inside a white key's
    footprint column 52 mm below its top when the arm is in its third posture (reach
    -0.10 m: a wrong press by check's body rule). The motion holds it at the nearest pose
    that enters no key's column in any posture, at any rail; a motion started in the
    third posture has it there."""
    from planner.hand.model import load_hand
    from planner.music import keyboard as kb
    from planner.music.keybodies import sphere_depths
    from planner.play.motion import Motion
    from planner.play.places import Places

    places = Places(load_hand("default"))
    hand, fb = places.hand, places.atlas.bodies
    js = hand.joint_slice("thumb")

    def deepest(joints, posture, rail_m):
        q = places.atlases[posture].base.copy()
        q[places.rail], q[js] = rail_m, joints
        p, r = fb.points(hand.apply_couplings(q), "thumb")
        return float(sphere_depths(p, r).max())

    natural, idle = places.atlas.base[js], places.idle.pose("thumb")
    assert deepest(natural, 2, 0.0) > kb.DOWN_DEPTH_M
    assert not np.array_equal(idle, natural)
    for posture in range(places.postures):
        for rail in (-0.2, -0.05, 0.0, 0.13, 0.25):
            assert deepest(idle, posture, rail) < 0.0
    motion = Motion((), places, 100.0, 0.1, posture=2)
    assert np.array_equal(motion.rows(np.array([0.0, 1.0]))[:, js], np.tile(idle, (2, 1)))

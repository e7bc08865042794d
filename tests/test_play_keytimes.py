"""Where the rows put a key down and let it up (planner.play.keytimes), and what it buys
in the physics: the servo-driven hand lags its rows into a key and leaves it early."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import planner
from planner.hand.model import load_hand
from planner.play.keytimes import (
    DRIVE_LAG_S,
    LATE_MIN_S,
    NOTE_HIT_FRACTION,
    ROW_MARGIN_S,
    down_rows,
    first_row,
    held_enough_at,
    held_enough_parts,
    held_enough_s,
    key_down_s,
    key_up_s,
    late_frames,
    sounding_frames,
    struck_s,
    up_rows,
)


@pytest.mark.parametrize(("rate_hz", "down"), [(100.0, 0.9), (120.0, 0.88), (50.0, 0.5),
                                               (1.0, 0.5)])
def test_crossings_lead_the_drive_lag_within_their_row_intervals(rate_hz, down):
    """Down: inside the row interval before the note's first row, ``DRIVE_LAG_S`` before
    that row where the rows leave room (at least the middle, at least ``ROW_MARGIN_S``
    after the row before); up: inside the interval before the first row at or after its
    end, as far after the note's last row; and a note's frames are its rows."""
    dt = 1.0 / rate_hz
    assert down_rows(dt) == pytest.approx(down) and up_rows(dt) == pytest.approx(1.0 - down)
    rng = np.random.default_rng(7)
    onsets = np.concatenate([rng.uniform(0.0, 20.0, 300), np.arange(0, 200) * dt])
    for on in onsets.tolist():
        off = on + float(rng.uniform(dt, 2.0))
        first = math.ceil(on / dt - 1e-9)  # the note's first row
        after = math.ceil(off / dt - 1e-9)  # the first row at or after its end
        d, u = key_down_s(on, dt), key_up_s(off, dt)
        assert (first - 1) * dt + ROW_MARGIN_S - 1e-12 <= d <= first * dt - 0.5 * dt + 1e-12
        assert first * dt - d == pytest.approx(max(0.5 * dt, min(DRIVE_LAG_S, dt - ROW_MARGIN_S)))
        assert (after - 1) * dt + 0.5 * dt - 1e-12 <= u <= after * dt - ROW_MARGIN_S + 1e-12
        assert u - (after - 1) * dt == pytest.approx(first * dt - d)
        assert sounding_frames(d, u, dt) == pytest.approx(after - first, abs=1e-6)


def test_fast_notes_sound_in_physics_from_their_first_row(tmp_path):
    """The sample song ``fast`` (10-frame notes at 8.8 per second) planned and replayed
    in full contact: the physics finds every note the check finds and loses almost no
    frame against it: at most one a late note (a late key-down crosses where its move
    brings it, not at its row's edge, so the drive's lag may cost its first frame), none
    an on-time note (a key struck at the middle of the row before its note, as the plan
    did, sounded a frame late in physics at 16 of its 40 notes: 0.9007 against the check's
    0.9276)."""
    pytest.importorskip("mujoco")
    from planner.check import check_trajectory
    from planner.simulate import simulate_trajectory

    song = "songs/fast.mid"
    path = str(tmp_path / "fast.csv")
    planner.plan_song(planner.load_song(song), load_hand("default"), path)
    check = check_trajectory(path, song)
    phys = simulate_trajectory(path, song)
    assert check.ok and phys.ok, phys.problems
    assert phys.play.notes_hit == check.play.notes_hit
    assert not phys.play.wrong_keys
    lost = (check.play.f1 - phys.play.f1) * phys.play.song_frames
    assert lost <= len(check.play.late) + 1e-6, (check.play.f1, phys.play.f1, check.play.late)


def test_a_late_key_costs_what_the_physics_loses():
    """On time within ``LATE_MIN_S``; then a whole frame (the target leads the first row
    by about the drive's lag: any later and the physics is down after that row), and a
    frame more for each row's time."""
    dt = 0.01
    assert late_frames(0.0, dt) == 0.0 and late_frames(LATE_MIN_S, dt) == 0.0
    assert late_frames(0.002, dt) == 1.0 and late_frames(0.0099, dt) == 1.0
    assert late_frames(0.0101, dt) == 2.0 and late_frames(0.035, dt) == 4.0


@pytest.mark.parametrize("rate_hz", [100.0, 50.0])
def test_a_late_key_before_the_first_row_goes_down_just_after_it(rate_hz):
    """A key its moves bring down after its target but before the note's first row goes
    down ``ROW_MARGIN_S`` after that row (the physics loses the row either way); on time,
    or already past the row, where its moves bring it."""
    dt = 1.0 / rate_hz
    for on in (0.1234, 0.5, 1.0 - 1e-4, 2.718):
        want, edge = key_down_s(on, dt), first_row(on, dt) * dt + ROW_MARGIN_S
        assert struck_s(on, want, dt) == want
        assert struck_s(on, want + 0.5 * LATE_MIN_S, dt) == want + 0.5 * LATE_MIN_S
        for late in (2 * LATE_MIN_S, 0.5 * (edge - want)):
            assert struck_s(on, want + late, dt) == edge
        assert struck_s(on, edge + 0.003, dt) == edge + 0.003


def test_a_cut_note_is_held_until_the_physics_sounds_it():
    """A note cut early (a move needs its finger) stays down until half its rows hold
    with the drive's lag at both ends; a cut that loses it anyway, or none, stays."""
    dt = 0.01
    on, off = 0.341, 0.455  # (11 rows: 0.35 to 0.45; 6 to hit it)
    down, up = key_down_s(on, dt), key_up_s(off, dt)
    assert held_enough_s(on, off, down, up + 0.01, up, dt) == up + 0.01  # (no cut)
    assert held_enough_s(on, off, down, 0.38, up, dt) == 0.38  # (lost anyway: 3 rows)
    assert held_enough_s(on, off, down, 0.40, up, dt) == 0.40  # (5 rows: lost anyway)
    # (6 rows by the rows, 5 with the lag: held until the 6th row after the lag, 0.41)
    kept = held_enough_s(on, off, down, 0.41, up, dt)
    assert kept == pytest.approx(0.36 + 5 * dt + DRIVE_LAG_S + ROW_MARGIN_S)
    assert held_enough_s(on, off, down, 0.43, up, dt) == 0.43  # (enough already)


def _held_enough_plain(onset_s, offset_s, down_s, cut_s, up_s, dt_s):
    """``held_enough_s`` as one expression (before its parts were kept apart)."""
    if cut_s >= up_s:
        return cut_s
    k0, k1 = first_row(onset_s, dt_s), first_row(offset_s, dt_s)
    need = math.ceil(NOTE_HIT_FRACTION * (k1 - k0) - 1e-9)
    if max(0, min(k1, first_row(cut_s, dt_s)) - max(k0, first_row(down_s, dt_s))) < need:
        return cut_s
    first = max(k0, first_row(down_s + DRIVE_LAG_S, dt_s))
    return min(up_s, max(cut_s, (first + need - 1) * dt_s + DRIVE_LAG_S + ROW_MARGIN_S))


@pytest.mark.parametrize("rate_hz", [100.0, 120.0])
def test_the_parts_of_a_held_key_give_the_same_float(rate_hz):
    """``held_enough_at`` of a note's ``held_enough_parts`` (what the programme keeps per
    state before and note: ``ArmCosts._cut_up_s``) is the one expression's float, for
    ``fast.mid``'s notes, keys down on time and late, cut across each note; held, lost
    anyway and uncut all occur."""
    from planner.music.midi import load_song

    dt = 1.0 / rate_hz
    song = load_song(Path(planner.__file__).resolve().parents[1] / "songs" / "fast.mid")
    kinds = set()
    for n in song.notes[:40]:
        down, up = key_down_s(n.onset_s, dt), key_up_s(n.offset_s, dt)
        for late in (0.0, 0.013):
            parts = held_enough_parts(n.onset_s, n.offset_s, down + late, up, dt)
            for i in range(37):
                cut = down + (up - down + 0.02) * i / 32
                want = _held_enough_plain(n.onset_s, n.offset_s, down + late, cut, up, dt)
                assert held_enough_at(parts, cut) == want
                assert held_enough_s(n.onset_s, n.offset_s, down + late, cut, up, dt) == want
                kinds.add("uncut" if cut >= up else "lost" if want == cut else "held")
    assert kinds == {"uncut", "lost", "held"}

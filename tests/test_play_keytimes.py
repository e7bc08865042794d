"""Where the rows put a key down and let it up (planner.play.keytimes), and what it buys
in the physics: the servo-driven hand lags its rows into a key and leaves it early."""

from __future__ import annotations

import math

import numpy as np
import pytest

import planner
from planner.hand.model import load_hand
from planner.play.keytimes import (
    DRIVE_LAG_S,
    ROW_MARGIN_S,
    down_rows,
    key_down_s,
    key_up_s,
    sounding_frames,
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

"""bench/frame_losses.py's attribution of `check`'s lost frames, on rows made here: each
note's frames without its key down go to one cause, and their F1 weights sum to the
rows' own loss (rows times one less the mean frame F1)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from planner.check.criteria import expected_keys, frame_scores
from planner.music.midi import Note

_PATH = Path(__file__).resolve().parents[1] / "bench" / "frame_losses.py"
_SPEC = importlib.util.spec_from_file_location("frame_losses", _PATH)
fl = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(fl)

RAIL, REACH = 0, 1  # (the rows' joints here: the rail, the reach axis)


def _rows(notes, downs, T=100):
    """A replay of ``T`` rows at 100 Hz: ``downs`` (pitch, first row, end row, holder)."""
    t = np.arange(T) / 100.0
    down = np.zeros((T, 88), dtype=bool)
    finger = np.full((T, 88), -1)
    for pitch, r0, r1, who in downs:
        down[r0:r1, pitch - 21] = True
        finger[r0:r1, pitch - 21] = who
    return SimpleNamespace(t_s=t, q=np.zeros((T, 2)), down=down, finger=finger,
                           expected=expected_keys(notes, t))


def test_each_lost_frame_has_one_cause_and_the_weights_are_the_rows_loss():
    notes = (Note(60, 0.10, 0.30, 80),  # C4: down 2 rows late, the rail moving before
             Note(62, 0.30, 0.50, 80),  # D4: up 4 rows early, the reach moving after
             Note(64, 0.50, 0.70, 80),  # E4: up 3 rows early, struck again at 0.70
             Note(64, 0.70, 0.90, 80),
             Note(65, 0.10, 0.30, 80))  # F4: left out
    rp = _rows(notes, [(60, 12, 30, 1), (62, 30, 46, 2), (64, 50, 67, 3), (64, 70, 90, 3)])
    rp.q[5:11, RAIL] = np.linspace(0.0, 0.02, 6)  # (the rail moves before C4 goes down)
    rp.q[11:, RAIL] = 0.02
    rp.q[46:50, REACH] = np.linspace(0.0, -0.025, 4)  # (the reach moves after D4 is up)
    rp.q[50:, REACH] = -0.025
    out = fl.song_losses(rp, notes, {4: "too_late"}, (RAIL, REACH), False, "t")
    got = {c: v[1] for c, v in out.items() if not c.startswith("(")}
    assert got == {"late: rail": 2, "early: posture": 4, "early: repeat": 3,
                   "left out: too_late": 20}
    f1 = frame_scores(rp.expected, rp.down)[2]
    lost = sum(v[2] for c, v in out.items() if not c.startswith("("))
    assert lost == pytest.approx(len(f1) * (1.0 - f1.mean()))
    # (C4 and F4 together in rows 10-11: each missing key costs half of its frame's F1)
    assert out["late: rail"][2] == pytest.approx(2 * 0.5)


def test_a_late_press_without_a_move_is_the_finger_or_the_descent():
    notes = (Note(60, 0.10, 0.30, 80), Note(62, 0.30, 0.50, 80), Note(67, 0.60, 0.80, 80))
    rp = _rows(notes, [(60, 10, 30, 1), (62, 33, 50, 1), (67, 61, 80, 2)])
    out = fl.song_losses(rp, notes, {}, (RAIL, REACH), False, "t")
    got = {c: v[1] for c, v in out.items() if not c.startswith("(")}
    assert got == {"late: finger move": 3, "late: descent": 1}


def test_the_frames_before_a_change_of_posture_split_by_the_arms_move():
    """``early: posture``'s rows split by the reach axis's move after the key-up: D4 up
    from row 46, the reach away from row 47 and still at its end from row 49: D4's four
    rows up are 1 before the arm, 2 while it moves, 1 after; their weights sum to the
    cause's."""
    notes = (Note(62, 0.30, 0.50, 80), Note(67, 0.50, 0.60, 80))
    rp = _rows(notes, [(62, 30, 46, 2), (67, 50, 60, 1)])
    rp.q[46:50, REACH] = np.linspace(0.0, -0.025, 4)  # (rows 47-48 moving, 49 at its end)
    rp.q[50:, REACH] = -0.025
    assert fl.posture_phases(rp.q, REACH, 46) == (47, 49)
    assert fl.posture_phases(rp.q, REACH, 60) == (100, 100)  # (no move after)
    out = fl.song_losses(rp, notes, {}, (RAIL, REACH), False, "t")
    assert out["early: posture"][1] == 4
    got = [out[f"(posture: {name})"][1] for name in fl.POSTURE_PHASES]
    assert got == [1, 2, 1]
    assert sum(out[f"(posture: {name})"][2] for name in fl.POSTURE_PHASES) \
        == pytest.approx(out["early: posture"][2])

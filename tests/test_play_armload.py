"""Every motor within its capacity while several joint groups move at once
(planner/play/armload.py): fingers crossing at height together with the rail add their
reactions on the wrist's motors, which no finger's own bound (planner.play.tendonload)
sees."""

from __future__ import annotations

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.check.criteria import DOWN_DEPTH_M, key_contacts
from planner.check.kinematics import Kinematics
from planner.check.limits import LimitAudit
from planner.hand.model import load_hand
from planner.music.midi import Note, load_song, write_notes_midi
from planner.play import Planner, plan_song
from planner.play.armload import rows_load
from planner.trajfile import read_trajectory

# two four-note chords a hand's position apart: between them the rail moves while the
# four long fingers swing sideways to their new keys, all at once (before the whole-hand
# bound: 2.115 N m on the default hand's wrist deviation motor, limit 2.00)
CHORDS = [(52, 55, 59, 62), (57, 59, 62, 65)]


def _chords(mirrored: bool) -> list[Note]:
    """``CHORDS`` 1.2 s apart, each held 1.08 s; ``mirrored`` about D4 (pitch p -> 124 - p:
    the same reach for a left hand)."""
    return [Note(124 - p if mirrored else p, 0.5 + 1.2 * i, 1.58 + 1.2 * i, 80)
            for i, chord in enumerate(CHORDS) for p in chord]


@pytest.mark.parametrize("hand_name, mirrored", [("default", False), ("default-left", True)])
def test_fingers_crossing_together_keep_the_wrist_within_its_motor(tmp_path, hand_name,
                                                                   mirrored):
    hand = load_hand(hand_name)
    song, out = tmp_path / "chords.mid", tmp_path / "chords.csv"
    write_notes_midi(_chords(mirrored), song)
    plan = plan_song(load_song(song), hand, str(out), planner=Planner(hand))
    report = check_trajectory(str(out), str(song), strict=False)
    torque = next(lc for lc in report.limits if lc.category == "motor_torque")
    assert not plan.verdict.rejected, plan.verdict.problem_lines()
    assert torque.count == 0 and torque.worst <= torque.limit, torque


def test_the_bound_judges_rows_with_checks_own_motor_torques(tmp_path):
    """``RowsLoad.torques`` on a plan's rows is the audit's motor torque: the worst motor,
    row and value of ``check``'s ``LimitAudit`` (with the hand's inertia) to the bit."""
    hand = load_hand("default")
    song, out = tmp_path / "chords.mid", tmp_path / "chords.csv"
    write_notes_midi(_chords(False), song)
    plan_song(load_song(song), hand, str(out), planner=Planner(hand))
    tr = read_trajectory(str(out))
    kin = Kinematics(hand, hand.T_world_root)
    tips, _ = kin.frames(tr.q)
    pressing = np.nan_to_num(key_contacts(tips).tip_depth, nan=-1.0) >= DOWN_DEPTH_M
    audit = LimitAudit(hand, kin, inertia=True)
    audit.add(tr.t_s, tr.q, tr.q_motor, pressing)
    checks, _ = audit.finish()
    worst = next(lc for lc in checks if lc.category == "motor_torque")
    load = rows_load(hand)
    TM = np.abs(load.torques(tr.t_s, tr.q))  # (rows 1 .. -2)
    r, m = np.unravel_index(np.argmax(TM / hand.motor_peak_torque), TM.shape)
    assert worst.name == f"motor.{hand.motor_names[m]}"
    assert worst.time_s == tr.t_s[r + 1]
    assert worst.worst == TM[r, m]

"""Tests of planner.check, the independent replay check, on play trajectories.

The trajectories are built without the planner (tests/trajbuild.py); the catch
checks are in test_check_catch.py.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
import pytest

from planner import check
from planner.check import (
    check_trajectory,
    frame_f1,
    frame_scores,
    key_contacts,
    key_episodes,
    keys_down,
)
from planner.cli.check import run as check_cli
from planner.errors import InputError
from planner.hand.model import load_hand
from planner.music.keyboard import key
from planner.music.midi import Note, load_song, write_notes_midi
from tests.trajbuild import (
    RATE,
    SONG,
    meta,
    play_trajectory,
    press_posture,
    rewrite,
    song_file,
    write_traj,
)

FORBIDDEN = ("planner.play", "planner.ik", "planner.trajectory", "planner.catch",
             "planner.selfcheck")


@pytest.fixture()
def good(tmp_path, hand):
    t, q = play_trajectory(SONG, 3.4)
    return write_traj(tmp_path / "good.csv", hand, t, q), song_file(tmp_path), t, q


# ---------------------------------------------------------------- independence


def test_imports_no_planner_stage():
    from planner.check import trajcheck  # (the entry points, imported on first use)

    for path in (check.__file__, trajcheck.__file__):
        with open(path, encoding="utf-8") as f:
            src = f.read()
        for mod in FORBIDDEN:
            assert f"import {mod}" not in src and f"from {mod} " not in src, mod
    # and importing it (its entry points too) does not pull them in
    code = (f"import sys, planner.check.trajcheck; "
            f"bad = [m for m in sys.modules if m in {FORBIDDEN!r}]; print(bad); assert not bad")
    import subprocess

    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       check=False)
    assert r.returncode == 0, r.stdout + r.stderr


# ---------------------------------------------------------------- frame F1


def test_frame_scores_zero_division_semantics():
    e = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0], [1, 1, 0], [1, 0, 0]], dtype=bool)
    p = np.array([[0, 0, 0], [0, 0, 0], [0, 1, 0], [1, 0, 1], [1, 0, 0]], dtype=bool)
    prec, rec, f1 = frame_scores(e, p)
    # empty/empty -> 1; missed only -> precision 1 (0/0), recall 0, F1 0;
    # false positive only -> precision 0, recall 1 (0/0), F1 0
    np.testing.assert_allclose(prec, [1, 1, 0, 0.5, 1])
    np.testing.assert_allclose(rec, [1, 0, 1, 0.5, 1])
    np.testing.assert_allclose(f1, [1, 0, 0, 0.5, 1])
    assert frame_f1(e, p) == pytest.approx(2.5 / 5)
    assert frame_f1(np.zeros((0, 88), bool), np.zeros((0, 88), bool)) == 1.0
    with pytest.raises(ValueError):
        frame_scores(e, p[:, :2])


def test_frame_scores_match_sklearn_definition():
    rng = np.random.default_rng(1)
    e = rng.random((200, 88)) < 0.03
    p = rng.random((200, 88)) < 0.03
    p[:50] = e[:50]
    _, _, f1 = frame_scores(e, p)
    for k in range(200):
        tp = np.sum(e[k] & p[k])
        pr = tp / p[k].sum() if p[k].sum() else 1.0
        rc = tp / e[k].sum() if e[k].sum() else 1.0
        want = 1.0 if not (e[k].any() or p[k].any()) else (
            0.0 if pr + rc == 0 else 2 * pr * rc / (pr + rc))
        assert f1[k] == pytest.approx(want)


# ---------------------------------------------------------------- key rule


def test_key_rule_white_black_and_depths():
    c4, cs4 = key(60), key(61)
    tips = np.array([[
        [c4.center_x_m, 0.03, -0.005],   # C4 down at exactly 5 mm
        [c4.center_x_m, 0.03, -0.0049],  # not yet
        [cs4.center_x_m, 0.10, 0.0075],  # C#4 down (5 mm below its 12.5 mm top)
        [cs4.center_x_m, 0.10, -0.001],  # inside the black rectangle: C#4, not C4/D4, key bed
        [c4.x_max_m + 0.0005, 0.03, -0.008],  # in the 1 mm gap: no key
    ]])
    kc = key_contacts(tips)
    assert kc.tip_key[0].tolist() == [60 - 21, 60 - 21, 61 - 21, 61 - 21, -1]
    np.testing.assert_allclose(kc.tip_depth[0, :4], [0.005, 0.0049, 0.005, 0.0135])
    assert np.flatnonzero(kc.down[0]).tolist() == [60 - 21, 61 - 21]
    assert kc.finger[0, 60 - 21] == 0
    assert kc.finger[0, 61 - 21] == 3  # the deepest of the two fingers on C#4


def test_frames_are_pinocchio_frames_bit_for_bit(hand):
    """``Kinematics.frames_of`` (the joints' placements, then only the tips' and the
    palm's frames) gives exactly what ``framesForwardKinematics`` of every frame does."""
    import pinocchio as pin

    from planner.check.kinematics import Kinematics

    kin = Kinematics(hand, hand.T_world_root)
    rng = np.random.default_rng(7)
    lo, hi = np.asarray(hand.lower), np.asarray(hand.upper)
    U = lo + rng.uniform(size=(50, hand.n)) * (hi - lo)
    tips, palm = kin.frames_of(U)
    m, d = kin.model, kin.model.createData()
    for k, q in enumerate(U):
        pin.framesForwardKinematics(m, d, kin.pin_q(q))
        want = np.array([d.oMf[f].translation for f in kin.tip_ids]) @ kin.R.T + kin.p
        assert np.array_equal(tips[k], want)
        assert np.array_equal(palm[k], kin.T @ d.oMf[kin.palm_id].homogeneous)


def test_keys_down_from_joints(hand):
    q = press_posture(64, "ring", 0.008)
    down, finger = keys_down(hand, np.zeros(1), q[None])
    assert np.flatnonzero(down[0]).tolist() == [64 - 21]
    assert hand.fingers[finger[0, 64 - 21]] == "ring"
    q = press_posture(64, "ring", 0.004)
    down, _ = keys_down(hand, np.zeros(1), q[None])
    assert not down.any()


def test_key_episodes():
    t = np.arange(6) * 0.01
    m = np.zeros((6, 88), bool)
    m[1:3, 39] = True
    m[4:, 39] = True
    f = np.full((6, 88), -1, np.int8)
    f[1:3, 39] = 1
    f[4:, 39] = 2
    eps = key_episodes(m, t, f)
    assert [(e.name, e.start_s, e.end_s, e.fingers) for e in eps] == [
        ("C4", 0.01, 0.03, ("index",)), ("C4", 0.04, pytest.approx(0.06), ("middle",))]


# ---------------------------------------------------------------- a good play


def test_good_trajectory_passes(good, hand):
    traj, song, t, _q = good
    r = check_trajectory(traj, song, min_f1=0.99)
    assert r.ok, r.summary()
    assert r.play.f1 == 1.0 and r.play.precision == 1.0 and r.play.recall == 1.0
    assert r.play.notes == 4 and r.play.notes_hit == 4 and r.play.hit_rate == 1.0
    assert not r.play.missed and not r.play.wrong_presses and not r.play.key_bed_hits
    assert [(e.name, e.start_s, e.end_s, e.fingers) for e in r.play.played] == [
        ("C4", 0.3, 0.6, ("index",)), ("D4", 1.1, 1.4, ("middle",)),
        ("E4", 1.9, 2.2, ("ring",)), ("C#4", 2.7, 3.0, ("index",))]
    assert {lc.category for lc in r.limits} == {
        "joint_position", "joint_stop_margin", "joint_velocity", "joint_acceleration",
        "joint_jerk", "motor_velocity", "motor_consistency", "motor_torque", "coupling",
        "tendon_tension"}
    assert all(lc.ok for lc in r.limits)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["ok"] is True and d["play"]["f1"] == 1.0 and "replay" not in d
    s = r.summary()
    assert "OK" in s.splitlines()[0] and "F1 1.0000" in s
    # replay arrays for plots
    assert r.replay.tips.shape == (len(t), 5, 3) and r.replay.down.shape == (len(t), 88)


def test_without_song_lists_presses(good):
    r = check_trajectory(good[0])
    assert r.ok and r.play.f1 is None and r.play.hit_rate is None
    assert [e.pitch for e in r.play.played] == [60, 62, 64, 61]
    assert check_trajectory(good[0], hand_override="default").ok
    assert check_trajectory(good[0], hand_override=load_hand("default")).ok
    with pytest.raises(InputError, match="min-f1 needs a song"):
        check_trajectory(good[0], min_f1=0.5)


# ---------------------------------------------------------------- play failures


def test_wrong_key_is_reported(tmp_path, hand):
    wrong = [SONG[0], (64, "middle", 1.10, 1.40), SONG[2], SONG[3]]
    t, q = play_trajectory(wrong, 3.4)
    traj = write_traj(tmp_path / "w.csv", hand, t, q)
    r = check_trajectory(traj, song_file(tmp_path), min_f1=0.95)
    assert not r.ok
    (w,) = r.play.wrong_presses
    assert (w.pitch, w.name, w.start_s, w.end_s, w.fingers) == (64, "E4", 1.1, 1.4, ("middle",))
    (m,) = r.play.missed
    assert (m.pitch, m.name, m.onset_s, m.reason) == (62, "D4", 1.1, "key never down")
    assert r.play.notes_hit == 3
    # 30 of the song's 300 frames (3.0 s at 100 Hz; the 41 rows after it are not scored)
    assert r.play.song_frames == 300 < len(t)
    assert r.play.f1 == pytest.approx(1 - 30 / 300)
    assert any("wrong presses" in p for p in r.problems)
    assert any("frame F1" in p for p in r.problems)
    assert "E4" in r.summary()


def test_late_release_is_a_wrong_press(tmp_path, hand):
    late = [SONG[0], (62, "middle", 1.10, 1.45), SONG[2], SONG[3]]
    t, q = play_trajectory(late, 3.4)
    r = check_trajectory(write_traj(tmp_path / "l.csv", hand, t, q), song_file(tmp_path))
    (w,) = r.play.wrong_presses
    assert (w.name, w.start_s, w.end_s) == ("D4", 1.4, 1.45)
    assert r.play.notes_hit == 4 and not r.ok


def test_key_bed_hit(tmp_path, hand):
    deep = [SONG[0], (62, "middle", 1.10, 1.40, 0.015), SONG[2], SONG[3]]
    t, q = play_trajectory(deep, 3.4)
    r = check_trajectory(write_traj(tmp_path / "k.csv", hand, t, q), song_file(tmp_path))
    assert not r.ok
    (hit,) = r.play.body_bed_hits  # (the middle's body 15 mm down: 4 mm past the 11 allowed)
    assert (hit.link.split("_")[0], hit.name) == ("middle", "D4")
    assert hit.depth_m == pytest.approx(0.015, abs=1e-5)
    assert 1.0 < hit.time_s < hit.end_s < 1.5
    assert any("body key-bed hits" in p for p in r.problems)


def _limit(r, category):
    return next(lc for lc in r.limits if lc.category == category)


def test_joint_limit_violation(tmp_path, hand, good):
    _, _, t, q = good
    q = q.copy()
    j = hand.index["middle_mcp_abd"]
    q[150:152, j] = hand.upper[j] + 0.01
    r = check_trajectory(write_traj(tmp_path / "j.csv", hand, t, q))
    lc = _limit(r, "joint_position")
    assert not r.ok and lc.count == 2
    assert (lc.name, lc.time_s, lc.limit) == ("middle_mcp_abd", 1.5, pytest.approx(hand.upper[j]))
    assert lc.worst == pytest.approx(hand.upper[j] + 0.01, abs=1e-6)


def test_broken_coupling(tmp_path, hand, good):
    _, _, t, q = good
    q = q.copy()
    q[200, hand.index["index_dip"]] += 0.001  # dip != 0.667 pip
    r = check_trajectory(write_traj(tmp_path / "c.csv", hand, t, q))
    lc = _limit(r, "coupling")
    assert not r.ok and lc.count == 1
    assert (lc.name, lc.time_s) == ("index_dip", 2.0)
    assert lc.worst == pytest.approx(0.001, abs=2e-6)


def test_too_fast_step(tmp_path, hand, good):
    _, _, t, q = good
    q = q.copy()
    j = hand.index["thumb_ip"]
    step = 1.3 * hand.velocity[j] / RATE  # one row at 1.3x the speed limit
    q[100:, j] += step
    r = check_trajectory(write_traj(tmp_path / "s.csv", hand, t, q))
    v = _limit(r, "joint_velocity")
    assert v.count == 1 and v.name == "thumb_ip" and v.time_s == 1.0
    assert v.worst == pytest.approx(step * RATE, rel=1e-4) and v.limit == hand.velocity[j]
    a = _limit(r, "joint_acceleration")
    assert a.count == 2 and a.name == "thumb_ip"
    assert not r.ok


def test_jerky_row_flagged(tmp_path, hand, good):
    """One row half the jerk bound x dt^3 out of line: its third differences (1, -3, 3,
    -1 times the offset over dt^3) put two rows' jerks at 1.5 x the bound (the other two
    at 0.5 x), while the acceleration (2 x the offset / dt^2) stays within its limit."""
    _, _, t, q = good
    q = q.copy()
    j = hand.index["index_mcp_abd"]
    dt = 1.0 / RATE
    off = 0.5 * hand.jerk[j] * dt ** 3  # 4.2e-3 rad (a jerk bound of 8333 rad/s^3)
    q[150, j] += off
    r = check_trajectory(write_traj(tmp_path / "j.csv", hand, t, q))
    lc = _limit(r, "joint_jerk")
    assert lc.name == "index_mcp_abd" and lc.limit == hand.jerk[j]
    assert lc.count == 2
    assert lc.worst == pytest.approx(3 * off / dt ** 3, rel=1e-3)
    assert lc.time_s in (1.49, 1.5)
    assert _limit(r, "joint_acceleration").ok and _limit(r, "joint_velocity").ok
    assert not r.ok and any("joint jerk violations" in p for p in r.problems)
    # a tenth of that offset: 0.15 of the bound, no violation
    q[150, j] -= 0.9 * off
    assert _limit(check_trajectory(write_traj(tmp_path / "j2.csv", hand, t, q)),
                  "joint_jerk").ok


def test_row_on_a_stop_flagged(tmp_path, hand, good):
    """Rows with thumb_ip on its hard stop (0 rad): inside its 2 deg margin, counted by
    joint_stop_margin, while joint_position (the hard stops) passes; a row 1 deg off the
    stop is counted too, one at the margin's edge is not."""
    _, _, t, q = good
    j = hand.index["thumb_ip"]
    assert hand.stop_margin[j] == pytest.approx(np.radians(2.0))
    q = q.copy()
    q[:, j] = np.radians(2.0)  # at the margin's edge: the plan's lowest
    r = check_trajectory(write_traj(tmp_path / "edge.csv", hand, t, q))
    assert _limit(r, "joint_stop_margin").ok and r.ok, r.summary()
    q[:, j] = 0.0  # the hard stop, in every row
    r = check_trajectory(write_traj(tmp_path / "stop.csv", hand, t, q))
    lc = _limit(r, "joint_stop_margin")
    assert lc.count == len(t) and lc.name == "thumb_ip"
    assert lc.worst == 0.0 and lc.limit == pytest.approx(np.radians(2.0))
    assert _limit(r, "joint_position").ok
    assert not r.ok and any("joint stop margin violations" in p for p in r.problems)
    q[:, j] = np.radians(2.0)
    q[200:210, j] = np.radians(1.0)  # ten rows 1 deg off the stop (a slow dip: no jerk)
    r = check_trajectory(write_traj(tmp_path / "near.csv", hand, t, q))
    assert _limit(r, "joint_stop_margin").count == 10


def test_motor_column_inconsistent(tmp_path, hand, good):
    _, _, t, q = good
    qm = hand.motor_angles(q)
    qm[10, hand.motor_names.index("index_pip")] += 1e-4
    r = check_trajectory(write_traj(tmp_path / "m.csv", hand, t, q, qm=qm))
    lc = _limit(r, "motor_consistency")
    assert lc.count == 1 and lc.name == "motor.index_pip" and lc.time_s == 0.1
    # the rail's belt (100 rad/m) turns the 6-decimal rounding into 5e-5 rad: tolerated
    assert _limit(check_trajectory(good[0]), "motor_consistency").count == 0


def test_motor_torque_counts_gravity(tmp_path, hand, good, monkeypatch):
    r = check_trajectory(good[0])
    lc = _limit(r, "motor_torque")
    assert lc.ok and lc.worst > 0
    monkeypatch.setattr(hand, "motor_peak_torque", hand.motor_peak_torque * 1e-3)
    r = check_trajectory(good[0])
    assert not _limit(r, "motor_torque").ok and not r.ok


# ---------------------------------------------------------------- refused inputs


def test_refused_inputs(tmp_path, hand, good):
    _, _, t, q = good
    bad_hash = meta(hand, urdf_sha256="0" * 64)
    with pytest.raises(InputError, match="urdf_sha256 mismatch"):
        check_trajectory(write_traj(tmp_path / "h.csv", hand, t, q, metadata=bad_hash))
    with pytest.raises(InputError, match="no_such_hand"):
        check_trajectory(write_traj(tmp_path / "u.csv", hand, t, q,
                                    metadata=meta(hand, hand="no_such_hand")))
    names = [n for n in hand.joint_names if n != "ring_pip"]
    cols = [hand.joint_names.index(n) for n in names]
    p = write_traj(tmp_path / "col.csv", hand, t, q[:, cols], hand.motor_angles(q),
                   joint_names=names)
    with pytest.raises(InputError, match="missing ring_pip"):
        check_trajectory(str(p))
    p = write_traj(tmp_path / "mcol.csv", hand, t, q, np.c_[hand.motor_angles(q),
                   np.zeros(len(t))], motor_names=[*hand.motor_names, "extra"])
    with pytest.raises(InputError, match="extra motor.extra"):
        check_trajectory(str(p))
    T = hand.T_world_root.copy()
    T[0, 3] += 0.01
    with pytest.raises(InputError, match="T_world_root"):
        check_trajectory(write_traj(tmp_path / "T.csv", hand, t, q,
                                    metadata=meta(hand, T_world_root=T.tolist())))
    with pytest.raises(InputError, match="ball"):  # a catch without its ball
        check_trajectory(write_traj(tmp_path / "cat.csv", hand, t, q, metadata=meta(hand, "catch")))
    with pytest.raises(InputError, match="catch trajectory"):  # a song for a catch
        check_trajectory(write_traj(tmp_path / "cat2.csv", hand, t, q,
                                    metadata=meta(hand, "catch")), good[1])


def test_nan_refused(good):
    def put_nan(ls):
        parts = ls[5].split(",")
        parts[3] = "nan"
        return ls[:5] + [",".join(parts)] + ls[6:]

    nan = rewrite(good[0], put_nan)
    with pytest.raises(InputError, match="NaN"):
        check_trajectory(nan)


def test_time_not_increasing_refused(good):
    def swap(ls):
        parts = ls[10].split(",")
        parts[0] = ls[9].split(",")[0]
        return ls[:10] + [",".join(parts)] + ls[11:]

    with pytest.raises(InputError, match="not strictly increasing"):
        check_trajectory(rewrite(good[0], swap))


def test_incomplete_refused_or_allowed(good):
    path = rewrite(good[0], lambda ls: [x for x in ls if x and '"end"' not in x] + [""])
    with pytest.raises(InputError, match="incomplete"):
        check_trajectory(path)
    r = check_trajectory(path, good[1], allow_incomplete=True)
    assert not r.complete and r.ok and r.play.f1 == 1.0
    assert "INCOMPLETE" in r.summary()


# ---------------------------------------------------------------- CLI


def _args(**kw):
    """``check``'s arguments as its parser gives them, with ``kw`` instead."""
    from planner.cli import build_parser

    base = vars(build_parser().parse_args(["check", "x.csv"]))
    base.update(kw)
    return argparse.Namespace(**base)


def test_cli_summary_json_and_played(good, tmp_path, capsys):
    traj, song, _, _ = good
    assert check_cli(_args(trajectory=traj, song=song)) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"check {traj}: OK")
    played = tmp_path / "played.mid"
    assert check_cli(_args(trajectory=traj, song=song, json=True, played=str(played))) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["ok"] and d["play"]["notes_hit"] == 4
    notes = load_song(played).notes
    want = load_song(song).notes
    assert [n.pitch for n in notes] == [n.pitch for n in want]
    for a, b in zip(notes, want):
        assert a.onset_s == pytest.approx(b.onset_s, abs=1e-3)
        assert a.offset_s == pytest.approx(b.offset_s, abs=1e-3)
        assert a.velocity == 64


def test_cli_failure_exit_1_and_input_error_exit_2(tmp_path, hand, good, capsys):
    _, song, t, q = good
    q = q.copy()
    q[50:, hand.index["thumb_ip"]] += 0.3
    traj = write_traj(tmp_path / "f.csv", hand, t, q)
    assert check_cli(_args(trajectory=traj, song=song)) == 1
    assert "FAILED" in capsys.readouterr().out
    import cli

    assert cli.main(["check", str(tmp_path / "missing.csv")]) == 2
    assert cli.main(["check", traj, song, "--json"]) == 1


# ---------------------------------------------------------------- a long file


def test_check_of_a_60_s_song(tmp_path, hand):
    """A 6000-row file checks correctly (its timing is measured in bench/, not asserted here)."""
    pattern = [(60, "index"), (62, "middle"), (64, "ring"), (61, "index")]
    presses = [(*pattern[i % 4], 0.3 + 0.8 * i, 0.6 + 0.8 * i) for i in range(74)]
    t, q = play_trajectory(presses, 59.99)
    assert len(t) == 6000
    traj = write_traj(tmp_path / "long.csv", hand, t, q)
    song = song_file(tmp_path, presses)
    r = check_trajectory(traj, song)
    assert r.ok and r.play.f1 == 1.0 and r.play.notes_hit == 74, r.summary()


# ---------------------------------------------------------------- issue 14: strict, claims, song


def test_strict_fails_on_a_missed_note_and_a_late_one(tmp_path, hand):
    late = [SONG[0], (62, "middle", 1.16, 1.40), SONG[2]]  # D4 60 ms late; C#4 never pressed
    t, q = play_trajectory(late, 3.4)
    traj = write_traj(tmp_path / "l.csv", hand, t, q)
    song = song_file(tmp_path)
    r = check_trajectory(traj, song)
    assert r.ok, r.summary()  # no wrong key, no limit: the default verdict passes
    s = check_trajectory(traj, song, strict=True)
    assert not s.ok
    (m,) = s.play.missed
    (lt,) = s.play.late
    assert (m.name, m.note) == ("C#4", 3) and (lt.name, lt.note) == ("D4", 1)
    assert lt.late_s == pytest.approx(0.06, abs=0.011)
    assert any("1 notes missed" in p for p in s.problems)
    assert any("1 notes late" in p for p in s.problems)
    assert check_cli(_args(trajectory=traj, song=song, strict=True)) == 1


def _claiming(path, hand, t, q, left_out):
    return write_traj(path, hand, t, q, metadata=meta(hand, notes=4), end_info={
        "notes": 4, "played": 4 - len(left_out),
        "left_out": [{"note": i, "reason": "left_out", "detail": "x"} for i in left_out]})


def test_claims_the_replay_contradicts_fail_the_check(tmp_path, hand):
    """A note the end marker says was played, which the replay finds missed, fails the
    verdict even without --strict; a true claim passes."""
    partial = SONG[:3]  # C#4 (note 3) never pressed
    t, q = play_trajectory(partial, 3.4)
    song = song_file(tmp_path)
    honest = check_trajectory(_claiming(tmp_path / "h.csv", hand, t, q, [3]), song)
    assert honest.ok and honest.play.claims and not honest.play.claim_mismatches
    lying = check_trajectory(_claiming(tmp_path / "x.csv", hand, t, q, []), song)
    assert not lying.ok
    (c,) = lying.play.claim_mismatches
    assert (c.note, c.name, c.claimed, c.found) == (3, "C#4", "played", "missed")
    wrong_way = check_trajectory(_claiming(tmp_path / "y.csv", hand, t, q, [0, 3]), song)
    (c,) = wrong_way.play.claim_mismatches
    assert (c.note, c.claimed, c.found) == (0, "left out", "hit")
    bad = _claiming(tmp_path / "z.csv", hand, t, q, [9])  # no note 9 in a song of 4
    with pytest.raises(InputError, match="left_out"):
        check_trajectory(bad, song)


def test_f1_counts_missing_rows_at_the_end_as_misses(tmp_path, hand, good):
    """A file cut to its first rows cannot pass a song it never reaches (issue 14: cut to
    10 %, --min-f1 0.9 passed with F1 1.0)."""
    _, song, t, q = good
    cut = write_traj(tmp_path / "cut.csv", hand, t[:40], q[:40])
    r = check_trajectory(cut, song, min_f1=0.9)
    assert r.play.song_frames == 300 and r.play.notes_hit == 0
    # the four notes sound in 120 frames; rows 30..39 (C4 down from its first frame) are
    # the only ones of them present: 110 frames score 0
    assert r.play.f1 == pytest.approx(1 - 110 / 300)
    assert not r.ok


def test_the_song_is_read_as_the_plan_was(tmp_path, hand):
    """track / channel / transpose come from the metadata; a song of another note count
    is refused (exit 2) with the options named."""
    t, q = play_trajectory(SONG, 3.4)
    high = tmp_path / "high.mid"  # SONG an octave above C8's range would be... C4 + 60
    write_notes_midi([Note(p + 60, on, off, 80) for p, _, on, off in SONG[:1]]
                     + [Note(p, on, off, 80) for p, _, on, off in SONG[1:]], high)
    plain = write_traj(tmp_path / "p.csv", hand, t, q, metadata=meta(hand, notes=4))
    with pytest.raises(InputError, match="outside the piano range|A0-C8|range"):
        check_trajectory(plain, str(high))
    tr = write_traj(tmp_path / "t.csv", hand, t, q, metadata=meta(hand, notes=4, transpose=True))
    r = check_trajectory(tr, str(high))
    assert r.play.notes == 4  # C9 read as C8 .. down by octaves into the range
    other = write_traj(tmp_path / "o.csv", hand, t, q, metadata=meta(hand, notes=5))
    with pytest.raises(InputError, match="planned for a song of 5 notes"):
        check_trajectory(other, song_file(tmp_path))


def test_a_gap_in_the_rows_is_refused_naming_the_row(tmp_path, hand, good):
    _, song, t, q = good
    keep = np.r_[0:60, 110:len(t)]
    write_traj(tmp_path / "gap.csv", hand, t[keep], q[keep])
    with pytest.raises(InputError, match=r"row 61 is at t=1.100000 s, not 0.600000 s"):
        check_trajectory(str(tmp_path / "gap.csv"), song)

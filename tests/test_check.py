"""Tests of planner.check, the independent replay check.

Trajectories are built here without the planner: a tiny damped-least-squares
IK puts one fingertip on a key (wrist flexed 20 deg, the other fingers
hyperextended so their tips stay ~10 cm above the keys), and keyframes are
joined by minimum-jerk segments, which keep speeds and accelerations inside
the hand's limits.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from functools import cache, lru_cache

import numpy as np
import pytest

from planner import check
from planner.check import (
    ball_positions,
    check_cli,
    check_trajectory,
    frame_f1,
    frame_scores,
    key_contacts,
    key_episodes,
    keys_down,
)
from planner.errors import InputError
from planner.hand.model import load_hand
from planner.music.keyboard import key
from planner.music.midi import Note, load_song, write_notes_midi
from planner.trajfile import TrajectoryWriter, read_trajectory

FORBIDDEN = ("planner.play", "planner.ik", "planner.trajectory", "planner.catch",
             "planner.selfcheck")
RATE = 100.0
RAMP_S = 0.08  # press / release ramp; the 5 mm threshold is crossed at its middle


def meta(h, task="play", **extra):
    return {"task": task, "hand": "default", "urdf_sha256": h.urdf_sha256,
            "T_world_root": h.T_world_root.tolist(), "rate_hz": RATE, **extra}


def write_traj(path, hand, t, q, qm=None, metadata=None, joint_names=None, motor_names=None):
    q = np.asarray(q)
    w = TrajectoryWriter(str(path), metadata or meta(hand),
                         joint_names or hand.joint_names, motor_names or hand.motor_names)
    w.write_rows(t, q, hand.motor_angles(q) if qm is None else qm)
    w.close()
    return str(path)


# ---------------------------------------------------------------- a tiny IK


def _idx(hand, *names):
    return [hand.index[n] for n in names]


def base_posture(hand, wrist_deg=20.0):
    q = hand.q_neutral.copy()
    for f in ("index", "middle", "ring", "pinky"):
        q[hand.index[f"{f}_mcp_flex"]] = np.radians(-20.0)
    q[hand.index["wrist_flex"]] = np.radians(wrist_deg)
    return hand.apply_couplings(q)


@cache
def _press_posture(pitch, finger, depth):
    """Joints putting ``finger``'s tip ``depth`` below the top of key ``pitch``
    (negative: above), rail + that finger's MCP/PIP, the rest at base_posture."""
    hand = load_hand("default")
    q = base_posture(hand)
    fi = hand.fingers.index(finger)
    act = _idx(hand, "rail", f"{finger}_mcp_flex", f"{finger}_pip")
    k = key(pitch)
    y = 0.09 if k.black else 0.12  # inside the footprint, clear of the black keys
    target = np.array([k.center_x_m, y, k.top_z_m - depth])
    indep = list(hand.independent)
    cols = [indep.index(a) for a in act]
    q[0] += target[0] - hand.tip_positions(q)[fi][0]
    for _ in range(500):
        e = target - hand.tip_positions(q)[fi]
        if np.linalg.norm(e) < 1e-10:
            break
        Ja = (hand.tip_jacobians(q)[fi] @ hand.dq_dindependent(q))[:, cols]
        dq = Ja.T @ np.linalg.solve(Ja @ Ja.T + 1e-6 * np.eye(3), e)
        dq *= min(1.0, 0.1 / np.max(np.abs(dq)))
        q[act] += dq
        q = hand.apply_couplings(np.clip(q, hand.lower, hand.upper))
    assert np.linalg.norm(target - hand.tip_positions(q)[fi]) < 1e-7, "test IK failed"
    return q


def press_posture(pitch, finger, depth):
    return _press_posture(pitch, finger, round(depth, 6)).copy()


def min_jerk(times, keyframes, t):
    """Minimum-jerk blend between consecutive (time, q) keyframes, at rest at each."""
    times = np.asarray(times)
    Q = np.asarray(keyframes)
    t = np.clip(t, times[0], times[-1])
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    s = (t - times[i]) / (times[i + 1] - times[i])
    b = (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None]
    return Q[i] * (1 - b) + Q[i + 1] * b


def play_trajectory(presses, t_end, depth=0.010):
    """Rows at RATE for presses = [(pitch, finger, onset, offset[, depth])]: the key
    goes down at the frame of ``onset`` and up at the frame of ``offset``."""
    hand = load_hand("default")
    times, frames = [0.0], [press_posture(presses[0][0], presses[0][1], -0.015)]
    half = 0.5 / RATE  # the threshold crossing sits between two frames
    for p in presses:
        pitch, finger, on, off = p[:4]
        d = p[4] if len(p) > 4 else depth
        hover, up, down = (press_posture(pitch, finger, x) for x in (-0.015, 0.0, d))
        ramp_on = on - half - RAMP_S / 2
        if times[-1] < ramp_on - 0.1 - 1e-9:
            times.append(ramp_on - 0.1)
            frames.append(hover)
        times += [ramp_on, on - half + RAMP_S / 2, off - half - RAMP_S / 2, off - half + RAMP_S / 2]
        frames += [up, down, down, up]
    times.append(times[-1] + 0.1)
    frames.append(press_posture(presses[-1][0], presses[-1][1], -0.015))
    assert np.all(np.diff(times) >= RAMP_S - 1e-9), times
    t = np.arange(round(t_end * RATE) + 1) / RATE
    q = hand.apply_couplings(min_jerk(times, frames, t))
    return t, q


SONG = [(60, "index", 0.30, 0.60), (62, "middle", 1.10, 1.40),
        (64, "ring", 1.90, 2.20), (61, "index", 2.70, 3.00)]


def song_file(tmp_path, presses=SONG):
    path = tmp_path / "song.mid"
    # times on the MIDI tick grid (1/960 s) so that the file reads back exactly
    write_notes_midi([Note(p, on, off, 80) for p, _, on, off, *_ in presses], path)
    return str(path)


@pytest.fixture()
def good(tmp_path, hand):
    t, q = play_trajectory(SONG, 3.4)
    return write_traj(tmp_path / "good.csv", hand, t, q), song_file(tmp_path), t, q


def rewrite(path, fn):
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    lines = fn(lines)
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines))
    return path


# ---------------------------------------------------------------- independence


def test_imports_no_planner_stage():
    with open(check.__file__, encoding="utf-8") as f:
        src = f.read()
    for mod in FORBIDDEN:
        assert f"import {mod}" not in src and f"from {mod} " not in src, mod
    # and importing it does not pull them in
    code = (f"import sys, planner.check; bad = [m for m in sys.modules if m in {FORBIDDEN!r}]; "
            "print(bad); assert not bad")
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
        "joint_position", "joint_velocity", "joint_acceleration", "motor_velocity",
        "motor_consistency", "motor_torque", "coupling", "tendon_tension"}
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
    hits = r.play.key_bed_hits
    assert hits and {(h.finger, h.name) for h in hits} == {("middle", "D4")}
    assert max(h.depth_m for h in hits) == pytest.approx(0.015, abs=1e-5)
    assert all(1.0 < h.time_s < 1.5 for h in hits)
    assert any("key-bed" in p for p in r.problems)


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
    p = tmp_path / "col.csv"
    w = TrajectoryWriter(str(p), meta(hand), names, hand.motor_names)
    w.write_rows(t, q[:, cols], hand.motor_angles(q))
    w.close()
    with pytest.raises(InputError, match="missing ring_pip"):
        check_trajectory(str(p))
    p = tmp_path / "mcol.csv"
    w = TrajectoryWriter(str(p), meta(hand), hand.joint_names, [*hand.motor_names, "extra"])
    w.write_rows(t, q, np.c_[hand.motor_angles(q), np.zeros(len(t))])
    w.close()
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
    base = {"trajectory": None, "song": None, "allow_incomplete": False, "min_f1": None,
            "json": False, "played": None, "report": None, "html": None}
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


@pytest.mark.skipif(importlib.util.find_spec("planner.report") is not None,
                    reason="planner.report exists")
def test_cli_report_needs_report_module(good):
    with pytest.raises(InputError, match="--report needs planner.report"):
        check_cli(_args(trajectory=good[0], report="out"))


# ---------------------------------------------------------------- catch


def test_ball_closed_form_and_rk4():
    p0, v0 = np.array([0.0, 0.1, 1.0]), np.array([4.0, -0.5, 3.0])
    t = np.array([0.0, 0.1234, 0.5, 0.9])
    want = p0 + np.outer(t, v0) + 0.5 * np.outer(t**2, [0, 0, -9.81])
    np.testing.assert_allclose(ball_positions(p0, v0, 0.0, t), want, atol=1e-12)
    # RK4 with a vanishing drag tends to the closed form
    np.testing.assert_allclose(ball_positions(p0, v0, 1e-12, t), want, atol=1e-9)
    # and with drag it matches a tight reference integration
    from scipy.integrate import solve_ivp

    k = 0.02

    def f(_, s):
        v = s[3:]
        return np.r_[v, np.array([0, 0, -9.81]) - k * np.linalg.norm(v) * v]

    ref = solve_ivp(f, (0, 0.9), np.r_[p0, v0], t_eval=t, rtol=1e-12, atol=1e-12).y[:3].T
    got = ball_positions(p0, v0, k, t[::-1])[::-1]  # any order of times
    np.testing.assert_allclose(got, ref, atol=1e-9)
    assert np.linalg.norm(got[-1] - want[-1]) > 1e-3  # drag matters


BALL_R = 0.05
T_I = 0.5
SPEED = 6.0


@lru_cache(maxsize=1)
def grasp_posture():
    """Thumb, index and middle tips 4 mm off a ball resting on the palm."""
    hand = load_hand("default")
    q = hand.q_neutral.copy()
    q[_idx(hand, "thumb_cmc_abd", "thumb_cmc_flex", "thumb_ip")] = np.radians([30, 60, 40])
    P = hand.palm_pose(q)
    C = P[:3, 3] + BALL_R * P[:3, 2]
    fj = {f: _idx(hand, *(("thumb_cmc_abd", "thumb_cmc_flex", "thumb_ip") if f == "thumb" else
                          (f"{f}_mcp_abd", f"{f}_mcp_flex", f"{f}_pip")))
          for f in ("thumb", "index", "middle")}
    indep = list(hand.independent)
    for _ in range(3000):
        tips = hand.tip_positions(q)
        Js = hand.tip_jacobians(q) @ hand.dq_dindependent(q)
        for f, act in fj.items():
            fi = hand.fingers.index(f)
            d = tips[fi] - C
            e = C + (BALL_R + 0.004) * d / np.linalg.norm(d) - tips[fi]
            Ja = Js[fi][:, [indep.index(a) for a in act]]
            dq = Ja.T @ np.linalg.solve(Ja @ Ja.T + 1e-4 * np.eye(3), e)
            q[act] += dq * min(1.0, 0.05 / np.max(np.abs(dq)))
        q = hand.apply_couplings(np.clip(q, hand.lower, hand.upper))
    dist = np.linalg.norm(hand.tip_positions(q) - C, axis=1)[:3] - BALL_R
    assert np.all(np.abs(dist - 0.004) < 1e-4), dist
    return q, C, P[:3, 2]


STOP_M = 0.10  # this test ball (0.2 kg at 6 m/s) stopped over 10 cm: 36 N, within the
# wrist flexion motor's 2 N m (over the catch planner's 2 cm it would need 180 N)


def catch_file(path, hand, offset=(0.0, 0.0, 0.0), close_from=T_I - 0.12, close_s=0.25,
               hold_to=None, t_end=T_I + 0.4):
    """A catch: the ball arrives along -normal at SPEED onto the palm (plus
    ``offset``); the fingers close by min-jerk over [close_from, close_from + close_s]."""
    q_grasp, C, n = grasp_posture()
    q_open = hand.q_neutral.copy()
    v_i = -SPEED * n
    g = np.array([0, 0, -9.81])
    v0 = v_i - g * T_I
    p0 = C + np.asarray(offset) - v0 * T_I - 0.5 * g * T_I**2
    t = np.arange(round(t_end * RATE) + 1) / RATE
    frames = [q_open, q_open, q_grasp, q_grasp]
    times = [0.0, close_from, close_from + close_s, t_end + 1]
    if hold_to is not None:
        frames += [q_open, q_open]
        times = [0.0, close_from, close_from + close_s, hold_to, hold_to + 0.25, t_end + 1]
    q = hand.apply_couplings(min_jerk(times, frames, t))
    m = meta(hand, "catch", ball={"p0": p0.tolist(), "v0": v0.tolist(), "radius": BALL_R,
                                  "mass": 0.2, "drag": 0.0}, intercept_t=T_I,
             catch={"stop_distance_m": STOP_M})
    return write_traj(path, hand, t, q, metadata=m)


def test_catch_passes(tmp_path, hand):
    r = check_trajectory(catch_file(tmp_path / "c.csv", hand))
    assert r.ok, r.summary()
    c = r.catch
    assert c.intercept_ok and c.intercept_error_m < 1e-5
    assert not c.early_touches and c.grasp_held
    assert c.grasp_time_s <= T_I + 0.150 and {"thumb", "index", "middle"} <= set(c.grasp_fingers)
    assert r.play is None
    d = json.loads(json.dumps(r.to_dict()))
    assert d["catch"]["ok"] is True and d["ok"] is True
    assert "catch at t=0.500 s" in r.summary()


def test_catch_palm_off_by_5cm(tmp_path, hand):
    _q_grasp, _C, n = grasp_posture()
    side = np.cross(n, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    r = check_trajectory(catch_file(tmp_path / "c.csv", hand, offset=0.05 * side))
    assert not r.ok and not r.catch.intercept_ok
    assert r.catch.intercept_error_m == pytest.approx(0.05, abs=1e-5)
    assert any("misses the palm: 50.0 mm" in p for p in r.problems)


def test_catch_early_touch_late_grasp_and_release(tmp_path, hand):
    # closed before the ball arrives: the fingertips are in its way
    r = check_trajectory(catch_file(tmp_path / "a.csv", hand, close_from=0.1))
    assert not r.ok and r.catch.early_touches
    assert all(e.time_s < T_I and e.distance_m < BALL_R for e in r.catch.early_touches)
    # closing too late
    r = check_trajectory(catch_file(tmp_path / "b.csv", hand, close_from=T_I + 0.1))
    assert not r.ok and r.catch.grasp_time_s is None
    assert any("no grasp within 150 ms" in p for p in r.problems)
    # grasped, then let go
    r = check_trajectory(catch_file(tmp_path / "c.csv", hand, hold_to=T_I + 0.2))
    assert not r.ok and r.catch.grasp_time_s is not None and not r.catch.grasp_held
    assert any("grasp lost" in p for p in r.problems)


def test_catch_intercept_outside_and_bad_metadata(tmp_path, hand):
    path = catch_file(tmp_path / "c.csv", hand, t_end=0.3)
    r = check_trajectory(path)
    assert not r.ok and any("outside the trajectory" in p for p in r.problems)

    def drop_radius(ls):
        m = json.loads(ls[0][2:])
        del m["ball"]["radius"]
        return ["# " + json.dumps(m)] + ls[1:]

    with pytest.raises(InputError, match="radius"):
        check_trajectory(rewrite(path, drop_radius))


def test_catch_frame_mount_may_differ(tmp_path, hand):
    """The catch frame's origin is the launch point: the hand may be mounted anywhere."""
    path = catch_file(tmp_path / "c.csv", hand)
    shift = np.array([2.0, 0.0, 1.0])

    def move(ls):
        m = json.loads(ls[0][2:])
        T = np.array(m["T_world_root"])
        T[:3, 3] += shift
        m["T_world_root"] = T.tolist()
        m["ball"]["p0"] = (np.array(m["ball"]["p0"]) + shift).tolist()
        return ["# " + json.dumps(m)] + ls[1:]

    r = check_trajectory(rewrite(path, move))
    assert r.ok, r.summary()
    assert r.catch.ball_at_intercept[0] == pytest.approx(
        check_trajectory(catch_file(tmp_path / "d.csv", hand)).catch.ball_at_intercept[0] + 2.0)


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
    w = TrajectoryWriter(str(path), meta(hand, notes=4), hand.joint_names, hand.motor_names)
    w.write_rows(t, q, hand.motor_angles(q))
    w.close({"notes": 4, "played": 4 - len(left_out),
             "left_out": [{"note": i, "reason": "left_out", "detail": "x"} for i in left_out]})
    return str(path)


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
    w = TrajectoryWriter(str(tmp_path / "gap.csv"), meta(hand), hand.joint_names,
                         hand.motor_names)
    w.write_rows(t[keep], q[keep], hand.motor_angles(q[keep]))
    w.close()
    with pytest.raises(InputError, match=r"row 61 is at t=1.100000 s, not 0.600000 s"):
        check_trajectory(str(tmp_path / "gap.csv"), song)


def test_catch_stopping_force_judged(tmp_path, hand):
    """The dynamic judgment: the same catch stopped over 2 cm needs 5x the force of 10 cm,
    more than the wrist flexion motor can give; the loads are reported per phase."""
    ok = check_trajectory(catch_file(tmp_path / "c.csv", hand))
    stop, hold = ok.catch.loads
    assert stop.phase == "stop" and hold.phase == "hold"
    assert stop.speed_m_s == pytest.approx(SPEED, rel=1e-3)
    # F = m (v^2 / (2 d) n - g): against the arrival (along -n), and the weight
    n = grasp_posture()[2]
    want = np.linalg.norm(0.2 * (SPEED**2 / (2 * STOP_M) * n + np.array([0.0, 0.0, 9.81])))
    assert stop.force_n == pytest.approx(want, rel=1e-3)
    assert 0.0 < stop.headroom < 1.0 and ok.ok
    tr = read_trajectory(str(tmp_path / "c.csv"))
    meta = dict(tr.metadata, catch={"stop_distance_m": 0.02})
    bad = write_traj(tmp_path / "hard.csv", hand, tr.t_s, tr.q, metadata=meta)
    rep = check_trajectory(bad)
    assert not rep.ok and rep.catch.loads[0].headroom < 0
    assert any(p.startswith("stopping the ball needs") and "motor.wrist_flex" in p
               for p in rep.problems)
    del meta["catch"]
    rep = check_trajectory(write_traj(tmp_path / "none.csv", hand, tr.t_s, tr.q, metadata=meta))
    assert not rep.ok and any("no stopping distance" in p for p in rep.problems)


def test_catch_plan_edited_to_stop_over_2_mm_rejected(tmp_path):
    """Issue 15: the planner's feasible plan (30 deg from 1.5 m) passes; the same rows
    with its metadata edited to stop the ball over 2 mm instead of 2 cm do not."""
    from planner.catch.plan import plan_catch

    res = plan_catch(30.0, 1.5, 0.0, "default", str(tmp_path / "c.csv"))
    assert res.feasible
    good = check_trajectory(str(tmp_path / "c.csv"))
    assert good.ok, good.problems
    assert good.catch.loads[0].headroom == pytest.approx(res.plan.stop.headroom, abs=0.03)
    text = (tmp_path / "c.csv").read_text()
    assert text.count('"stop_distance_m": 0.02') == 1
    (tmp_path / "e.csv").write_text(text.replace('"stop_distance_m": 0.02',
                                                 '"stop_distance_m": 0.002'))
    rep = check_trajectory(str(tmp_path / "e.csv"))
    assert not rep.ok
    assert rep.catch.loads[0].force_n > 9 * good.catch.loads[0].force_n
    assert rep.problems == tuple(p for p in rep.problems if p.startswith("stopping the ball"))


def test_values_as_written_are_the_files_bit_for_bit():
    """``as_written`` (the rows the writer hands its self-check) is what reading the
    file's 6-decimal text gives, bit for bit: on random values of every scale, halves
    and near-halves of the last decimal, negative zeros, and values a product's
    rounding could decide."""
    from planner.trajfile import as_written

    rng = np.random.default_rng(9)
    x = np.concatenate([rng.normal(0.0, 1.0, 20000), rng.uniform(-0.62, 0.7, 20000),
                        rng.uniform(-4000.0, 4000.0, 5000),
                        (np.arange(-3000, 3000) + 0.5) / 1e6,  # (exact halves)
                        (rng.integers(-10**7, 10**7, 5000) + 0.5) * 1e-6,  # (near halves)
                        [-4e-7, -0.0, 0.0, 4e-7, 1e12, -2.5e-6, np.inf, -np.inf]])
    got = as_written(x)
    want = np.array([float(f"{v:.6f}") for v in x.tolist()])
    assert np.array_equal(np.signbit(got), np.signbit(want))
    assert got.tobytes() == want.tobytes()


def test_the_rows_a_writer_returns_are_the_files(tmp_path, hand):
    """``write_rows`` hands back (to the self-check) the rows as the file holds them."""
    rng = np.random.default_rng(10)
    t = np.arange(300) / 100.0
    q = np.clip(hand.lower + (hand.upper - hand.lower) * rng.random((300, hand.n)),
                hand.lower, hand.upper)
    q[100:150] = q[99]  # (rows equal to the one before: formatted once)
    w = TrajectoryWriter(str(tmp_path / "r.csv"), {"task": "play", "hand": hand.name,
                         "urdf_sha256": hand.urdf_sha256,
                         "T_world_root": hand.T_world_root.tolist(), "rate_hz": 100.0},
                         hand.joint_names, hand.motor_names)
    got = np.concatenate([w.write_rows(t[:120], q[:120], hand.motor_angles(q[:120])),
                          w.write_rows(t[120:], q[120:], hand.motor_angles(q[120:]))])
    w.close()
    tr = read_trajectory(str(tmp_path / "r.csv"))
    assert got.tobytes() == np.column_stack([tr.t_s, tr.q, tr.q_motor]).tobytes()

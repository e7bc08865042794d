"""Tests of planner.report: PNG plots and the offline meshcat animation of a check.

Inputs are built without the planner (tests/trajbuild.py): a short
play trajectory with one missed note and one wrong press, and a catch with
the hand mounted tilted so that the ball arrives on a lob.
"""

from __future__ import annotations

import base64
import json
import re
import struct

import numpy as np
import pytest

from planner.check import ball_positions, check_trajectory
from planner.report import write_check_report, write_html
from planner.report.html import _frame_rows
from tests.trajbuild import (
    BALL_R,
    PAD10_HAND,
    RATE,
    SONG,
    SPEED,
    STOP_M,
    T_I,
    grasp_posture,
    meta,
    min_jerk,
    open_posture,
    play_trajectory,
    song_file,
    write_traj,
)

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PLAY_PNGS = ("play_piano_roll.png", "play_fingertip_heights.png", "joint_positions.png",
             "joint_speeds.png", "motor_angles.png", "motor_speeds.png")
CATCH_PNGS = ("catch_paths.png", "catch_closing.png", "joint_positions.png",
              "joint_speeds.png", "motor_angles.png", "motor_speeds.png")


@pytest.fixture(scope="module")
def play_report(tmp_path_factory, hand):
    """SONG is played except its last note (missed); an extra D4 is played that
    the song does not have (a wrong press)."""
    d = tmp_path_factory.mktemp("play")
    presses = SONG[:-1] + [(62, "middle", 2.70, 3.00)]
    t, q = play_trajectory(presses, 3.5)
    traj = write_traj(d / "play.csv", hand, t, q)
    song = song_file(d, SONG)
    r = check_trajectory(traj, song)
    assert r.play.missed and r.play.wrong_presses, r.summary()
    return r


def tilted_catch_file(path, hand, tilt_deg=120.0):
    """test_check's catch with the hand's mount turned about y by ``tilt_deg``:
    the palm faces the launch point and the ball comes in on a lob; launch at
    the origin of the catch frame."""
    q_grasp, C, n = grasp_posture()
    th = np.radians(tilt_deg)
    R = np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])
    g = np.array([0.0, 0.0, -9.81])
    v0 = -SPEED * (R @ n) - g * T_I
    p0 = R @ C - v0 * T_I - 0.5 * g * T_I**2  # in the rotated frame; shift it to the origin
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = -p0
    T = T @ hand.T_world_root
    t = np.arange(round((T_I + 0.4) * RATE) + 1) / RATE
    q_open = open_posture(hand)
    q = hand.apply_couplings(min_jerk([0.0, T_I - 0.12, T_I + 0.13, T_I + 2.0],
                                      [q_open, q_open, q_grasp, q_grasp], t))
    m = meta(hand, "catch", ball={"p0": [0.0, 0.0, 0.0], "v0": v0.tolist(), "radius": BALL_R,
                                  "mass": 0.2, "drag": 0.0}, intercept_t=T_I,
             catch={"stop_distance_m": STOP_M}, hand=PAD10_HAND)
    m["T_world_root"] = T.tolist()
    return write_traj(path, hand, t, q, metadata=m)


@pytest.fixture(scope="module")
def catch_report(tmp_path_factory, hand):
    d = tmp_path_factory.mktemp("catch")
    r = check_trajectory(tilted_catch_file(d / "catch.csv", hand))
    assert r.catch.intercept_ok and r.catch.grasp_held, r.summary()
    return r


def _read(path) -> str:
    with open(path, encoding="utf-8") as f:
        return f.read()


def _png_ok(path):
    import matplotlib.image as mpimg

    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == PNG_SIGNATURE, path
    w, h = struct.unpack(">II", head[16:24])  # IHDR
    img = mpimg.imread(path)
    assert img.shape[:2] == (h, w)
    assert img.ndim == 3 and img.shape[2] in (3, 4)
    assert 400 <= w <= 4000 and 300 <= h <= 3000, (path, w, h)
    assert img[..., :3].std() > 0.01  # not a blank canvas


def test_play_pngs(play_report, tmp_path):
    paths = write_check_report(play_report, str(tmp_path / "out"))
    assert [p.split("/")[-1] for p in paths] == list(PLAY_PNGS)
    for p in paths:
        _png_ok(p)


def test_catch_pngs(catch_report, tmp_path):
    paths = write_check_report(catch_report, str(tmp_path / "out"))
    assert [p.split("/")[-1] for p in paths] == list(CATCH_PNGS)
    for p in paths:
        _png_ok(p)


def _commands(text):
    import umsgpack

    m = re.search(r"var sceneCommands = \[(.*?)\];", text, re.DOTALL)
    assert m
    return [umsgpack.unpackb(base64.b64decode(s)) for s in re.findall(r'"([A-Za-z0-9+/=]+)"',
                                                                         m.group(1))]


def _offline(text):
    assert not re.search(r"<script[^>]*\bsrc\s*=", text, re.IGNORECASE)
    assert not re.search(r"<link[^>]*\bhref\s*=", text, re.IGNORECASE)
    # the inlined viewer only mentions the XHTML namespace
    assert set(re.findall(r"https?://[^\s\"'<>]*", text)) <= {"http://www.w3.org/1999/xhtml"}


def _animation(cmds):
    anims = [c for c in cmds if c["type"] == "set_animation"]
    assert len(anims) == 1 and cmds[-1] is anims[0]  # played after every object exists
    return {a["path"]: a["clip"] for a in anims[0]["animations"]}


def test_play_html(play_report, tmp_path, monkeypatch):
    import meshcat.visualizer

    def no_server(*a, **k):
        raise AssertionError("write_html must not start meshcat's server")

    monkeypatch.setattr(meshcat.visualizer, "start_zmq_server_as_subprocess", no_server)
    (tmp_path / "a").mkdir()  # (no folder is created for it: issue 32)
    out = write_html(play_report, str(tmp_path / "a" / "play.html"))
    text = _read(out)
    assert text.startswith("<!DOCTYPE html>") and "MeshCat.Viewer" in text
    _offline(text)
    cmds = _commands(text)
    clips = _animation(cmds)
    rows, fps = _frame_rows(play_report.replay.t_s)
    assert fps == 25.0 and len(rows) == 88  # 3.5 s: frames at 0, 0.04, ..., 3.48 s
    # the hand's links and tips are animated, one key per frame
    tip = clips["/meshcat/hand/index_tip"]
    pos = next(tr for tr in tip["tracks"] if tr["name"] == ".position")
    assert len(pos["keys"]) == len(rows)
    got = np.array([k["value"] for k in pos["keys"]])
    np.testing.assert_allclose(got, play_report.replay.tips[rows, 1], atol=1e-6)
    assert "/meshcat/hand/palm" in clips and "/meshcat/hand/index_base" in clips
    # 88 keys; the pressed ones move down (at most the dip)
    objs = {c["path"] for c in cmds if c["type"] == "set_object"}
    assert sum(p.startswith("/meshcat/keyboard/") and p.endswith("/box") for p in objs) == 88
    c4 = next(tr for tr in clips["/meshcat/keyboard/60"]["tracks"] if tr["name"] == ".position")
    z = np.array([k["value"][2] for k in c4["keys"]])
    assert z.max() == pytest.approx(0.0, abs=1e-7) and z.min() == pytest.approx(-0.010, abs=1e-6)
    assert "/meshcat/keyboard/71" not in clips  # B4 is never touched
    # deterministic
    (tmp_path / "b").mkdir()
    out2 = write_html(play_report, str(tmp_path / "b" / "play.html"))
    assert _read(out2) == _read(out)


def test_catch_html(catch_report, tmp_path):
    out = write_html(catch_report, str(tmp_path / "catch.html"))
    text = _read(out)
    _offline(text)
    cmds = _commands(text)
    clips = _animation(cmds)
    ball = next(tr for tr in clips["/meshcat/ball"]["tracks"] if tr["name"] == ".position")
    rows, _ = _frame_rows(catch_report.replay.t_s)
    assert len(ball["keys"]) == len(rows)
    assert np.allclose(ball["keys"][0]["value"], 0.0, atol=1e-6)  # launched from the origin
    # in flight before the intercept, on the palm (centre + radius * normal) from it on
    rp, tr = catch_report.replay, catch_report.replay.t_s[rows]
    i = int(np.flatnonzero(tr < T_I)[-1])
    m = json.loads(_read(catch_report.trajectory).split("\n", 1)[0][2:])["ball"]
    np.testing.assert_allclose(ball["keys"][i]["value"],
                               ball_positions(m["p0"], m["v0"], 0.0, [tr[i]])[0], atol=1e-5)
    palm = rp.palm[rows[-1]]
    np.testing.assert_allclose(ball["keys"][-1]["value"], palm[:3, 3] + BALL_R * palm[:3, 2],
                               atol=1e-5)
    assert not any(c["type"] == "set_object" and c["path"].startswith("/meshcat/keyboard")
                   for c in cmds)
    out2 = write_html(catch_report, str(tmp_path / "again.html"))
    assert _read(out2) == _read(out)


def test_long_plans_are_subsampled():
    t = np.arange(20000) / 100.0  # 200 s at 100 Hz
    rows, fps = _frame_rows(t)
    assert len(rows) <= 2000 and fps < 25.0
    assert rows[0] == 0 and rows[-1] == len(t) - 1 and np.all(np.diff(rows) > 0)
    rows, fps = _frame_rows(np.arange(101) / 100.0)
    assert fps == 25.0 and list(rows) == list(range(0, 101, 4))


def test_check_cli_writes_report_and_html(catch_report, tmp_path, capsys):
    """``cli.py check TRAJ --report DIR --html FILE`` goes through planner.report."""
    import cli

    out, page = tmp_path / "rep", tmp_path / "page.html"
    rc = cli.main(["check", catch_report.trajectory, "--report", str(out), "--html", str(page)])
    assert rc == 0, capsys.readouterr()
    assert sorted(p.name for p in out.iterdir()) == sorted(CATCH_PNGS)
    assert page.stat().st_size > 100_000

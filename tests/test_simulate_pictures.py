"""simulate --video / --html (planner.simulate.pictures, render, video, page): the mp4
and the page read back, their error paths, FIFO and symlink outputs."""

from __future__ import annotations

import base64
import io
import json
import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")
av = pytest.importorskip("av")

import planner
from planner.cli import main
from planner.hand.model import load_hand
from planner.simulate.page import frame_jpeg, page_html
from planner.simulate.render import frame_rows
from planner.simulate.video import encode_mp4
from planner.trajfile import TrajectoryWriter, read_trajectory

ROOT = Path(__file__).resolve().parents[1]
ROWS = 60  # 0.6 s of twinkle: its first note pressed and released


def _frames(n: int, h: int = 48, w: int = 64) -> list[np.ndarray]:
    """A white square moving across a dark ground, one step a frame."""
    out = []
    for i in range(n):
        img = np.full((h, w, 3), 30, dtype=np.uint8)
        img[10:26, 2 + 3 * i:18 + 3 * i] = 240
        out.append(img)
    return out


def _read_mp4(data: bytes):
    with av.open(io.BytesIO(data)) as c:
        s = c.streams.video[0]
        frames = [f.to_ndarray(format="rgb24") for f in c.decode(video=0)]
        return s.codec_context.name, s.width, s.height, float(s.average_rate), frames


def test_mp4_holds_the_frames_at_their_rate():
    src = _frames(12)
    data = encode_mp4(src, 25.0)
    assert data[4:8] == b"ftyp"
    codec, w, h, fps, frames = _read_mp4(data)
    assert (codec, w, h, fps, len(frames)) == ("h264", 64, 48, 25.0, 12)
    for a, b in zip(src, frames):  # lossy, but the square is where it was
        assert np.abs(a.astype(int) - b.astype(int)).mean() < 6.0
    assert encode_mp4(_frames(12), 25.0) == data  # the same bytes again


def test_page_holds_every_frame_and_needs_nothing_outside():
    src = _frames(5)
    page = page_html("t<itle>", "summary & more", [frame_jpeg(f) for f in src],
                     [0.0, 0.04, 0.08, 0.12, 0.16], 25.0)
    frames = json.loads(re.search(r'id="frames">(.*?)</script>', page, re.DOTALL).group(1))
    times = json.loads(re.search(r'id="times">(.*?)</script>', page, re.DOTALL).group(1))
    assert len(frames) == 5 and times == [0.0, 0.04, 0.08, 0.12, 0.16]
    from PIL import Image

    for b64, f in zip(frames, src):
        with Image.open(io.BytesIO(base64.b64decode(b64))) as im:
            assert im.format == "JPEG" and im.size == (64, 48)
            assert np.abs(np.asarray(im).astype(int) - f.astype(int)).mean() < 8.0
    assert "t&lt;itle&gt;" in page and "summary &amp; more" in page
    assert not re.search(r'(src|href)="(https?:)?//', page)  # no CDN, no network
    assert 'max="4"' in page


def test_frame_rows_every_25th_of_a_second_and_capped():
    t = np.arange(0, 962) / 100.0
    f = frame_rows(t)
    assert f.fps == 25.0 and len(f.rows) == 241 and np.all(np.diff(f.rows) == 4)
    f = frame_rows(np.arange(0, 10001) / 100.0, max_frames=500)  # 100 s
    assert len(f.rows) == 500 and f.fps == pytest.approx(499 / 100.0)


@pytest.fixture(scope="module")
def short_play(tmp_path_factory):
    """Twinkle's first 0.6 s as a trajectory of its own (no song: keys scored alone)."""
    hand = load_hand("default")
    d = tmp_path_factory.mktemp("pictures")
    full = d / "twinkle.csv"
    planner.plan_song(planner.load_song("songs/twinkle.mid"), hand, str(full))
    tr = read_trajectory(str(full))
    path = d / "short.csv"
    w = TrajectoryWriter(str(path), {k: v for k, v in tr.metadata.items()
                                     if k not in ("format", "version")},
                         hand)
    w.write_rows(tr.t_s[:ROWS], tr.q[:ROWS], hand.motor_angles(tr.q[:ROWS]))
    w.close({})
    return path


def _cli(*args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}  # the CLI picks egl
    return subprocess.run([sys.executable, "cli.py", "simulate", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True, check=False)


def test_cli_writes_the_video_and_the_page_of_one_run(short_play, tmp_path):
    video, page = tmp_path / "run.mp4", tmp_path / "run.html"
    r = _cli(str(short_play), "--contact", "pads", "--video", str(video), "--html", str(page),
             "--json")
    assert r.returncode in (0, 1), r.stderr
    d = json.loads(r.stdout)
    assert d["video"] == str(video) and d["html"] == str(page)
    n = len(frame_rows(np.arange(ROWS) / 100.0).rows)  # 0.59 s at 25 fps: 15 frames
    codec, w, h, fps, frames = _read_mp4(video.read_bytes())
    assert (codec, w, h, fps, len(frames)) == ("h264", 960, 360, 25.0, n)
    assert frames[0].std() > 10  # a picture, not a blank
    text = page.read_text()
    b64 = json.loads(re.search(r'id="frames">(.*?)</script>', text, re.DOTALL).group(1))
    assert len(b64) == n and "physics frame" not in text  # (no song: no F1 line)
    assert "contact pads" in text and " in " not in text.split("simulated")[1].split("\n")[0]


def test_outputs_written_through_fifo_and_symlink(short_play, tmp_path):
    fifo = tmp_path / "page.fifo"
    os.mkfifo(fifo)
    target = tmp_path / "real.mp4"
    target.write_bytes(b"old")
    link = tmp_path / "link.mp4"
    link.symlink_to(target)
    got = {}

    def read():
        with open(fifo, "rb") as f:
            got["page"] = f.read()

    reader = threading.Thread(target=read)
    reader.start()
    r = _cli(str(short_play), "--contact", "pads", "--html", str(fifo), "--video", str(link))
    reader.join()
    assert r.returncode in (0, 1), r.stderr
    assert got["page"].startswith(b"<!DOCTYPE html>")
    assert fifo.is_fifo() and link.is_symlink() and os.readlink(link) == str(target)
    assert target.read_bytes()[4:8] == b"ftyp"


@pytest.mark.parametrize("where", ["dir", "nofolder"])
def test_bad_output_path_is_one_line_exit_2_before_simulating(short_play, tmp_path, capsys,
                                                              where):
    bad = str(tmp_path) if where == "dir" else str(tmp_path / "missing" / "x.mp4")
    for option in ("--video", "--html"):
        assert main(["simulate", str(short_play), option, bad]) == 2
        out = capsys.readouterr()
        assert out.out == "" and len(out.err.strip().splitlines()) == 1
        assert out.err.startswith("error: cannot write")


def test_missing_encoder_is_one_line_exit_2(short_play, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "av", None)  # import av -> ImportError
    assert main(["simulate", str(short_play), "--video", str(tmp_path / "x.mp4")]) == 2
    err = capsys.readouterr().err
    assert err.strip() == 'error: --video needs PyAV: pip install -e ".[physics]"'
    assert not (tmp_path / "x.mp4").exists()

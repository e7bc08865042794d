"""planner.progress: a bar on a terminal (rate, time left), nothing on a pipe or with
--json; the CLI's play, --report and batch draw it."""

from __future__ import annotations

import fcntl
import os
import pty
import shutil
import struct
import subprocess
import sys
import termios
from pathlib import Path

from planner.progress import Progress, progress_bar

ROOT = Path(__file__).resolve().parents[1]
TWINKLE = ROOT / "songs" / "twinkle.mid"


def _on_terminal(args: list[str], cwd: Path) -> tuple[int, str]:
    """Run the CLI with stderr on a pseudo-terminal of 40 x 120 (stdout a pipe); its exit
    status and what the terminal showed."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    proc = subprocess.Popen([sys.executable, str(ROOT / "cli.py"), *args], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=slave, stdin=subprocess.DEVNULL)
    os.close(slave)
    shown = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # (EIO: the child closed the terminal)
            break
        if not chunk:
            break
        shown += chunk
    os.close(master)
    proc.stdout.read()
    return proc.wait(), shown.decode("utf-8", "replace")


def test_disabled_progress_draws_nothing_and_writes_lines_plainly(capsys):
    bar = Progress("note", enabled=False)
    bar.update(3, 10)
    bar.write("a line")
    bar.close()
    assert capsys.readouterr().err == "a line\n"


def test_not_a_terminal_means_no_bar(capsys):
    # (pytest's captured stderr is not a terminal)
    with progress_bar("song") as bar:
        assert not bar.enabled
        bar.update(1, 2)
        bar.write("x")
    assert capsys.readouterr().err == "x\n"


def test_play_draws_a_bar_with_rate_and_time_left_on_a_terminal(tmp_path):
    status, shown = _on_terminal(["play", str(TWINKLE), "-o", "t.csv"], tmp_path)
    assert status == 0
    assert "note/s" in shown and "/14 [" in shown  # tqdm: "n/14 [elapsed<left, rate]"
    assert "twinkle.mid: 14 notes" in shown  # the summary after the bar


def test_play_on_a_pipe_has_no_bar(tmp_path):
    res = subprocess.run([sys.executable, str(ROOT / "cli.py"), "play", str(TWINKLE), "-o",
                          "t.csv"], cwd=tmp_path, capture_output=True, text=True, check=False)
    assert res.returncode == 0
    assert "note/s" not in res.stderr and "\r" not in res.stderr


def test_report_draws_a_bar_over_its_pictures(tmp_path):
    status, shown = _on_terminal(["play", str(TWINKLE), "-o", "t.csv", "--report", "rep"],
                                 tmp_path)
    assert status == 0
    assert "picture" in shown and "/6 [" in shown  # 6 plots of a play
    assert len(list((tmp_path / "rep").glob("*.png"))) == 6


def test_batch_draws_a_bar_over_its_songs(tmp_path):
    songs = tmp_path / "songs"
    songs.mkdir()
    for name in ("twinkle.mid", "scale.mid"):
        shutil.copy(ROOT / "songs" / name, songs / name)
    status, shown = _on_terminal(["batch", "songs", "out", "--workers", "1"], tmp_path)
    assert status == 0
    assert "song" in shown and "/2 [" in shown
    assert "twinkle.mid: 14/14 played" in shown  # the per-song lines above the bar


def test_json_output_has_no_bar(tmp_path):
    status, shown = _on_terminal(["play", str(TWINKLE), "-o", "t.csv", "--json"], tmp_path)
    assert status == 0
    assert "note/s" not in shown

"""Output goes where the user named it (issue 14): into the path itself, readable while
it is written; a FIFO, a device or a symlink's target is written, never replaced; a
closed pipe ends quietly; SIGTERM and SIGHUP stop a run as SIGINT does."""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import cli
from planner.output import write_file
from planner.trajfile import read_trajectory

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
TWINKLE = ROOT / "songs" / "twinkle.mid"
LONG_SONG = ROOT / "songs" / "fur_elise.mid"


def _cli(*argv, **kw) -> subprocess.Popen:
    return subprocess.Popen([PY, str(ROOT / "cli.py"), *map(str, argv)], **kw)


def test_fifo_is_written_and_its_reader_gets_every_row(tmp_path):
    fifo = tmp_path / "traj.fifo"
    os.mkfifo(fifo)
    got: list[str] = []
    def read() -> None:
        with open(fifo, encoding="utf-8") as f:
            got.extend(f)

    reader = threading.Thread(target=read)
    reader.start()
    p = _cli("play", TWINKLE, "-o", fifo, stderr=subprocess.PIPE, text=True)
    _, err = p.communicate(timeout=300)
    reader.join(timeout=60)
    assert p.returncode == 0, err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode), "the FIFO was replaced"
    end = json.loads(got[-1][2:])
    assert end["end"] is True and end["rows"] == len(got) - 3 > 100
    assert os.listdir(tmp_path) == ["traj.fifo"]


def test_symlink_is_followed_and_stays_a_link(tmp_path, capsys):
    target = tmp_path / "real.csv"
    target.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    assert cli.main(["play", str(TWINKLE), "-o", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert read_trajectory(str(target)).complete
    urdf_link = tmp_path / "hand.urdf"
    urdf_link.symlink_to(tmp_path / "hand_target.urdf")  # dangling: created through it
    assert cli.main(["hand", "--urdf", str(urdf_link)]) == 0
    assert urdf_link.is_symlink() and (tmp_path / "hand_target.urdf").read_text().startswith("<")
    assert sorted(os.listdir(tmp_path)) == ["hand.urdf", "hand_target.urdf", "link.csv",
                                            "real.csv"]


def test_character_device_stays_a_device(tmp_path, capsys):
    dev = tmp_path / "null"
    try:
        os.mknod(dev, stat.S_IFCHR | 0o666, os.makedev(1, 3))  # the null device's numbers
    except PermissionError:
        pytest.skip("mknod needs root (CI runs as root)")
    assert cli.main(["catch", "--angle", "30", "--dist", "1.5", "-o", str(dev)]) == 0
    assert cli.main(["hand", "--urdf", str(dev)]) == 0
    assert cli.main(["play", str(TWINKLE), "-o", str(dev)]) == 0
    assert stat.S_ISCHR(os.lstat(dev).st_mode), "the device was replaced by a file"
    assert os.listdir(tmp_path) == ["null"]


def test_write_file_of_a_regular_file_is_complete_or_absent(tmp_path):
    out = tmp_path / "a.txt"
    write_file(out, "one")
    write_file(out, b"two")
    assert out.read_text() == "two" and os.listdir(tmp_path) == ["a.txt"]


def test_a_reader_tailing_the_file_sees_rows_before_the_plan_ends(tmp_path, monkeypatch, capsys):
    """The rows are in the named file while the song is planned (not in a hidden one)."""
    from planner.play.motion import Motion

    real = Motion.place
    seen: list[int] = []

    def timed(self, item):
        if out.exists():
            text = out.read_text()
            seen.append(-1 if '"end": true' in text else text.count("\n") - 2)
        return real(self, item)

    out = tmp_path / "o.csv"
    monkeypatch.setattr(Motion, "place", timed)
    assert cli.main(["play", str(LONG_SONG), "-o", str(out)]) == 0
    assert -1 not in seen and max(seen) > 100, seen
    assert read_trajectory(str(out)).complete


def _wait_for_rows(path: Path, n: int, p: subprocess.Popen, timeout_s: float = 120) -> None:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s and p.poll() is None:
        if path.exists() and path.read_text().count("\n") > n:
            return
        time.sleep(0.01)
    pytest.fail("no rows appeared before the plan ended")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
# (a song of 15 minutes: it is still being planned when the signal comes, however fast)
def test_signal_stops_cleanly_and_leaves_a_visibly_incomplete_file(tmp_path, sig):
    long_song = tmp_path / "long.mid"
    from planner.music.midi import Note, write_notes_midi

    write_notes_midi([Note(60 + (k % 5) * 2, 0.3 * k, 0.3 * k + 0.25, 80) for k in range(3000)],
                     long_song)
    out = tmp_path / "o.csv"
    # (SIGINT as a terminal leaves it: a shell starts a background job, a suite run with
    # `&` included, with SIGINT ignored, and Python then keeps ignoring it, as it should)
    p = _cli("play", long_song, "-o", out, stderr=subprocess.PIPE, text=True,
             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    _wait_for_rows(out, 20, p)
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 128 + sig, err
    assert err == f"interrupted ({signal.Signals(sig).name})\n"
    assert sorted(os.listdir(tmp_path)) == ["long.mid", "o.csv"]  # nothing hidden
    text = out.read_text()
    assert '"end"' not in text and text.count("\n") > 20
    tr = read_trajectory(str(out), allow_incomplete=True)
    assert not tr.complete


@pytest.mark.parametrize("argv", [
    ["play", str(TWINKLE), "-o", "-"],
    ["hand", "--urdf", "-"],
    ["hand"],
    ["catch", "--angle", "30", "--dist", "1.5", "-o", "-"],
], ids=lambda a: " ".join(a[:1] + a[-2:]))
def test_a_closed_pipe_ends_quietly(argv):
    p = _cli(*argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.readline()
    p.stdout.close()  # what `| head -1` does
    err = p.stderr.read().decode()
    p.wait(timeout=300)
    assert p.returncode in (0, 141), err  # 0: it had written everything before the close
    assert "Traceback" not in err and "Broken pipe" not in err and "Exception" not in err


def test_check_into_a_closed_pipe_exits_141(tmp_path):
    out = tmp_path / "t.csv"
    assert subprocess.run([PY, str(ROOT / "cli.py"), "play", str(TWINKLE), "-o", str(out)],
                          check=False, capture_output=True).returncode == 0
    for _ in range(3):
        p = _cli("check", out, TWINKLE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        time.sleep(0.05)
        p.stdout.close()  # closed before the summary is printed
        err = p.stderr.read().decode()
        p.wait(timeout=300)
        assert p.returncode == 141 and err == "", (p.returncode, err)


def test_a_new_paths_probe_leaves_nothing_and_steps_over_a_leftover(tmp_path):
    """``check_file_target`` of a path not yet there writes a probe file beside it and
    removes it (made exclusively, named by the process, without ``tempfile``); a leftover
    of an earlier probe of the same name is stepped over and left as it was; a folder
    that cannot be written is refused."""
    from planner.errors import InputError
    from planner.output import check_file_target

    leftover = tmp_path / f".probe.{os.getpid()}.0.part"
    leftover.write_text("earlier")
    check_file_target(str(tmp_path / "new.csv"), "output")
    assert sorted(p.name for p in tmp_path.iterdir()) == [leftover.name]
    assert leftover.read_text() == "earlier"
    shut = tmp_path / "shut"
    shut.mkdir()
    shut.chmod(0o500)
    try:
        if os.access(shut, os.W_OK):  # (root writes anyway: nothing to refuse)
            check_file_target(str(shut / "new.csv"), "output")
            assert list(shut.iterdir()) == []
        else:
            with pytest.raises(InputError, match="cannot write"):
                check_file_target(str(shut / "new.csv"), "output")
    finally:
        shut.chmod(0o700)

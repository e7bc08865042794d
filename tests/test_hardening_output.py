"""Hardening (the harness and its contract: tests/hardening.py), (4) output never
lies: unwritable paths, interrupts, a full disk, the file mode, stdout; and (6)
determinism: the same song gives the same bytes in any directory, in-process or
not."""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import tempfile
from pathlib import Path

import pytest

from planner.errors import InputError
from planner.trajfile import read_trajectory
from tests.hardening import (
    ROOT,
    SCALE,
    SUMMARY,
    assert_input_refused,
    one_line,
    part_files,
    run_cli,
    run_sub,
)
from tests.midibytes import events_track, header

# ====================================================================== 4. output never lies


def _unwritable_paths(tmp_path: Path) -> list[Path]:
    paths = [tmp_path / "no" / "such" / "dir" / "o.csv", tmp_path / "afile.txt" / "o.csv"]
    (tmp_path / "afile.txt").write_text("x")
    if os.path.isdir("/proc/self"):  # read-only even for root
        paths.append(Path("/proc/self/o.csv"))
    if os.geteuid() != 0:  # root ignores permissions
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        paths.append(ro / "o.csv")
    return paths


def test_unwritable_output_path(capsys, tmp_path):
    for out in _unwritable_paths(tmp_path):
        rc, o, err = run_cli(capsys, "play", SCALE, "-o", out)
        assert rc in (1, 2), (out, rc, err)
        one_line(err)
        assert str(out) in err and o == ""
        assert not out.exists()


def test_output_path_that_is_a_directory_or_empty(capsys, tmp_path):
    (tmp_path / "adir").mkdir()
    for out in (tmp_path / "adir", ""):
        rc, o, err = run_cli(capsys, "play", SCALE, "-o", out)
        assert_input_refused(rc, err)
        assert o == ""
        assert os.listdir(tmp_path / "adir") == [] and part_files(tmp_path) == []
        assert part_files(".") == []


def test_unwritable_urdf_and_played_paths(capsys, planned, tmp_path):
    for out in _unwritable_paths(tmp_path):
        rc, _, err = run_cli(capsys, "hand", "--urdf", out)
        assert_input_refused(rc, err, None)
        rc, _, err = run_cli(capsys, "check", planned, "--played", out)
        assert rc in (1, 2)
        one_line(err)


@pytest.mark.parametrize("dest", ["file", "stdout"])
def test_interrupt_during_planning_leaves_an_incomplete_file(capsys, monkeypatch, tmp_path, dest):
    """The rows streamed into the named file stay there without the end marker (what
    says a file is complete); nothing hidden is left beside it."""
    from planner.play.motion import Motion

    real = Motion.place
    calls = {"n": 0, "rows_before": None}
    out = tmp_path / "o.csv"

    def interrupted(self, item):
        calls["n"] += 1
        if calls["n"] == 40:
            calls["rows_before"] = out.read_text().count("\n") if out.exists() else 0
            raise KeyboardInterrupt
        return real(self, item)

    monkeypatch.setattr(Motion, "place", interrupted)
    song = ROOT / "songs" / "ode_to_joy.mid"
    rc, o, err = run_cli(capsys, "play", song, "-o", out if dest == "file" else "-")
    assert calls["n"] == 40, "the interrupt never fired: pick a longer song"
    assert rc == 130 and err == "interrupted (SIGINT)\n"
    assert part_files(tmp_path) == []
    if dest == "file":
        assert calls["rows_before"] > 2, "rows had been streamed before the interrupt"
        text = out.read_text()
        assert '"end"' not in text and text.count("\n") >= calls["rows_before"]
        with pytest.raises(InputError, match="incomplete"):
            read_trajectory(str(out))
    else:  # stdout: rows went out, the end marker (the completeness signal) did not
        assert not out.exists()
        assert o.count("\n") > 2 and '"end"' not in o


class _FullDisk:
    """A file object whose write (or flush, or close) fails with ENOSPC once ``budget``
    characters have been written."""

    def __init__(self, f, budget: int, where: str) -> None:
        self._f, self.budget, self.where = f, budget, where

    def _fail(self):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def write(self, s):
        self.budget -= len(s)
        if self.where == "write" and self.budget < 0:
            self._fail()
        return self._f.write(s)

    def flush(self):
        if self.where == "flush" and self.budget < 0:
            self._fail()
        return self._f.flush()

    def close(self):
        if self.where == "close":
            self._f.close()
            self._fail()
        return self._f.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __getattr__(self, name):
        return getattr(self._f, name)


def _fill_disk(monkeypatch, budget: int, where: str, directory: Path) -> None:
    """Every temporary ``*.part`` file created in ``directory`` (the atomic writers') and
    every file opened there for binary writing gets a full disk after ``budget`` chars."""
    real_mkstemp, real_fdopen, real_open = tempfile.mkstemp, os.fdopen, open
    ours: set[int] = set()

    def mkstemp(*a, **kw):
        fd, name = real_mkstemp(*a, **kw)
        if name.endswith(".part") and Path(name).parent == directory:
            ours.add(fd)
        return fd, name

    def fdopen(fd, *a, **kw):
        f = real_fdopen(fd, *a, **kw)
        return _FullDisk(f, budget, where) if fd in ours else f

    def open_(file, mode="r", *a, **kw):
        f = real_open(file, mode, *a, **kw)
        if isinstance(file, (str, os.PathLike)) and "w" in mode and \
                Path(file).parent == directory:
            return _FullDisk(f, budget, where)
        return f

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    monkeypatch.setattr(os, "fdopen", fdopen)
    import builtins

    monkeypatch.setattr(builtins, "open", open_)


@pytest.mark.parametrize("where, budget", [("write", 0), ("write", 3000), ("write", 60_000),
                                           ("flush", 3000), ("close", 0)])
def test_full_disk(capsys, monkeypatch, tmp_path, where, budget):
    _fill_disk(monkeypatch, budget, where, tmp_path)
    out = tmp_path / "o.csv"
    rc, _, err = run_cli(capsys, "play", SCALE, "-o", out)
    monkeypatch.undo()
    assert rc in (1, 2), (rc, err)
    one_line(err)
    assert "No space left on device" in err and str(out) in err
    assert part_files(tmp_path) == []
    # what reached the disk stays, visibly incomplete: no end marker (a close that fails
    # comes after the end marker was written and flushed: the file holds the whole plan)
    assert ('"end"' in out.read_text()) == (where == "close")


@pytest.mark.parametrize("where", ["write", "close"])
def test_full_disk_while_writing_played_midi(capsys, monkeypatch, planned, tmp_path, where):
    """``check --played OUT.mid``: a full disk leaves no truncated MIDI file behind."""
    _fill_disk(monkeypatch, 20, where, tmp_path)
    rc, _, err = run_cli(capsys, "check", planned, "--played", tmp_path / "played.mid")
    monkeypatch.undo()
    assert rc in (1, 2), (rc, err)
    one_line(err)
    assert "No space left on device" in err
    assert os.listdir(tmp_path) == [], "a truncated MIDI file was left behind"


def test_full_temporary_directory_during_planning(capsys, monkeypatch, tmp_path):
    real = tempfile.mkstemp

    def mkstemp(*a, **kw):
        if kw.get("suffix") == ".urdf":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(*a, **kw)

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    out = tmp_path / "o.csv"
    rc, _, err = run_cli(capsys, "play", SCALE, "-o", out)
    monkeypatch.undo()
    # planner/ik.py once wrote the URDF to a temporary file (and died with a traceback
    # when it could not); it now hands placo the URDF text
    assert rc == 0, err
    assert read_trajectory(str(out)).complete


def test_output_files_are_readable_like_any_other_file(capsys, tmp_path):
    """The atomic writer's temporary file is 0600; the published file must follow the umask."""
    old = os.umask(0o022)
    try:
        for argv, path in ((["play", SCALE, "-o", tmp_path / "o.csv"], tmp_path / "o.csv"),
                           (["hand", "--urdf", tmp_path / "h.urdf"], tmp_path / "h.urdf")):
            assert run_cli(capsys, *argv)[0] == 0
            assert (path.stat().st_mode & 0o777) == 0o644, oct(path.stat().st_mode)
    finally:
        os.umask(old)


def test_stdout_output_is_complete(capsys):
    rc, out, err = run_cli(capsys, "play", SCALE, "-o", "-")
    assert rc == 0
    lines = out.split("\n")[:-1]
    end = json.loads(lines[-1][2:])
    assert (end["end"], end["rows"], end["notes"], end["played"]) == (True, len(lines) - 3, 15, 15)
    assert end["left_out"] == []
    m = SUMMARY.search(err)
    assert int(m["rows"]) == len(lines) - 3


# minimal example found by test_zero_length_and_overlapping_notes (hypothesis, shrunk):
# C4 struck five times 30 ms apart at velocity 1 over a held E4
POLISH_EVENTS = ([(0, "on", 60, 1, 0)] * 4 + [(0, "on", 64, 1, 0)] + [(29, "on", 60, 1, 0)] * 5
                 + [(1, "on", 60, 1, 0)])


def test_stdout_stream_is_only_the_trajectory(capsys, tmp_path):
    song = tmp_path / "s.mid"
    song.write_bytes(header(1, 1) + events_track(POLISH_EVENTS))
    rc, out, err = run_cli(capsys, "play", song, "-o", "-")
    assert rc == 0, err
    (tmp_path / "stdout.csv").write_text(out)
    tr = read_trajectory(str(tmp_path / "stdout.csv"))
    assert int(SUMMARY.search(err)["rows"]) == len(tr.t_s)


# ====================================================================== 6. determinism


def test_same_song_same_bytes_in_different_directories(tmp_path):
    song = tmp_path / "song" / "twinkle.mid"
    song.parent.mkdir()
    shutil.copy(ROOT / "songs" / "twinkle.mid", song)
    outs = []
    for k in range(2):
        cwd = tmp_path / f"run{k}" / ("deeper" * k)
        cwd.mkdir(parents=True)
        r = run_sub("play", song, "-o", cwd / "out.csv", cwd=cwd, timeout=120)
        assert r.returncode == 0, r.stderr
        outs.append((cwd / "out.csv").read_bytes())
    assert outs[0] == outs[1]
    meta_line = outs[0].split(b"\n", 1)[0].decode()
    meta = json.loads(meta_line[2:])
    assert meta["song"] == "twinkle.mid"
    for s in re.findall(r'"((?:[^"\\]|\\.)*)"', meta_line):
        assert not s.startswith("/") and str(tmp_path) not in s, s
    # no time of day or date anywhere in the metadata
    assert not re.search(r"\d{1,2}:\d{2}|\d{4}-\d{2}-\d{2}", meta_line), meta_line
    assert set(meta) == {"format", "version", "task", "hand", "urdf_sha256", "T_world_root",
                         "rate_hz", "song", "notes", "track", "channel", "transpose",
                         "song_start_s"}


def test_in_process_run_gives_the_same_bytes_as_a_subprocess(capsys, tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert run_cli(capsys, "play", SCALE, "-o", a)[0] == 0
    r = run_sub("play", SCALE, "-o", b, cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    assert a.read_bytes() == b.read_bytes()

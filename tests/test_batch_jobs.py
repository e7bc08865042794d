"""``batch`` as a job runner (issue 32, item 4): a signal stops the workers and writes
the summary of what is done, with the signal's exit status; no worker outlives the main
process; a failing song is recorded with its one-line reason and the batch goes on; the
summary's names are reserved; what is not a MIDI file is skipped with a line. Every
run is a subprocess in its own session in a tmp dir; waits are generous, never timed."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from planner.batch import batch_plan
from planner.batchpool import Failed, WorkerPool

ROOT = Path(__file__).resolve().parents[1]
WAIT_S = 300.0  # generous: a shared CI machine


def _songs(d: Path, n: int) -> Path:
    d.mkdir()
    for i in range(n):
        (d / f"song{i:02d}.mid").write_bytes((ROOT / "songs" / "fur_elise.mid").read_bytes())
    return d


def _wait(pred, what: str) -> None:
    end = time.monotonic() + WAIT_S
    while not pred():
        assert time.monotonic() < end, f"gave up waiting: {what}"
        time.sleep(0.1)


def _group_gone(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return True
    return False


def _start(songs: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, str(ROOT / "cli.py"), "batch", str(songs), str(out),
                             "--workers", "2"], cwd=out.parent, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=_default_sigint)  # noqa: PLW1509 (no threads here)


def _default_sigint() -> None:
    # (a test run from a background job inherits SIGINT ignored, and Python keeps it so)
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP],
                         ids=lambda s: s.name)
def test_a_signal_stops_the_batch_and_writes_what_is_done(tmp_path, sig):
    songs, out = _songs(tmp_path / "songs", 12), tmp_path / "out"
    p = _start(songs, out)
    _wait(lambda: any(out.glob("*.json")), "a first song done")
    os.kill(p.pid, sig)
    _, err = p.communicate(timeout=WAIT_S)
    assert p.returncode == 128 + sig, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1] == f"interrupted ({sig.name})"
    rows = list(csv.DictReader((out / "summary.csv").open()))
    records = sorted(r.stem for r in out.glob("song*.json"))
    assert 1 <= len(rows) < 12  # (the queue was not planned to its end)
    assert sorted(Path(r["song"]).stem for r in rows) == records
    _wait(lambda: _group_gone(p.pid), "the workers gone")


def test_no_worker_outlives_a_killed_batch(tmp_path):
    songs, out = _songs(tmp_path / "songs", 12), tmp_path / "out"
    p = _start(songs, out)
    _wait(lambda: any(out.glob("*.csv")), "a first trajectory started")
    os.kill(p.pid, signal.SIGKILL)
    p.communicate(timeout=WAIT_S)
    _wait(lambda: _group_gone(p.pid), "the workers gone after their parent's SIGKILL")


def _raise_on_two(x: int) -> int:
    if x == 2:
        raise ValueError("two\nsecond line")
    if x == 3:
        os._exit(7)  # (a worker dying under its task)
    return x * 10


def test_a_task_that_raises_or_kills_its_worker_fails_alone():
    with WorkerPool(_raise_on_two, 2) as pool:
        got = dict(pool.run([1, 2, 3, 4, 5]))
    assert got[1] == 10 and got[4] == 40 and got[5] == 50
    assert got[2] == Failed("ValueError: two")
    assert isinstance(got[3], Failed) and "worker died (exit status 7)" in got[3].reason


def test_a_song_that_crashes_the_planner_is_failed_and_the_batch_goes_on(tmp_path,
                                                                         monkeypatch):
    import planner.play

    songs = _songs(tmp_path / "songs", 2)

    def boom(*a, **k):
        raise AttributeError("'NoneType' object has no attribute 'high'")

    monkeypatch.setattr(planner.play, "plan_song", boom)
    s = batch_plan(songs, tmp_path / "out", workers=1)
    assert [r.error for r in s.results] == [("AttributeError: 'NoneType' object has no "
                                             "attribute 'high'")] * 2
    assert (tmp_path / "out" / "summary.csv").exists()


def test_the_summary_names_are_reserved(tmp_path):
    songs = tmp_path / "songs"
    songs.mkdir()
    for n in ("summary", "twinkle"):
        (songs / f"{n}.mid").write_bytes((ROOT / "songs" / "twinkle.mid").read_bytes())
    s = batch_plan(songs, tmp_path / "out", workers=1)
    by = {r.song: r for r in s.results}
    assert "summary.csv" in by["summary.mid"].error and not by["summary.mid"].check_ok
    assert by["twinkle.mid"].check_ok
    d = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert [r["song"] for r in d["songs"]] == ["summary.mid", "twinkle.mid"]
    assert not (tmp_path / "out" / "summary.mid.csv").exists()


def test_entries_that_are_not_midi_files_are_skipped_with_a_line(tmp_path):
    songs = tmp_path / "songs"
    songs.mkdir()
    (songs / "twinkle.mid").write_bytes((ROOT / "songs" / "twinkle.mid").read_bytes())
    (songs / "dir.mid").mkdir()
    (songs / "notes.txt").write_text("x")
    (songs / "fake.mid").write_text("not midi")
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "batch", str(songs),
                        str(tmp_path / "out")], cwd=tmp_path, capture_output=True, text=True,
                       timeout=WAIT_S, check=False)
    assert r.returncode == 0, r.stderr
    for line in ("dir.mid: skipped (not a regular file (a folder?))",
                 "notes.txt: skipped (not a .mid file)",
                 "fake.mid: skipped (not a MIDI file (no MThd header))"):
        assert line in r.stderr.splitlines(), r.stderr
    assert "1 songs: 1 planned" in r.stderr

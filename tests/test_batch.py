"""Batch planning (planner/batch.py): parallel equals serial, a second run skips what is
done, a changed or damaged song is planned again, bad input is refused."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import asdict, replace
from pathlib import Path

import pytest

from planner.batch import batch_plan, format_song_line
from planner.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
SONGS = ("twinkle", "scale", "leaps")


@pytest.fixture()
def songs(tmp_path):
    d = tmp_path / "songs"
    d.mkdir()
    for n in SONGS:
        (d / f"{n}.mid").write_bytes((ROOT / "songs" / f"{n}.mid").read_bytes())
    return d


def _outcome(summary) -> list[dict]:
    return [{k: v for k, v in asdict(r).items() if k not in ("planning_s", "realtime_factor")}
            for r in summary.results]


def test_two_workers_give_what_one_gives_and_a_second_run_skips_all(songs, tmp_path):
    serial = batch_plan(songs, tmp_path / "one", workers=1)
    parallel = batch_plan(songs, tmp_path / "two", workers=2)
    assert _outcome(serial) == _outcome(parallel)
    assert [r.song for r in serial.results] == sorted(f"{n}.mid" for n in SONGS)
    assert all(r.check_ok and r.played == r.notes and not r.error for r in serial.results)
    for n in SONGS:  # same bytes from either
        assert (tmp_path / "one" / f"{n}.csv").read_bytes() == \
            (tmp_path / "two" / f"{n}.csv").read_bytes()
    again = batch_plan(songs, tmp_path / "two", workers=2)
    assert again.skipped == 3 and again.planned == 0
    assert _outcome(again) == [{**o, "skipped": True} for o in _outcome(parallel)]
    table = (tmp_path / "two" / "summary.csv").read_text().splitlines()
    assert table[0].startswith("song,notes,played") and len(table) == 4
    assert len(json.loads((tmp_path / "two" / "summary.json").read_text())["songs"]) == 3


def test_a_changed_or_damaged_song_is_planned_again(songs, tmp_path):
    out = tmp_path / "out"
    batch_plan(songs, out, workers=1)
    (songs / "scale.mid").write_bytes((ROOT / "songs" / "fur_elise.mid").read_bytes())
    csv = (out / "leaps.csv").read_text()
    (out / "leaps.csv").write_text(csv[: len(csv) // 2])  # cut: no end marker
    again = batch_plan(songs, out, workers=1)
    by = {r.song: r for r in again.results}
    assert by["twinkle.mid"].skipped
    assert not by["scale.mid"].skipped and by["scale.mid"].notes > 15
    assert not by["leaps.mid"].skipped and by["leaps.mid"].check_ok


def test_a_bad_song_is_recorded_and_the_others_are_planned(songs, tmp_path):
    (songs / "bad.mid").write_bytes(b"MThd\x00\x00\x00\x06\x00\x01\x00")
    r = subprocess.run([sys.executable, "-m", "planner.cli", "batch", str(songs),
                        str(tmp_path / "out"), "--json"], capture_output=True, text=True,
                       check=False, timeout=600)
    assert r.returncode == 1, r.stderr
    d = json.loads(r.stdout)
    assert d["failed"] == 1 and d["planned"] == 3
    bad = next(s for s in d["songs"] if s["song"] == "bad.mid")
    assert bad["error"] and "\n" not in bad["error"]


@pytest.mark.parametrize("case", ["no_folder", "empty", "workers"])
def test_bad_batch_input_is_refused(tmp_path, case):
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError):
        if case == "no_folder":
            batch_plan(tmp_path / "none", tmp_path / "out")
        elif case == "empty":
            batch_plan(tmp_path / "empty", tmp_path / "out")
        else:
            batch_plan(ROOT / "songs", tmp_path / "out", workers=0)


def test_a_cluster_address_without_ray_is_refused(songs, tmp_path):
    try:
        import ray  # noqa: F401
    except ImportError:
        with pytest.raises(InputError, match="Ray"):
            batch_plan(songs, tmp_path / "out", address="local")
    else:
        s = batch_plan(songs, tmp_path / "out", address="local")
        assert s.planned == 3


def test_a_cluster_that_cannot_be_joined_is_one_clear_error(songs, tmp_path, monkeypatch):
    """Ray's ConnectionError (no cluster there, or a token it does not accept) becomes an
    InputError naming the address (exit 2, one line), not a traceback."""
    import types

    def init(**kwargs):
        raise ConnectionError(f"Failed to connect to Ray cluster at {kwargs['address']}")

    monkeypatch.setitem(sys.modules, "ray", types.SimpleNamespace(init=init))
    with pytest.raises(InputError, match=r"--address 10\.0\.0\.9:6379: cannot join the Ray "
                       r"cluster \(Failed to connect to Ray cluster at 10\.0\.0\.9:6379\)"):
        batch_plan(songs, tmp_path / "out", address="10.0.0.9:6379")
    assert not (tmp_path / "out" / "summary.json").exists()


def test_physics_replays_every_plan_and_records_its_verdict(tmp_path):
    """``batch --physics``: each plan replayed in MuJoCo (full contact); its physics F1,
    wrong keys and longest motor saturation in the record and the summary; a record
    made without physics is planned again for a physics batch."""
    d = tmp_path / "songs"
    d.mkdir()
    (d / "twinkle.mid").write_bytes((ROOT / "songs" / "twinkle.mid").read_bytes())
    plain = batch_plan(d, tmp_path / "out", workers=1)
    assert plain.results[0].physics_f1 is None
    phys = batch_plan(d, tmp_path / "out", workers=1, physics=True)
    r = phys.results[0]
    assert not r.skipped and r.physics_f1 is not None and 0.0 <= r.physics_f1 <= 1.0
    assert r.physics_wrong_keys >= 0 and r.physics_saturated_ms >= 0.0
    assert phys.ok == (r.check_ok and r.physics_ok)
    header = (tmp_path / "out" / "summary.csv").read_text().splitlines()[0].split(",")
    assert header[-6:] == ["physics_f1", "physics_wrong_keys", "physics_saturated_ms",
                           "physics_ok", "physics_saturated_motor", "physics_error"]
    rec = json.loads((tmp_path / "out" / "twinkle.json").read_text())
    assert rec["physics_f1"] == r.physics_f1
    assert (r.physics_saturated_motor != "") == (r.physics_saturated_ms > 0)
    # the totals: in the closing lines, --json and summary.json
    ph = phys.physics
    assert (ph.replayed, ph.failed, ph.mean_f1, ph.min_f1, ph.wrong_keys) == (
        1, 0, r.physics_f1, r.physics_f1, r.physics_wrong_keys)
    assert ph.saturated_ms == r.physics_saturated_ms and ph.ok == int(r.physics_ok)
    assert f"physics: 1 replayed, {ph.ok} OK; F1 mean {r.physics_f1:.4f}" in phys.format(
        tmp_path / "out")
    assert phys.to_dict()["physics"]["wrong_keys"] == r.physics_wrong_keys
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["physics"][
        "mean_f1"] == r.physics_f1
    assert plain.physics is None and plain.to_dict()["physics"] is None
    assert "\nphysics:" not in plain.format(tmp_path / "out")
    again = batch_plan(d, tmp_path / "out", workers=1, physics=True)
    assert again.results[0].skipped and again.results[0].physics_f1 == r.physics_f1
    assert again.physics == ph  # (the totals of the records read back)


def test_physics_totals_of_several_songs():
    """The batch's physics totals: the mean and the lowest F1 with its song, the wrong
    keys summed, the longest saturation with its song and motor; songs without a replay
    (or without a plan) are not counted."""
    from planner.batch import SongResult, physics_totals

    def res(song, f1, wrong, sat_ms, motor, ok=True, error=""):
        return SongResult(song, 10, 10, 0, 1.0, True, 1.0, 10.0, f"{song}.csv", error,
                          physics_f1=f1, physics_wrong_keys=wrong, physics_saturated_ms=sat_ms,
                          physics_ok=ok, physics_saturated_motor=motor)

    rs = (res("a.mid", 0.9, 1, 0.0, ""), res("b.mid", 0.7, 2, 30.0, "motor.rail", ok=False),
          res("c.mid", None, None, None, None), res("d.mid", 0.8, 0, 10.0, "motor.reach"),
          res("e.mid", 0.1, 9, 90.0, "motor.x", error="planning failed"))
    t = physics_totals(rs)
    assert (t.replayed, t.ok, t.failed, t.min_f1, t.min_f1_song, t.wrong_keys) == (
        3, 2, 0, 0.7, "b.mid", 3)
    assert abs(t.mean_f1 - 0.8) < 1e-12
    assert (t.saturated_ms, t.saturated_song, t.saturated_motor) == (30.0, "b.mid", "motor.rail")
    assert "longest motor saturation 30 ms (motor.rail, b.mid)" in t.format()
    # a replay that failed to run: counted, not OK, no F1 of its own
    broken = replace(rs[2], physics_ok=False, physics_error="RuntimeError: boom")
    t = physics_totals((*rs, broken))
    assert (t.replayed, t.ok, t.failed, t.min_f1) == (4, 2, 1, 0.7)
    assert "4 replayed (1 failed to run), 2 OK" in t.format()
    alone = physics_totals((broken,))
    assert (alone.replayed, alone.failed, alone.mean_f1, alone.saturated_ms) == (1, 1, None, 0.0)
    assert "no F1" in alone.format()
    assert physics_totals(rs[2:3]) is None


def test_a_replay_that_fails_keeps_the_plan_and_fails_the_physics(tmp_path, monkeypatch):
    """A physics replay that raises fails that song's physics with its one-line reason;
    the plan and its check stand (not a failed song), the batch is not OK, and the next
    physics batch replays it again."""
    from planner import batch

    def boom(traj, song):
        raise RuntimeError("boom\nsecond line")

    d = tmp_path / "songs"
    d.mkdir()
    (d / "twinkle.mid").write_bytes((ROOT / "songs" / "twinkle.mid").read_bytes())
    monkeypatch.setattr(batch, "physics_verdict", boom)
    s = batch_plan(d, tmp_path / "out", workers=1, physics=True)
    r = s.results[0]
    assert not r.error and r.played > 0 and r.check_ok
    assert (r.physics_ok, r.physics_f1, r.physics_error) == (False, None, "RuntimeError: boom")
    assert not s.ok and s.failed == 0 and s.physics.failed == 1
    assert format_song_line(r).endswith("; physics FAILED: RuntimeError: boom")
    monkeypatch.undo()
    again = batch_plan(d, tmp_path / "out", workers=1, physics=True)
    r2 = again.results[0]
    assert not r2.skipped and r2.physics_f1 is not None and not r2.physics_error


def test_an_interrupt_after_a_record_is_written_keeps_it_in_the_summary(songs, tmp_path,
                                                                         monkeypatch):
    """A worker writes a song's record before the batch hears of it; a signal between the
    two still leaves that song in the summary (as planned by this run), like its record."""
    import csv

    from planner import batch

    real = batch.plan_one

    def then_interrupted(*args):
        real(*args)
        raise KeyboardInterrupt

    monkeypatch.setattr(batch, "plan_one", then_interrupted)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        batch_plan(songs, out, workers=1)
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert [r["song"] for r in rows] == ["leaps.mid"]  # (the first song by name)
    assert sorted(p.name for p in out.glob("*.json")) == ["leaps.json", "summary.json"]
    rec = json.loads((out / "leaps.json").read_text())
    assert rows[0]["check_ok"] == "True" and float(rows[0]["frame_f1"]) == rec["frame_f1"]

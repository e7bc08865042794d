"""Pictures of a two-hand plan (``planner.report.pair``): each hand's one-hand pictures,
judged against the notes its ``by_hand`` claim gives it; ``check --report/--html`` of a
two-hand file."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from planner.hand.model import load_hand
from planner.music.midi import Note, load_song, write_notes_midi
from planner.play.twohands import PairPlanner, plan_two_hands
from planner.report.pair import hand_reports, side_path

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def pair_file(tmp_path_factory) -> tuple[Path, Path, object]:
    d = tmp_path_factory.mktemp("pair")
    notes = [Note(48 + 2 * (i % 4), 0.5 + 0.5 * i, 0.9 + 0.5 * i, 80, 1) for i in range(6)]
    notes += [Note(76 - 2 * (i % 3), 0.5 + 0.5 * i, 0.9 + 0.5 * i, 80, 0) for i in range(6)]
    write_notes_midi(notes, d / "two.mid")
    song = load_song(d / "two.mid", every_part=True)
    pp = PairPlanner(load_hand("default-left"), load_hand("default"))
    plan = plan_two_hands(song, pp, str(d / "two.csv"))
    return d / "two.csv", d / "two.mid", plan


def test_each_hand_judged_on_its_own_notes(pair_file) -> None:
    path, mid, plan = pair_file
    got = hand_reports(str(path), str(mid))
    assert [side for side, _ in got] == ["left", "right"]
    for (side, rep), played in zip(got, (plan.played_of("left"), plan.played_of("right"))):
        assert rep.replay is not None and rep.play.notes == len(played) > 0
        assert rep.play.notes_hit == len(played)  # (each claimed note hit by its hand)
        assert rep.hand == ("default-left" if side == "left" else "default")
        assert rep.song is None and rep.trajectory.endswith(f"({side})")


def test_side_path() -> None:
    assert side_path("out/a.html", "left") == "out/a.left.html"
    assert side_path("b", "right") == "b.right.html"


def test_check_cli_draws_both_hands(pair_file, tmp_path) -> None:
    path, mid, _ = pair_file
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "check", str(path), str(mid),
                        "--report", "rep", "--html", "two.html"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=900, check=False)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    for side in ("left", "right"):
        assert (tmp_path / "rep" / side / "play_piano_roll.png").stat().st_size > 0
        assert (tmp_path / f"two.{side}.html").read_text().startswith("<!DOCTYPE html>")
    assert not (tmp_path / "two.html").exists()


def test_play_two_hands_draws_both_hands(pair_file, tmp_path) -> None:
    _, mid, _ = pair_file
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "play", str(mid), "--hands", "2",
                        "-o", "p.csv", "--report", "rep"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=900, check=False)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "report -> rep (left, right)" in r.stderr
    for side in ("left", "right"):
        assert (tmp_path / "rep" / side / "joint_positions.png").stat().st_size > 0

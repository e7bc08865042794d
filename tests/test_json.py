"""``--json`` on every subcommand: one JSON object on stdout, nothing else there, of the
documented shape (README, "Machine-readable output"); exit codes as without it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NUM = (int, float)
OPT_NUM = (int, float, type(None))

PLAY = {"command": str, "song": str, "notes": int, "played": int, "left_out": list,
        "late": list, "wrong_presses": list, "frame_f1": NUM, "rows": int, "duration_s": NUM,
        "trajectory": str, "song_s": NUM, "planning_s": NUM, "first_row_s": NUM,
        "setup_s": NUM, "realtime_factor": OPT_NUM, "hand_positions": int,
        "part": (dict, type(None)), "softer": list}
LEFT_OUT = {"note": int, "onset_s": NUM, "pitch": int, "name": str, "reason": str,
            "detail": str}
CATCH = {"command": str, "feasible": bool, "reasons": list, "reason_kinds": list, "throw": dict,
         "launch_speed_m_s": NUM, "flight_time_s": OPT_NUM, "intercept_t_s": NUM,
         "intercept_point_m": list, "arrival_speed_m_s": NUM, "palm_misalignment_deg": NUM,
         "intercept_error_m": NUM, "move_start_s": NUM, "close_start_s": NUM, "close_s": NUM,
         "grasp_t_s": OPT_NUM, "grasp_fingers": list, "margins_s": dict,
         "min_clearance_before_m": NUM, "stopping": (dict, type(None)),
         "holding": (dict, type(None)), "impact": (dict, type(None)),
         "riding": (dict, type(None)), "uncertainty": (dict, type(None)), "notes": list,
         "rows": int, "rate_hz": NUM, "duration_s": NUM, "trajectory": str,
         "planning_s": NUM, "setup_s": NUM}
HAND = {"command": str, "name": str, "description": str, "side": str, "urdf_sha256": str, "rail": bool,
        "fingers": list, "joints": list, "couplings": list, "actuators": list,
        "play": (dict, type(None))}
JOINT = {"name": str, "lower": NUM, "upper": NUM, "velocity": NUM, "acceleration": NUM,
         "jerk": NUM, "stop_margin": NUM, "unit": str}


def _shaped(obj: dict, schema: dict) -> None:
    assert set(obj) == set(schema), set(obj) ^ set(schema)
    for k, t in schema.items():
        assert isinstance(obj[k], t), (k, obj[k])


def _run(*args, cwd):
    r = subprocess.run([sys.executable, "-m", "planner.cli", *map(str, args)],
                       capture_output=True, text=True, cwd=cwd, check=False, timeout=300)
    return r.returncode, r.stdout, r.stderr


def test_play_json(tmp_path):
    from planner.music.midi import Note, write_notes_midi

    song = tmp_path / "wide.mid"  # a chord too wide for the hand, then a note it plays
    write_notes_midi([Note(p, 0.0, 1.0, 80) for p in (36, 48, 60, 72, 84)]
                     + [Note(64, 1.5, 2.0, 80)], song)
    rc, out, err = _run("play", song, "-o", tmp_path / "w.csv", "--json", cwd=tmp_path)
    assert rc == 0 and err == "", err
    (line,) = out.splitlines()
    d = json.loads(line)
    _shaped(d, PLAY)
    assert d["command"] == "play" and d["notes"] == 6
    assert d["played"] == 6 - len(d["left_out"])
    assert d["left_out"] and all(_shaped(x, LEFT_OUT) is None for x in d["left_out"])
    assert d["trajectory"] == str(tmp_path / "w.csv") and (tmp_path / "w.csv").exists()
    rc, out, _ = _run("play", song, "-o", tmp_path / "w.csv", "--json", "--strict",
                      cwd=tmp_path)
    assert rc == 1 and json.loads(out)["left_out"]  # (--strict: exit 1, as without --json)


def test_catch_json(tmp_path):
    rc, out, err = _run("catch", "--angle", "30", "--dist", "1.5", "-o", tmp_path / "c.csv",
                        "--json", cwd=tmp_path)
    assert rc == 0 and err == "", err
    d = json.loads(out)
    _shaped(d, CATCH)
    assert d["feasible"] is True and d["reasons"] == [] and len(d["intercept_point_m"]) == 3


def test_catch_json_speeds_are_the_summarys(tmp_path):
    """``stopping.relative_speed_m_s`` is the ball's speed relative to the palm when the palm
    meets it, the number the text summary prints ("... m/s relative"; 3.49 m/s on 30 deg /
    1.5 m), not the speed at the stop's worst moment (``worst_relative_speed_m_s``)."""
    import re

    rc, out, _ = _run("catch", "--angle", "30", "--dist", "1.5", "-o", tmp_path / "c.csv",
                      "--json", cwd=tmp_path)
    st = json.loads(out)["stopping"]
    rc2, _, err = _run("catch", "--angle", "30", "--dist", "1.5", "-o", tmp_path / "d.csv",
                       cwd=tmp_path)
    assert rc == rc2 == 0
    palm, rel = map(float, re.search(r"meeting it at ([\d.]+) m/s, ([\d.]+) m/s relative",
                                     err).groups())
    assert f"{st['palm_speed_m_s']:.2f}" == f"{palm:.2f}"
    assert f"{st['relative_speed_m_s']:.2f}" == f"{rel:.2f}" and rel > 1.0
    assert isinstance(st["worst_t_s"], float) and st["worst_relative_speed_m_s"] >= 0.0


def test_hand_json(tmp_path):
    rc, out, _ = _run("hand", "--json", cwd=tmp_path)
    assert rc == 0
    d = json.loads(out)
    _shaped(d, HAND)
    assert d["name"] == "default" and d["rail"] is True and len(d["fingers"]) == 5
    for j in d["joints"]:
        _shaped(j, JOINT)
        assert j["lower"] <= j["upper"]
    rc, out, _ = _run("hand", "--list", "--json", cwd=tmp_path)
    assert rc == 0 and [h["name"] for h in json.loads(out)["hands"]] == ["default", "default-left", "agh", "mk5"]
    rc, out, _ = _run("hand", "--urdf", tmp_path / "h.urdf", "--json", cwd=tmp_path)
    assert rc == 0 and json.loads(out)["urdf"] == str(tmp_path / "h.urdf")


@pytest.mark.parametrize("argv", [["play", str(ROOT / "songs" / "scale.mid"), "-o", "-"],
                                  ["catch", "--angle", "30", "--dist", "1.5", "-o", "-"],
                                  ["hand", "--urdf", "-"]])
def test_json_refuses_stdout_for_the_artefact(tmp_path, argv):
    rc, out, err = _run(*argv, "--json", cwd=tmp_path)
    assert rc == 2 and out == "" and len(err.strip().splitlines()) == 1 and "--json" in err

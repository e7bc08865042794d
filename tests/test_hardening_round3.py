"""Hardening (the harness: tests/hardening.py), round 3 of hostile inputs (issue 32;
the inputs in tests/data/round3/, README there): every one ends in one line and exit
2, or in a plan ``check`` confirms. Damaged trajectories are made afresh from a plan
(the ``planned`` fixture, conftest.py)."""

from __future__ import annotations

import json
import os
import resource
import subprocess
from pathlib import Path

import pytest

from planner.trajfile import read_trajectory
from tests.hardening import (
    LONG,
    PY,
    ROOT,
    SCALE,
    assert_input_refused,
    one_line,
    run_cli,
    run_sub,
)

DATA = ROOT / "tests" / "data"
R3 = DATA / "round3"
TWINKLE = ROOT / "songs" / "twinkle.mid"


# ---------------------------------------------------------------- crashes in play


def test_debussy_menuet_plans_and_checks(capsys, tmp_path):
    """The follow memo once handed a finger riding along no entry at its new rail
    (AttributeError in play/moves.py): the shortest cut of the file that raised it."""
    out = tmp_path / "d.csv"
    rc, _, err = run_cli(capsys, "play", DATA / "debussy_menuet_200_250s.mid", "-o", out)
    assert rc in (0, 1) and "Traceback" not in err, err
    assert read_trajectory(str(out)).complete
    crc, cout, _ = run_cli(capsys, "check", out, DATA / "debussy_menuet_200_250s.mid")
    assert (rc == 0) == (crc == 0), cout  # play exits 0 only with a plan check passes


@pytest.mark.skipif(not LONG, reason="a 4-minute song: long mode (HARDENING_EXAMPLES=1000)")
def test_the_whole_debussy_menuet_plans(capsys, tmp_path):
    out = tmp_path / "d.csv"
    rc, _, err = run_cli(capsys, "play", R3 / "debussy_menuet_tonejs.mid", "-o", out)
    assert rc in (0, 1) and "Traceback" not in err, err
    assert read_trajectory(str(out)).complete


def test_zero_length_notes_are_named_so(capsys, tmp_path):
    out = tmp_path / "z.csv"
    rc, _, err = run_cli(capsys, "play", R3 / "mozart_zero_len.mid", "-o", out)
    assert_input_refused(rc, err, out)
    assert "all 219 notes on channel(s) 0..15" in err and "zero length" in err, err
    assert "notes exist in" not in err


# ---------------------------------------------------------------- hand files

HANDS = {  # file -> the key its one line names
    "hand_zero_speed.toml": "'finger_speed.velocity_cap_rad_s' = 0.0",
    "hand_tiny_speed.toml": "'finger_speed.velocity_cap_rad_s' = 1e-06",
    "hand_huge_speed.toml": "'finger_speed.velocity_cap_rad_s' = 1e+300",
    "hand_neg_mass.toml": "'palm.mass_kg' = -1.0",
}


@pytest.mark.parametrize("name", sorted(HANDS))
@pytest.mark.parametrize("command", ["play", "catch", "hand"])
def test_a_hand_file_out_of_range_is_refused_naming_the_key(capsys, tmp_path, name, command):
    out = tmp_path / "o.csv"
    out.write_text("a good file\n")  # (an existing -o file is never touched on exit 2)
    argv = {"play": ["play", TWINKLE, "-o", out],
            "catch": ["catch", "--angle", "30", "--dist", "1.5", "-o", out],
            "hand": ["hand", "--urdf", tmp_path / "h.urdf"]}[command]
    rc, _, err = run_cli(capsys, *argv, "--hand", R3 / name)
    assert rc == 2, err
    one_line(err)
    assert HANDS[name] in err, err
    assert out.read_text() == "a good file\n"
    assert not (tmp_path / "h.urdf").exists()


# ---------------------------------------------------------------- output paths


def _paths(tmp_path: Path) -> dict[str, Path]:
    (tmp_path / "afile").write_text("x")
    return {"missing_parent": tmp_path / "nodir" / "x.out", "under_a_file": tmp_path / "afile" / "x",
            "proc": Path("/proc/nope/x.out")}


ARTEFACTS = {  # (command, option) -> argv before the option
    ("play", "--html"): lambda t: ["play", TWINKLE, "-o", t / "o.csv"],
    ("play", "--report"): lambda t: ["play", TWINKLE, "-o", t / "o.csv"],
    ("catch", "--html"): lambda t: ["catch", "--angle", "30", "--dist", "1.5", "-o", t / "o.csv"],
    ("catch", "--report"): lambda t: ["catch", "--angle", "30", "--dist", "1.5",
                                      "-o", t / "o.csv"],
    ("check", "--played"): lambda t: ["check", t / "plan.csv", SCALE],
    ("check", "--report"): lambda t: ["check", t / "plan.csv"],
    ("check", "--html"): lambda t: ["check", t / "plan.csv"],
    ("hand", "--urdf"): lambda t: ["hand"],
    ("play", "-o"): lambda t: ["play", TWINKLE],
    ("simulate", "--video"): lambda t: ["simulate", t / "plan.csv"],
    ("simulate", "--html"): lambda t: ["simulate", t / "plan.csv"],
}


@pytest.mark.parametrize("where", ["missing_parent", "under_a_file", "proc"])
@pytest.mark.parametrize("command,option", sorted(ARTEFACTS))
def test_every_output_path_is_checked_before_planning(capsys, planned, tmp_path, command,
                                                      option, where):
    """--report/--html/--urdf/--played/--video follow -o's rules: a path that cannot be
    written is refused in one line before any work, and no folder is ever created."""
    (tmp_path / "plan.csv").write_bytes(planned.read_bytes())
    bad = _paths(tmp_path)[where]
    before = sorted(p.name for p in tmp_path.iterdir())
    rc, out, err = run_cli(capsys, *ARTEFACTS[(command, option)](tmp_path), option, bad)
    assert_input_refused(rc, err)
    assert "planning" not in err and out == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # (no o.csv, no nodir/)


def test_report_into_an_existing_file_is_refused(capsys, tmp_path):
    (tmp_path / "afile").write_text("x")
    rc, _, err = run_cli(capsys, "play", TWINKLE, "-o", tmp_path / "o.csv",
                         "--report", tmp_path / "afile")
    assert_input_refused(rc, err, tmp_path / "o.csv")
    assert "not a folder" in err


# ---------------------------------------------------------------- closed streams, memory


def _closing(fd: int):
    return lambda: os.close(fd)


@pytest.mark.parametrize("argv", [["play", str(TWINKLE), "-o", "-"], ["hand"],
                                  ["hand", "--urdf", "-"]], ids=["play", "hand", "urdf"])
def test_a_closed_stdout_is_one_line_when_the_output_goes_there(tmp_path, argv):
    p = subprocess.run([PY, str(ROOT / "cli.py"), *argv], cwd=tmp_path, capture_output=False,
                       stderr=subprocess.PIPE, text=True, preexec_fn=_closing(1), timeout=300,
                       check=False)
    assert p.returncode == 2, p.stderr
    one_line(p.stderr)
    assert "standard output is closed" in p.stderr


def test_a_closed_stderr_still_writes_the_plan(tmp_path):
    p = subprocess.run([PY, str(ROOT / "cli.py"), "play", str(TWINKLE), "-o", "o.csv"],
                       cwd=tmp_path, stdout=subprocess.PIPE, preexec_fn=_closing(2),
                       timeout=300, check=False)
    assert p.returncode == 0
    tr = read_trajectory(str(tmp_path / "o.csv"))
    assert tr.complete and tr.end["played"] == 14


@pytest.mark.parametrize("limit_mb", [100, 150, 200])
def test_a_small_address_space_is_one_line(tmp_path, limit_mb):
    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (limit_mb << 20, limit_mb << 20))

    p = subprocess.run([PY, str(ROOT / "cli.py"), "play", str(TWINKLE), "-o", "o.csv"],
                       cwd=tmp_path, capture_output=True, text=True, preexec_fn=cap,
                       timeout=300, check=False)
    assert p.returncode == 2, p.stderr
    one_line(p.stderr)
    assert "ulimit -v" in p.stderr
    assert not (tmp_path / "o.csv").exists()


# ---------------------------------------------------------------- unclear messages


def test_a_crlf_trajectory_is_named_so(capsys, planned, tmp_path):
    crlf = tmp_path / "crlf.csv"
    crlf.write_bytes(planned.read_bytes().replace(b"\n", b"\r\n"))
    rc, _, err = run_cli(capsys, "check", crlf, SCALE)
    assert_input_refused(rc, err)
    assert "CR LF" in err and "missing" not in err, err


def test_simulate_names_the_file_of_a_wrong_hash(capsys, planned, tmp_path):
    pytest.importorskip("mujoco")
    lines = planned.read_text().split("\n")
    meta = json.loads(lines[0][2:])
    meta["urdf_sha256"] = "0" * 64
    bad = tmp_path / "wrong_sha.csv"
    bad.write_text("\n".join(["# " + json.dumps(meta), *lines[1:]]))
    rc, _, err = run_cli(capsys, "simulate", bad, SCALE)
    assert_input_refused(rc, err)
    assert str(bad) in err and "<memory>" not in err, err


def test_a_huge_observation_field_is_one_line(tmp_path):
    obs = tmp_path / "obs.csv"
    obs.write_text("t,x,y,z\n" + "0," + "1" * 140_000 + ",0,0\n0.01,0,0,0\n0.02,0,0,0\n")
    p = run_sub("catch", "--angle", "30", "--dist", "1.5", "--observations", obs, "-o",
                tmp_path / "o.csv", cwd=tmp_path)
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    one_line(p.stderr)


# ---------------------------------------------------------------- self-check = check


def test_play_exits_1_with_a_plan_its_self_check_and_check_reject(capsys, tmp_path):
    """A hand whose finger acceleration cap (1e6 rad/s^2, within its unit's range) is
    beyond what its tendons carry: the planner's self-check runs the check's limit
    audit, names the violation, writes it in the end marker, and play exits 1; check
    finds the same."""
    from tests.handfiles import default_text, edit

    hand = tmp_path / "fast.toml"
    hand.write_text(edit(default_text(), "acceleration_rad_s2 = 500.0",
                         "acceleration_rad_s2 = 1e6"))
    out = tmp_path / "o.csv"
    rc, _, err = run_cli(capsys, "play", TWINKLE, "-o", out, "--hand", hand)
    assert rc == 1, err
    lines = [ln for ln in err.splitlines() if "LIMIT:" in ln]
    claims = read_trajectory(str(out)).end["limit_violations"]
    crc, cout, _ = run_cli(capsys, "check", out, TWINKLE, "--hand", hand, "--json")
    rep = json.loads(cout)
    assert crc == 1
    found = [lc for lc in rep["limits"] if not lc["ok"]]
    assert len(found) == len(claims) == len(lines) >= 1
    assert sorted((f["category"], f["count"], f["name"]) for f in found) == \
        sorted((c["category"], c["count"], c["name"]) for c in claims)
    for f in found:
        assert any(f"{f['count']} {f['category'].replace('_', ' ')} violations" in ln
                   for ln in lines)

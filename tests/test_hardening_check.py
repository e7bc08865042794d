"""Hardening (the harness and its contract: tests/hardening.py), (3) ``check`` on
damaged trajectory files (the ``planned`` fixture, conftest.py: songs/scale.mid as
``cli.py play`` plans it): every damage refused in one line or audited, never a
crash."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from planner.trajfile import MIN_ROWS
from tests.hardening import SCALE, SETTINGS, one_line, run_cli, run_sub
from tests.midibytes import notes_track, smf

# ====================================================================== 3. check on damaged files



def _lines(path: Path) -> list[str]:
    return path.read_text().split("\n")[:-1]


def _with(lines: list[str]) -> str:
    return "\n".join(lines) + "\n"


def _retime(lines, scale: float, offset: float = 0.0):
    """Every row's t scaled and offset, the rest as it is."""
    return lines[:2] + [",".join([f"{float(ln.split(',')[0]) * scale + offset:.6f}",
                                  *ln.split(",")[1:]]) for ln in lines[2:-1]] + lines[-1:]


def _end(lines):
    """``lines`` (metadata, header, rows) with an end marker that counts its rows."""
    return [*lines, f'# {{"end": true, "rows": {len(lines) - 2}}}']


def _meta(lines, **kw):
    m = json.loads(lines[0][2:])
    m.update(kw)
    for k, v in kw.items():
        if v is KeyError:
            del m[k]
    return ["# " + json.dumps(m), *lines[1:]]


def _drop_column(lines, name):
    j = lines[1].split(",").index(name)
    cut = [lines[0]] + [",".join(c for i, c in enumerate(ln.split(",")) if i != j)
                        for ln in lines[1:-1]] + [lines[-1]]
    return cut


def _add_column(lines, name, value="0.000000"):
    return [lines[0], lines[1] + "," + name] + [ln + "," + value for ln in lines[2:-1]] \
        + [lines[-1]]


def _set(lines, row, col, value):
    cells = lines[2 + row].split(",")
    cells[col] = value
    return lines[:2 + row] + [",".join(cells)] + lines[3 + row:]


DAMAGE = {  # name -> (lines -> text or bytes, expected exit status)
    "missing_joint_column": (lambda L: _with(_drop_column(L, "index_pip")), 2),
    "missing_motor_column": (lambda L: _with(_drop_column(L, L[1].split(",")[-1])), 2),
    "missing_t_column": (lambda L: _with(_drop_column(L, "t")), 2),
    "extra_column": (lambda L: _with(_add_column(L, "elbow")), 2),
    "extra_motor_column": (lambda L: _with(_add_column(L, "motor.elbow")), 2),
    "duplicate_column": (lambda L: _with(_add_column(L, "rail")), 2),
    "unknown_hand": (lambda L: _with(_meta(L, hand="nosuchhand")), 2),
    "hand_path": (lambda L: _with(_meta(L, hand="/etc/passwd")), 2),
    "hand_not_a_string": (lambda L: _with(_meta(L, hand=[1, 2])), 2),
    "wrong_urdf_hash": (lambda L: _with(_meta(L, urdf_sha256="0" * 64)), 2),
    "missing_urdf_hash": (lambda L: _with(_meta(L, urdf_sha256=KeyError)), 2),
    "wrong_mount": (lambda L: _with(_meta(L, T_world_root=np.eye(4).tolist())), 2),
    "mount_not_a_matrix": (lambda L: _with(_meta(L, T_world_root="x")), 2),
    "rate_nan": (lambda L: _with(_meta(L, rate_hz=float("nan"))), 2),
    "rate_string": (lambda L: _with(_meta(L, rate_hz="100")), 2),
    "task_unknown": (lambda L: _with(_meta(L, task="dance")), 2),
    "version_3": (lambda L: _with(_meta(L, version=3)), 2),  # (3 is two hands: no 'hands')
    "version_4": (lambda L: _with(_meta(L, version=4)), 2),  # (1, 2 and 3 are read: spec 4)
    "format_other": (lambda L: _with(_meta(L, format="csv")), 2),
    "metadata_not_json": (lambda L: _with(["# {not json", *L[1:]]), 2),
    "metadata_deeply_nested": (lambda L: _with(["# " + "[" * 100_000, *L[1:]]), 2),
    "end_marker_deeply_nested": (lambda L: _with([*L[:-1], "# " + "[" * 100_000]), 2),
    "metadata_missing": (lambda L: _with(L[1:]), 2),
    "nan_value": (lambda L: _with(_set(L, 10, 3, "nan")), 2),
    "inf_value": (lambda L: _with(_set(L, 10, 3, "inf")), 2),
    "empty_value": (lambda L: _with(_set(L, 10, 3, "")), 2),
    "word_value": (lambda L: _with(_set(L, 10, 3, "zero")), 2),
    "repeated_time": (lambda L: _with(_set(L, 10, 0, L[2 + 9].split(",")[0])), 2),
    "time_backwards": (lambda L: _with(_set(L, 10, 0, "0.000000")), 2),
    "short_row": (lambda L: _with(L[:12] + [L[12].rsplit(",", 1)[0]] + L[13:]), 2),
    "long_row": (lambda L: _with(L[:12] + [L[12] + ",0.0"] + L[13:]), 2),
    "blank_line": (lambda L: _with(L[:12] + [""] + L[12:]), 2),
    "no_end_marker": (lambda L: _with(L[:-1]), 2),
    "end_marker_rows_wrong": (lambda L: _with([*L[:-1], '# {"end": true, "rows": 3}']), 2),
    "end_marker_rows_plus_one": (lambda L: _with(
        [*L[:-1], f'# {{"end": true, "rows": {len(L) - 2}}}']), 2),
    "no_rows": (lambda L: _with([L[0], L[1], '# {"end": true, "rows": 0}']), 2),
    "empty_file": (lambda L: "", 2),
    "only_newlines": (lambda L: "\n\n\n", 2),
    "garbage_text": (lambda L: "hello, world\n1,2,3\n", 2),
    "garbage_bytes": (lambda L: bytes(range(256)) * 8, 2),
    "binary_midi": (lambda L: SCALE.read_bytes(), 2),
    "utf16": (lambda L: _with(L).encode("utf-16"), 2),
    "nul_bytes": (lambda L: b"\0" * 5000, 2),
    # valid files the audit must fail (exit 1): the file is fine, the motion is not
    "joint_beyond_limit": (lambda L: _with(_set(L, 10, 4, "9.000000")), 1),
    "ten_times_faster": (lambda L: _with(_meta(_retime(L, 0.1), rate_hz=1000)), 1),
    # the file contract (issue 14): rows at rate_hz from t = 0, no gap, metadata as the rows
    "rows_cut_from_the_middle": (lambda L: _with(_end(L[:60] + L[110:-1])), 2),
    "time_offset_100_s": (lambda L: _with(_retime(L, 1.0, 100.0)), 2),
    "time_stretched_by_2": (lambda L: _with(_retime(L, 2.0)), 2),
    "rate_hz_not_the_rows": (lambda L: _with(_meta(L, rate_hz=50)), 2),
    "one_row": (lambda L: _with(_end(L[:3])), 2),
    "crlf_line_ends": (lambda L: _with(L).replace("\n", "\r\n"), 2),
}


@pytest.mark.parametrize("name", sorted(DAMAGE))
def test_check_damaged_file(capsys, planned, tmp_path, name):
    make, expected = DAMAGE[name]
    content = make(_lines(planned))
    path = tmp_path / "damaged.csv"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, newline="")
    rc, out, err = run_cli(capsys, "check", path)
    assert rc == expected, (rc, out[-500:], err[-500:])
    if rc == 2:
        one_line(err)
        assert out == ""
    else:  # the summary, verdict first, on stdout; nothing on stderr
        assert err == "" and out.startswith(f"check {path}: FAILED")
    assert os.listdir(tmp_path) == ["damaged.csv"]


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=5), inner,
                                                                max_size=4),
    max_leaves=20)


@SETTINGS
@given(key=st.sampled_from(["task", "hand", "urdf_sha256", "T_world_root", "rate_hz", "format",
                            "version", "notes", "song"]),
       value=JSON | st.just(KeyError))
def test_check_random_metadata_values(capsys, planned, key, value):
    """Any JSON value for a metadata key: the file is replayed or refused in one line."""
    lines = _lines(planned)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d, "m.csv")
        path.write_text(_with(_meta(lines, **{key: value})), newline="")
        rc, out, err = run_cli(capsys, "check", path)
        if rc == 2:
            one_line(err)
            assert out == ""
        else:
            assert rc in (0, 1) and err == "", (rc, err)
            assert out.startswith(f"check {path}: ")


@SETTINGS
@given(cells=st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 100), st.one_of(
    st.floats(allow_nan=False, allow_infinity=False),
    st.floats(-10, 10),
    st.sampled_from([1e300, -1e300, 5e-324, 0.0, -0.0]),
)), min_size=1, max_size=5))
def test_check_random_values_are_audited_not_crashed(capsys, planned, cells):
    """Finite but wrong numbers anywhere in the rows (time included): a valid file,
    audited (exit 0 or 1, nothing on stderr) or refused (exit 2, one line: e.g. time
    no longer increasing)."""
    lines = _lines(planned)
    rows = len(lines) - 3
    for r, c, v in cells:
        lines = _set(lines, r % rows, c % len(lines[1].split(",")), repr(v))
    with tempfile.TemporaryDirectory() as d:
        path = Path(d, "v.csv")
        path.write_text(_with(lines), newline="")
        rc, out, err = run_cli(capsys, "check", path, "--json")
        if rc == 2:
            one_line(err)
            assert out == ""
        else:
            assert rc in (0, 1) and err == "", (rc, err)
            rep = json.loads(out)
            assert rep["ok"] is (rc == 0)


def test_check_the_undamaged_file_passes(capsys, planned):
    rc, out, err = run_cli(capsys, "check", planned, SCALE)
    assert rc == 0 and err == "" and out.startswith(f"check {planned}: OK"), out


@SETTINGS
@given(frac=st.one_of(st.floats(0.0, 1.0, exclude_max=True), st.just(1.0 - 1e-16)))
def test_check_truncated_anywhere(capsys, planned, frac):
    """Cut the file anywhere: refused without --allow-incomplete; with it, exactly the
    complete rows are read (a half-written last row is not a row), fewer than
    ``MIN_ROWS`` refused."""
    data = planned.read_bytes()
    cut = data[:int(frac * len(data))]
    complete_rows = max(cut.count(b"\n") - 2, 0)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d, "cut.csv")
        path.write_bytes(cut)
        rc, out, err = run_cli(capsys, "check", path)
        if cut == data[:-1]:  # only the last line break is gone: the end marker is whole
            assert rc == 0 and err == "", (rc, err)
            return
        assert rc == 2 and out == "", (rc, err)
        one_line(err)
        rc, out, err = run_cli(capsys, "check", path, "--allow-incomplete", "--json")
        if complete_rows < MIN_ROWS:  # (one row is no trajectory: trajfile.MIN_ROWS)
            assert rc == 2 and out == "", (rc, err)
            one_line(err)
        else:
            assert rc in (0, 1) and err == "", (rc, err)
            rep = json.loads(out)
            assert rep["complete"] is False
            assert rep["rows"] == complete_rows


@pytest.mark.parametrize("argv", [
    ["--min-f1", "nan"], ["--min-f1", "2"], ["--min-f1", "-1"], ["--min-f1", "0.5"],
    ["SONG_GARBAGE"], ["SONG_MISSING"], ["SONG_OUT_OF_RANGE"], ["--played", "/nonexistent/x.mid"],
], ids=" ".join)
def test_check_bad_arguments(capsys, planned, tmp_path, argv):
    songs = {"SONG_GARBAGE": tmp_path / "g.mid", "SONG_MISSING": tmp_path / "missing.mid",
             "SONG_OUT_OF_RANGE": tmp_path / "r.mid"}
    songs["SONG_GARBAGE"].write_bytes(b"garbage")
    songs["SONG_OUT_OF_RANGE"].write_bytes(smf(notes_track([(10, 0, 100, 80)])))
    argv = [str(songs.get(a, a)) for a in argv]
    rc, out, err = run_cli(capsys, "check", planned, *argv)  # --min-f1 0.5: needs a song
    assert rc == 2 and out == "", (rc, err)
    one_line(err)


def test_subprocess_check_garbage_prints_one_line(tmp_path):
    (tmp_path / "g.csv").write_bytes(bytes(range(256)))
    r = run_sub("check", tmp_path / "g.csv", cwd=tmp_path, timeout=60)
    assert r.returncode == 2 and r.stdout == ""
    one_line(r.stderr)


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_check_an_endless_file_does_not_hang(tmp_path):
    r = run_sub("check", "/dev/zero", cwd=tmp_path, timeout=60, limit_memory=True)
    assert r.returncode == 2 and r.stdout == ""
    one_line(r.stderr)


def test_a_plan_of_a_hand_file_is_checked_and_simulated_with_that_file(tmp_path, capsys):
    """A hand file of the user's own (here the default hand with its rail 1 cm higher)
    plans a song; the file names the hand 'default', whose shipped mount is another, so
    ``check`` refuses it by name (exit 2) and checks it with ``--hand FILE``, as
    ``simulate`` replays it."""
    from planner.cli import main
    from tests.handfiles import remounted_play

    hand, song, out, rc = remounted_play(tmp_path, "[0.0, -0.40, 0.06]", (60, 64))
    assert rc == 0
    capsys.readouterr()
    assert main(["check", str(out), str(song)]) == 2
    err = capsys.readouterr().err
    one_line(err)
    assert "differs from hand 'default''s mount by 0.01" in err
    assert main(["check", str(out), str(song), "--hand", str(hand), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    # (both notes played; the pad points cross the key-down depth a little after the
    # bodies the plan is timed to: F1 0.965)
    assert rep["ok"] and rep["play"]["notes_hit"] == 2 and rep["play"]["f1"] > 0.95
    pytest.importorskip("mujoco")
    from planner.simulate import simulate_trajectory

    sim = simulate_trajectory(str(out), str(song), hand_override=str(hand), contact="pads")
    assert sim.play is not None and sim.kinematic_f1 == pytest.approx(rep["play"]["f1"])

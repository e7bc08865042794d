"""Hardening (the harness and its contract: tests/hardening.py), (2) ``catch``
arguments: angles, distances, NaN, infinities, words, huge and tiny values, any
plausible throw."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from planner.check import check_trajectory
from planner.trajfile import read_trajectory
from tests.hardening import SETTINGS, assert_input_refused, one_line, part_files, run_cli, run_sub

# ====================================================================== 2. catch arguments


FLOAT_TEXT = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(["nan", "-nan", "inf", "-inf", "Infinity", "1e400", "-1e400"]),
)


def _catch(capsys, tmp_path, *args: str):
    out = Path(tmp_path, "c.csv")
    rc, o, err = run_cli(capsys, "catch", *args, "-o", out)
    return rc, o, err, out


@SETTINGS
@given(angle=st.one_of(st.floats(max_value=0.0), st.floats(min_value=90.0),
                       st.sampled_from([0.0, -0.0, 90.0, 180.0, -90.0, 1e300, -1e300])).map(repr))
def test_catch_angle_outside_0_90(capsys, angle):
    with tempfile.TemporaryDirectory() as d:
        rc, _, err, out = _catch(capsys, d, f"--angle={angle}", "--dist=3")
        assert_input_refused(rc, err, out)


@SETTINGS
@given(dist=st.one_of(st.floats(max_value=0.0), st.sampled_from([0.0, -0.0, -1e300])).map(repr))
def test_catch_dist_not_positive(capsys, dist):
    with tempfile.TemporaryDirectory() as d:
        rc, _, err, out = _catch(capsys, d, "--angle=45", f"--dist={dist}")
        assert_input_refused(rc, err, out)


@SETTINGS
@given(which=st.sampled_from(["--angle", "--dist", "--height", "--rate"]),
       value=st.sampled_from(["nan", "-nan", "NaN", "inf", "-inf", "infinity", "1e400", "-1e999"]))
def test_catch_nan_and_inf(capsys, which, value):
    args = {"--angle": "45", "--dist": "3", "--height": "0", "--rate": "100", which: value}
    with tempfile.TemporaryDirectory() as d:
        rc, _, err, out = _catch(capsys, d, *[f"{k}={v}" for k, v in args.items()])
        assert_input_refused(rc, err, out)


@SETTINGS
@given(which=st.sampled_from(["--angle", "--dist", "--height", "--rate"]),
       value=st.one_of(st.text(max_size=12).filter(lambda s: not _is_float(s)),
                       st.sampled_from(["", "1,5", "0x10", "45deg", "½", "1e", "--", "None"])))
def test_catch_non_numbers(capsys, which, value):
    args = {"--angle": "45", "--dist": "3", which: value}
    with tempfile.TemporaryDirectory() as d:
        rc, _, err, out = _catch(capsys, d, *[f"{k}={v}" for k, v in args.items()])
        assert_input_refused(rc, err, out)


def _is_float(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


@pytest.mark.parametrize("args", [
    ["--angle=1e300", "--dist=3"], ["--angle=45", "--dist=3", "--height=1e300"],
    ["--angle=45", "--dist=3", "--height=-1e300"], ["--angle=45", "--dist=3", "--rate=1e300"],
    ["--angle=45", "--dist=3", "--ball=nosuchball"], ["--angle=45", "--dist=3", "--hand=nohand"],
    ["--angle=45", "--dist=3", "--observations=/nonexistent.csv"],
], ids=" ".join)
def test_catch_huge_and_unknown_values_are_refused(capsys, tmp_path, args):
    rc, _, err, out = _catch(capsys, tmp_path, *args)
    assert_input_refused(rc, err, out)


@pytest.mark.parametrize("dist", ["1e300", "1e12", "1e6"])
def test_catch_huge_distance_is_one_line_and_no_file(capsys, tmp_path, dist):
    """A finite but absurd distance: the throw is valid input the hand cannot meet; the
    catch module calls it infeasible (exit 1) rather than bad input (exit 2). Either way:
    one line, no file."""
    rc, _, err, out = _catch(capsys, tmp_path, "--angle=45", f"--dist={dist}")
    assert rc in (1, 2), (rc, err)
    one_line(err)
    assert not out.exists() and part_files(tmp_path) == []


TINY_DIST_BUGS = {  # (angle, dist) -> what planner/catch/plan.py did before --dist >= 0.1 m
    ("45", "1e-4"): "IndexError in CatchPlanner._check_rows -> _interp_row (Q has no rows)",
    ("45", "1e-10"): "IndexError in CatchPlanner._check_rows -> _interp_row (Q has no rows)",
    ("89", "1e-20"): "MemoryError: plans 474,351,208 rows (3.5 GiB of times, "
                       "78 GiB of joint rows)",
    ("45", "1e-50"): "ValueError: Maximum allowed size exceeded (row count overflows)",
    ("45", "1e-200"): "numpy RuntimeWarnings (invalid value in divide, _unit and _refine_time) "
                      "on stderr before 'error: t must be finite', which names no argument",
    ("89", "5e-324"): "ZeroDivisionError: float division by zero",
}


@pytest.mark.parametrize("angle, dist", list(TINY_DIST_BUGS), ids=lambda v: v)
def test_catch_tiny_distance_ends_cleanly(tmp_path, angle, dist):
    """A tiny positive distance (these once crashed planner/catch/plan.py: see
    TINY_DIST_BUGS) is refused: exit 2, one line naming --dist, no file."""
    out = tmp_path / "c.csv"
    r = run_sub("catch", f"--angle={angle}", f"--dist={dist}", "-o", out, cwd=tmp_path,
                timeout=120, limit_memory=True)
    assert "Traceback" not in r.stderr and r.returncode == 2, r.stderr[-3000:]
    one_line(r.stderr)
    assert "--dist" in r.stderr
    assert not out.exists() and part_files(tmp_path) == []


@SETTINGS
@given(angle=st.floats(0.5, 89.5), dist=st.floats(0.05, 30.0), height=st.floats(-9.9, 9.9),
       ball=st.sampled_from(["tennis", "baseball", "seed"]), drag=st.booleans())
def test_catch_any_plausible_throw_ends_cleanly(capsys, angle, dist, height, ball, drag):
    """Valid arguments: exit 0 with a complete file (and, when the summary says feasible,
    the independent check agrees), or exit 1 with one line and no file."""
    with tempfile.TemporaryDirectory() as d:
        rc, o, err, out = _catch(capsys, d, f"--angle={angle!r}", f"--dist={dist!r}",
                                 f"--height={height!r}", f"--ball={ball}",
                                 *(["--drag"] if drag else []))
        assert "Traceback" not in err and o == ""
        assert part_files(d) == []
        if rc == 0:
            assert read_trajectory(str(out)).complete
            if "feasible: yes" in err:
                rep = check_trajectory(str(out))
                assert rep.ok, rep.summary()
        else:
            assert rc in (1, 2), (rc, err)
            one_line(err)
            assert not out.exists()


def test_subprocess_catch_nan_prints_one_line(tmp_path):
    r = run_sub("catch", "--angle", "nan", "--dist", "3", "-o", tmp_path / "c.csv",
                cwd=tmp_path, timeout=60)
    assert_input_refused(r.returncode, r.stderr, tmp_path / "c.csv")
    assert os.listdir(tmp_path) == []

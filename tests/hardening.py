"""Hardening: bad input never crashes the CLI, output never lies, the hand's limits hold.
This is the harness of the tests/test_hardening_*.py files (no test here).

Every case goes through the real command line (``cli.main`` in-process, with a
few subprocess runs to prove that no traceback reaches stderr) and must end in
one of the documented ways (README, "Exit status"):

* exit 0: a complete trajectory file (end marker; ``read_trajectory`` accepts
  it) whose row and note counts are the ones the summary printed;
* exit 1: under ``--strict`` only, an infeasible or late note (the file is
  still complete); for ``check``, a valid file that fails the audit;
* exit 2: exactly one line on stderr, no output file, no leftover
  ``.NAME.*.part`` temporary file.

The files: (1) test_hardening_midi.py, MIDI input and ``play`` arguments, (2)
test_hardening_catch.py, ``catch`` arguments, (3) test_hardening_check.py, ``check`` on
damaged trajectory files, (4) test_hardening_output.py, output never lies (unwritable
paths, interrupts, a full disk) and (6) determinism, (5) test_hardening_envelope.py,
the joint/motor envelope as a property over random small songs.

Hypothesis runs derandomized (the same examples on every run, no example
database) with ``HARDENING_EXAMPLES`` examples per property (default 60, a
few minutes in all on 2 cores). The long mode::

    HARDENING_EXAMPLES=1000 pytest tests/test_hardening_*.py

runs 1000 examples per property (about 20 minutes) and also replays the
10,000-note song (planned in every mode) through the independent check. Planner
bugs found here were fixed at their source and keep a test with their minimal
example (a travel that swept a fingertip into a key, OSQP's polish message on
stdout, a temporary URDF file, tiny catch distances); the catch tests skip while
planner.catch.plan.api cannot be imported.
"""

from __future__ import annotations

import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

from hypothesis import HealthCheck, settings

import cli
from planner.check import check_trajectory
from planner.music.midi import parse_song_bytes
from planner.trajfile import read_trajectory

ROOT = Path(__file__).resolve().parents[1]
SONGS = sorted((ROOT / "songs").glob("*.mid"))
SCALE = ROOT / "songs" / "scale.mid"
PY = sys.executable

EXAMPLES = int(os.environ.get("HARDENING_EXAMPLES", "60"))
LONG = EXAMPLES >= 1000
SETTINGS = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                           HealthCheck.data_too_large, HealthCheck.filter_too_much],
)
# songs planned by the fuzz cases stay short so that every case runs in a couple of seconds
MAX_PLANNED_S = 40.0

SUMMARY = re.compile(r"^(?P<name>.*): (?P<notes>\d+) notes, (?P<played>\d+) played, "
                     r"(?P<bad>\d+) infeasible; (?P<rows>\d+) rows \((?P<dur>[0-9.]+) s\) -> "
                     r"(?P<out>.*)$", re.MULTILINE)


# ====================================================================== helpers: running


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    """``cli.main(argv)`` in-process: (exit status, stdout, stderr). Python warnings that a
    real run would print on stderr are appended to stderr (pytest would swallow them)."""
    capsys.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        for cat in (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning):
            warnings.filterwarnings("ignore", category=cat)
        try:
            rc = cli.main([str(a) for a in argv])
        except SystemExit as e:  # argparse
            rc = e.code
    out, err = capsys.readouterr()
    for w in caught:
        err += f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}\n"
    return rc, out, err


def run_sub(*argv: str, cwd: str | os.PathLike, timeout: float = 120,
            limit_memory: bool = False) -> subprocess.CompletedProcess:
    """``python cli.py ARGV`` in a fresh process (as a user runs it)."""

    def cap():  # a runaway reader must not take the CI machine down
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))

    return subprocess.run([PY, str(ROOT / "cli.py"), *map(str, argv)], check=False, cwd=cwd,
                          capture_output=True, text=True, timeout=timeout,
                          preexec_fn=cap if limit_memory else None)


def part_files(d: str | os.PathLike) -> list[str]:
    return sorted(p for p in os.listdir(d) if p.endswith(".part"))


def one_line(err: str) -> None:
    assert "Traceback" not in err, err
    assert err.endswith("\n") and err.count("\n") == 1, f"not exactly one stderr line: {err!r}"


def assert_input_refused(rc: int, err: str, out_path: str | os.PathLike | None = None) -> None:
    """Exit 2, one line on stderr, no output file and no temporary file beside it."""
    assert rc == 2, (rc, err)
    one_line(err)
    if out_path is not None:
        assert not os.path.lexists(out_path), f"{out_path} left behind on exit 2"
        assert part_files(Path(out_path).parent) == []


def assert_play_outcome(rc: int, err: str, out_path: str | os.PathLike, strict: bool = False,
                        out: str = "") -> tuple[int, dict | None]:
    """A play run ended in one of the documented ways; returns (rc, summary fields)."""
    out_path = Path(out_path)
    assert "Traceback" not in err, err
    assert part_files(out_path.parent) == [], "temporary file left behind"
    if rc == 2:
        assert_input_refused(rc, err, out_path)
        return rc, None
    m = SUMMARY.search(err)
    # (exit 1 without --strict: the plan's own replay found what check fails, and said so)
    rejected = "WRONG PRESS" in err or "LIMIT:" in err
    assert rc == 0 or (rc == 1 and (strict or rejected) and m is not None), (rc, err)
    assert m is not None, f"no summary on stderr: {err!r}"
    # (OSQP's polishing once printed here; stdout must stay empty with -o FILE)
    assert out == "", "text on stdout with -o FILE"
    tr = read_trajectory(str(out_path))  # complete: end marker and valid rows
    assert tr.complete
    # output never lies: the summary's counts are those of the file
    assert int(m["rows"]) == len(tr.t_s), (m["rows"], len(tr.t_s))
    assert int(m["notes"]) == tr.metadata["notes"]
    assert m["out"] == str(out_path)
    assert math.isclose(float(m["dur"]), len(tr.t_s) / tr.metadata["rate_hz"], abs_tol=0.006)
    if rc == 1:  # --strict: something was infeasible or late, and the summary says what
        assert int(m["bad"]) > 0 or "late:" in err or rejected, err
    else:
        assert strict is False or (int(m["bad"]) == 0 and "late:" not in err), err
    return rc, m.groupdict()


def assert_envelope(path: str | os.PathLike, song: str | os.PathLike | None = None) -> None:
    """The independent check finds no limit violation and no key-bed hit."""
    rep = check_trajectory(str(path), None if song is None else str(song))
    bad = [lc for lc in rep.limits if lc.count]
    assert bad == [] and not rep.play.key_bed_hits, rep.summary()


def play_bytes(capsys, data: bytes, *flags: str, check_limits: bool = False) -> int:
    """Write ``data`` as a .mid file, run ``play`` on it, check the outcome."""
    with tempfile.TemporaryDirectory() as d:
        song = Path(d, "song.mid")
        song.write_bytes(data)
        out = Path(d, "out.csv")
        rc, o, err = run_cli(capsys, "play", song, "-o", out, *flags)
        rc, _ = assert_play_outcome(rc, err, out, strict="--strict" in flags, out=o)
        if rc != 2 and check_limits and len(read_trajectory(str(out)).t_s) <= 2000:
            assert_envelope(out)
        return rc


def playable(data: bytes, transpose: bool = False) -> bool:
    """False when the file parses into a song too long to plan within a couple of seconds
    (the planner itself is fine with it; the fuzz cases stay bounded)."""
    try:
        song = parse_song_bytes(data, transpose=transpose)
    except Exception:  # noqa: BLE001 -- refused: the CLI must say so in one line
        return True
    return max(n.offset_s for n in song.notes) <= MAX_PLANNED_S

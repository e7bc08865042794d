"""``catch --live``'s start (planner/cli/catch.py): OpenBLAS kept to one thread unless the
user set its count; the set-up loads no placo (tests/test_placo_hand.py) and none of what
only the session's ending uses."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CODE = ("import os, sys; from planner.cli import main; "
        "rc = main(['catch', '--live', '--dist', '1.5', '-o', sys.argv[1]]); "
        "tasks = len(os.listdir('/proc/self/task')) if os.path.isdir('/proc/self/task') else 1; "
        "print(rc, os.environ.get('OPENBLAS_NUM_THREADS'), tasks)")


def _start(tmp_path: Path, **env: str) -> list[str]:
    e = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    r = subprocess.run([sys.executable, "-c", CODE, str(tmp_path / "live.csv")], cwd=ROOT,
                       stdin=subprocess.DEVNULL, capture_output=True, text=True, check=False,
                       env=dict(e, **env))
    return r.stdout.split()


def test_the_live_start_keeps_openblas_to_one_thread(tmp_path):
    """Set up, then ended by the empty input (exit 2): OpenBLAS was told one thread before
    numpy loaded, and the process has no other thread."""
    assert _start(tmp_path) == ["2", "1", "1"]


def test_a_thread_count_the_user_set_is_kept(tmp_path):
    rc, n, _ = _start(tmp_path, OPENBLAS_NUM_THREADS="2")
    assert (rc, n) == ("2", "2")


def test_a_program_with_its_own_numpy_keeps_its_threads(monkeypatch):
    """``main`` called after numpy is imported changes nothing (the variable would no
    longer be read)."""
    import numpy  # noqa: F401

    from planner.cli.catch import one_blas_thread

    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    one_blas_thread()
    assert "OPENBLAS_NUM_THREADS" not in os.environ


ENDING_ONLY = ("planner.check.ball", "planner.check.ballbodies", "planner.check.ballpalm",
               "planner.check.ballroll", "planner.check.limits", "planner.check.results",
               "planner.qp", "planner.catch.plan.drop", "planner.catch.flight.dragfit")
UNUSED = ("planner.check.trajcheck", "planner.check.keys", "planner.check.verdict")  # the
# check's entry points and play rules: a live session uses none of them
SESSION = ("import sys, numpy as np; "
           "from planner.catch.live.session import CatchSession; "
           "from planner.catch.flight.path import get_ball, predict_throw; "
           "ending, unused = sys.argv[1].split(','), sys.argv[2].split(','); "
           "s = CatchSession(1.5, 0.0, ball='tennis', drag=True); "
           "print(','.join(m for m in ending + unused if m in sys.modules) or '-'); "
           "fl = predict_throw(30.0, 1.5, 0.0, get_ball('tennis'), drag=True); "
           "rng = np.random.default_rng(3); k = 0\n"
           "while not s.done and k < 300:\n"
           "    k += 1; s.observe(k / 100.0, fl.position(k / 100.0) + rng.normal(0.0, 0.002, 3))\n"
           "print(s.outcome, ','.join(m for m in ending if m not in sys.modules) or '-', "
           "','.join(m for m in unused if m in sys.modules) or '-')")


def test_the_live_start_imports_none_of_what_only_its_ending_uses():
    """A live session set up (ready for its first observation) has imported none of the
    modules only its ending uses (the check's ball rules, the grasp QP's OSQP wrapper, the
    hand's drop, the drag's fit) nor the check's entry points; the session of a 30 deg /
    1.5 m throw then ends, held, with every one of the first imported (so the list names
    what the ending really uses) and still none of the second."""
    r = subprocess.run([sys.executable, "-c", SESSION, ",".join(ENDING_ONLY), ",".join(UNUSED)],
                       cwd=ROOT, capture_output=True, text=True, check=False)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["-", "held", "-", "-"], r.stdout + r.stderr


NOT_AT_START = ("tempfile", "csv", "importlib.resources", "planner.catch.plan.palmup",
                "planner.catch.plan.stopstages", "planner.simulate.verdict",
                "planner.hand.mk5_tables")  # the output path's probe, the observation files'
# reader, the hands' folder, the planned catch's fallbacks, the physics' verdict, the Mk5
# hand's tables: none of them is what a live session of the default hand runs
START = ("import sys; from planner.cli import main; import planner.catch.livecli as lc; "
         "names = sys.argv[2].split(','); run = lc.run_session\n"
         "def ready(session, stream):\n"
         "    print(','.join(m for m in names if m in sys.modules) or '-')\n"
         "    return run(session, stream)\n"
         "lc.run_session = ready; print(main(['catch', '--live', '--dist', '1.5', '--drag', "
         "'-o', sys.argv[1]]))")


def test_the_live_start_imports_none_of_what_a_live_session_does_not_run(tmp_path):
    """``catch --live`` into a new file, ready for its first observation (its session
    set up, about to read stdin; ended by the empty input, exit 2): none of
    ``NOT_AT_START`` imported, and the output path's probe left nothing beside it."""
    r = subprocess.run([sys.executable, "-c", START, str(tmp_path / "live.csv"),
                        ",".join(NOT_AT_START)], cwd=ROOT, stdin=subprocess.DEVNULL,
                       capture_output=True, text=True, check=False)
    assert r.stdout.split() == ["-", "2"], r.stdout + r.stderr
    assert list(tmp_path.iterdir()) == []

"""``catch --live``'s start (planner/cli/catch.py): OpenBLAS kept to one thread unless the
user set its count; the set-up loads no placo (tests/test_placo_hand.py)."""

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

"""Start-up of the command line (issue 18, item 4): wall time of each command from a fresh
interpreter to its exit, and of its imports alone, best of N runs.

    python bench/bench_start.py [--repeat 5]

Not a test: it prints what this machine measures. Target: `hand` and `catch` ready to
plan within 0.5 s of start; `catch --live` ready for its first observation within 0.5 s
(issue 15): the time until it first blocks reading standard input, everything set up.

Measured as a user's install runs: Python writes and then reuses its bytecode
(``__pycache__``). ``PYTHONDONTWRITEBYTECODE`` is taken out of the commands'
environment (some sandboxes set it; every run would then compile the planner's
sources again, 0.1 s), and each command runs once before it is timed.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CASES = {
    "hand": (["hand"], "import planner.cli, planner.hand.model"),
    "catch": (["catch", "--angle", "30", "--dist", "1.5", "-o", "{out}/c.csv"],
              "import planner.cli, planner.catch.summary"),
    "play twinkle": (["play", str(ROOT / "songs" / "twinkle.mid"), "-o", "{out}/t.csv"],
                     "import planner.cli, planner.play.stream"),
    "check twinkle": (["check", "{out}/t.csv", str(ROOT / "songs" / "twinkle.mid")],
                      "import planner.cli, planner.check"),
}


ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
LIVE = ["catch", "--live", "--dist", "1.5", "--drag", "-o", "{out}/live.csv"]
READ_SYSCALL = "0"  # x86-64 read(2): /proc/PID/syscall's first field while it blocks in it
POLL_S = 0.0005


def ready_s(cmd: list[str]) -> float:
    """From the start of ``cmd`` until it blocks reading its standard input (fd 0) for
    the first time: set up, waiting for the first observation. Then stdin is closed (no
    observation: the command ends with exit 2). /proc/PID/syscall names the system call
    a process is blocked in (Linux)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, cwd=ROOT, env=ENV)
    ready = None
    while ready is None and p.poll() is None:
        try:
            with open(f"/proc/{p.pid}/syscall") as f:
                call = f.read().split()
        except OSError:
            call = []
        if len(call) > 1 and call[0] == READ_SYSCALL and int(call[1], 16) == 0:
            ready = time.perf_counter() - t0
        else:
            time.sleep(POLL_S)
    p.communicate(b"")
    if ready is None:
        raise SystemExit(f"{' '.join(cmd)} ended before reading its input")
    return ready


def best_ready(cmd: list[str], repeat: int) -> float:
    ready_s(cmd)  # bytecode
    return min(ready_s(cmd) for _ in range(repeat))


def best_of(cmd: list[str], repeat: int) -> float:
    subprocess.run(cmd, capture_output=True, check=False, cwd=ROOT, env=ENV)  # bytecode
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        subprocess.run(cmd, capture_output=True, check=False, cwd=ROOT, env=ENV)
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    bare = best_of([sys.executable, "-c", "pass"], a.repeat)
    print(f"{'command':16s} {'wall s':>7s} {'imports s':>9s}   (a bare interpreter: {bare:.3f} s)")
    with tempfile.TemporaryDirectory() as out:
        for name, (argv, imports) in CASES.items():
            wall = best_of([sys.executable, "-m", "planner.cli",
                            *(x.format(out=out) for x in argv)], a.repeat)
            imp = best_of([sys.executable, "-c", imports], a.repeat)
            print(f"{name:16s} {wall:7.3f} {imp:9.3f}")
        if os.path.exists("/proc/self/syscall"):
            ready = best_ready([sys.executable, "-m", "planner.cli",
                                *(x.format(out=out) for x in LIVE)], a.repeat)
            print(f"{'catch --live':16s} ready for its first observation (blocked reading "
                  f"stdin) after {ready:.3f} s")


if __name__ == "__main__":
    main()

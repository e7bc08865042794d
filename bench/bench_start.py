"""Start-up of the command line (issue 18, item 4): wall time of each command from a fresh
interpreter to its exit, and of its imports alone, best of N runs.

    python bench/bench_start.py [--repeat 5]

Not a test: it prints what this machine measures. Target: `hand` and `catch` ready to
plan within 0.5 s of start; `catch --live` ready for its first observation within 0.5 s
(issue 15): the time until it first blocks reading standard input, everything set up.

``--live-against DIR``: ``catch --live`` of this checkout and of the checkout DIR
alternated (``--repeat`` runs each, after one of each for the bytecode): the medians of
the wall time until ready and of the CPU time the process has used by then (all its
threads, ``/proc/PID/task/*/schedstat``), and the machine's load. On a loaded machine
the wall time is 2-3x the CPU time whatever the priority: the CPU is what the command
itself costs.

Measured as a user's install runs: Python writes and then reuses its bytecode
(``__pycache__``). ``PYTHONDONTWRITEBYTECODE`` is taken out of the commands'
environment (some sandboxes set it; every run would then compile the planner's
sources again, 0.1 s), and each command runs once before it is timed.
"""

from __future__ import annotations

import argparse
import os
import statistics
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


def cpu_s(pid: int) -> float:
    """The CPU time process ``pid`` has used so far, all its threads (Linux)."""
    total = 0
    for t in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{t}/schedstat") as f:
                total += int(f.read().split()[0])
        except OSError:  # (a thread that has just ended)
            pass
    return total / 1e9


def ready_s(cmd: list[str], cwd: Path = ROOT, env: dict[str, str] | None = None
            ) -> tuple[float, float]:
    """From the start of ``cmd`` until it blocks reading its standard input (fd 0) for
    the first time: set up, waiting for the first observation; and the CPU time it has
    used by then. Then stdin is closed (no observation: the command ends with exit 2).
    /proc/PID/syscall names the system call a process is blocked in (Linux)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, cwd=cwd, env=env or ENV)
    ready = cpu = None
    while ready is None and p.poll() is None:
        try:
            with open(f"/proc/{p.pid}/syscall") as f:
                call = f.read().split()
        except OSError:
            call = []
        if len(call) > 1 and call[0] == READ_SYSCALL and int(call[1], 16) == 0:
            ready, cpu = time.perf_counter() - t0, cpu_s(p.pid)
        else:
            time.sleep(POLL_S)
    p.communicate(b"")
    if ready is None:
        raise SystemExit(f"{' '.join(cmd)} ended before reading its input")
    return ready, cpu


def best_ready(cmd: list[str], repeat: int) -> float:
    ready_s(cmd)  # bytecode
    return min(ready_s(cmd)[0] for _ in range(repeat))


def live_against(other: Path, repeat: int) -> None:
    """``catch --live`` here and in checkout ``other`` alternated: medians of ready and of
    the CPU by then."""
    trees = {"this": ROOT, str(other): other.resolve()}
    runs: dict[str, list[tuple[float, float]]] = {k: [] for k in trees}
    with tempfile.TemporaryDirectory() as out:
        def one(tree: Path) -> tuple[float, float]:
            env = dict(ENV, PYTHONPATH=str(tree))
            return ready_s([sys.executable, str(tree / "cli.py"),
                            *(x.format(out=out) for x in LIVE)], tree, env)

        for tree in trees.values():
            one(tree)  # bytecode
        for i in range(repeat):
            for name in (list(trees) if i % 2 == 0 else list(trees)[::-1]):
                runs[name].append(one(trees[name]))
    print(f"catch --live, {repeat} alternated runs each, load {os.getloadavg()[0]:.1f}")
    for name, r in runs.items():
        wall, cpu = sorted(x[0] for x in r), sorted(x[1] for x in r)
        print(f"  {name:24s} ready median {statistics.median(wall):.3f} s (best "
              f"{wall[0]:.3f}), CPU by then median {statistics.median(cpu):.3f} s")


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
    ap.add_argument("--live-against", type=Path, default=None, metavar="DIR",
                    help="only catch --live, alternated with the checkout DIR's")
    a = ap.parse_args()
    if a.live_against is not None:
        live_against(a.live_against, a.repeat)
        return
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

"""Peak memory of `play` and `check` against the song's length (issue 32, item 5): songs
of N notes (scale runs and chords, a fixed seed), each planned with `python cli.py play`
and checked with `python cli.py check`, both under `/usr/bin/time -v`; the peak resident
set size of each, and its ratio to the 300 MB the issue allows.

    python bench/bench_memory.py [--sizes 1000 5000 20000] [--code DIR]

``--code DIR``: the code to run (its ``cli.py``, on PYTHONPATH; default this checkout),
e.g. another worktree for a before / after table. Beside ``bench_growth.py`` (time
against N). Not a test: it prints what this machine measures.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from planner.music.midi import Note, write_notes_midi

BUDGET_MB = 300.0
SEED = 32
C_MAJOR = (0, 2, 4, 5, 7, 9, 11)


def _pitch(degree: int) -> int:
    octave, step = divmod(degree, 7)
    return 60 + 12 * octave + C_MAJOR[step]


def song_notes(n: int, seed: int = SEED) -> list[Note]:
    """``n`` notes: an eight-note scale run (0.3 s a note) up or down from a random degree,
    then a triad held 0.6 s, over and over (about 3.7 notes a second)."""
    rng = np.random.default_rng(seed)
    t, out = 0.0, []
    while len(out) < n:
        d0, step = int(rng.integers(-3, 5)), int(rng.choice([-1, 1]))
        for i in range(8):
            out.append(Note(_pitch(d0 + step * i), t, t + 0.28, 80))
            t += 0.3
        root = int(rng.integers(-2, 5))
        out.extend(Note(_pitch(root + k), t, t + 0.55, 80) for k in (0, 2, 4))
        t += 0.6
    return out[:n]


def peak(cmd: list[str], code: Path) -> tuple[float, float, int]:
    """Peak RSS (MB), wall time (s) and exit status of ``cmd`` under /usr/bin/time -v."""
    env = dict(os.environ, PYTHONPATH=str(code))
    p = subprocess.run(["/usr/bin/time", "-v", *cmd], cwd=code, env=env,
                       capture_output=True, text=True, check=False)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", p.stderr)
    secs = 0.0
    if wall:
        h, m, s = wall.groups()
        secs = 3600 * float(h or 0) + 60 * float(m) + float(s)
    return (int(rss.group(1)) / 1024 if rss else float("nan")), secs, p.returncode


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 5000, 20000])
    ap.add_argument("--code", default=str(ROOT), help="the checkout to run (default: this one)")
    a = ap.parse_args()
    code = Path(a.code).resolve()
    print(f"code: {code}")
    print(f"{'notes':>7s} {'song min':>8s} {'file MB':>8s} {'play MB':>8s} {'x 300':>6s} "
          f"{'play s':>7s} {'check MB':>8s} {'x 300':>6s} {'check s':>7s} {'exit':>5s}")
    with tempfile.TemporaryDirectory() as d:
        for n in a.sizes:
            notes = song_notes(n)
            mid, plan = os.path.join(d, f"s{n}.mid"), os.path.join(d, f"s{n}.csv")
            write_notes_midi(notes, mid)
            py = sys.executable
            pm, ps, pr = peak([py, "cli.py", "play", mid, "-o", plan], code)
            cm, cs, cr = peak([py, "cli.py", "check", plan, mid], code)
            size = os.path.getsize(plan) / 1e6 if os.path.exists(plan) else float("nan")
            print(f"{n:7d} {notes[-1].offset_s / 60:8.1f} {size:8.1f} {pm:8.0f} "
                  f"{pm / BUDGET_MB:6.2f} {ps:7.1f} {cm:8.0f} {cm / BUDGET_MB:6.2f} {cs:7.1f} "
                  f"{pr}/{cr}", flush=True)


if __name__ == "__main__":
    main()

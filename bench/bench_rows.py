"""Rows a controller can run (not a test): every song given, planned by ``cli.py play``
in a fresh process as a user runs it and judged by the independent check, per song:

* rest to rest: the first and the last row at the hand's rest pose (``Planner.rest_q``;
  the largest joint difference, rad or m, against the file's 1e-6 rounding) and still
  there: a row from rest moves each joint at most ``jerk * dt^3 / 6`` (speed and
  acceleration zero, the jerk within its bound), likewise the last row from the one before;
* no key down at the first or the last row (the check's body rule);
* every limit category of the check (``joint_jerk``: jerk within bounds,
  ``joint_stop_margin``: off the hard stops, and the others) with its count of (row,
  joint) samples past the limit; wrong presses, key-bed and body-bed hits.

    python bench/bench_rows.py OUT_DIR SONG_OR_DIR ... [--hand NAME] [--tree PATH]

``--tree PATH`` runs another checkout's ``cli.py`` and planner. One line a song, then the
totals; exit 0 whatever it finds.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

WRITE_TOL = 1.5e-6  # the file's six decimals: a value written is within 5e-7 of the
# planned one; two of them (a difference) within 1e-6, with room for the sum's rounding


def songs_of(paths: list[str]) -> list[Path]:
    out: list[Path] = []
    for p in map(Path, paths):
        out += sorted(p.glob("*.mid")) if p.is_dir() else [p]
    return out


def ends(q: np.ndarray, rest_q: np.ndarray, jerk: np.ndarray, dt: float) -> dict[str, float]:
    """How far the first and last rows are from rest (``rest``), and how far the second
    row (the one before the last) moved past what a start (stop) from rest allows
    (``start``, ``stop``: <= 0 when still), each the worst over the joints."""
    step = np.where(np.isfinite(jerk), jerk * dt ** 3 / 6.0, np.inf) + WRITE_TOL
    rest = max(float(np.abs(q[0] - rest_q).max()), float(np.abs(q[-1] - rest_q).max()))
    start = float((np.abs(q[1] - q[0]) - step).max())
    stop = float((np.abs(q[-1] - q[-2]) - step).max())
    return {"rest": rest, "start": start, "stop": stop}


def judge(csv: Path, song: Path, rest_q: np.ndarray, hand) -> str:
    from planner.check import check_trajectory

    rep = check_trajectory(str(csv), str(song))
    rp = rep.replay
    e = ends(rp.q, rest_q, hand.jerk, 1.0 / rep.rate_hz)
    still = e["rest"] <= WRITE_TOL and e["start"] <= 0.0 and e["stop"] <= 0.0
    down0 = int(rp.down[0].sum()) + int(rp.down[-1].sum())
    bad = [f"{lc.category} {lc.count} ({lc.worst:.6g}/{lc.limit:.6g} {lc.name} at {lc.time_s:.2f} s)"
           for lc in rep.limits if lc.count]
    pr = rep.play
    wrong = len(pr.wrong_presses)
    beds = len(pr.key_bed_hits) + len(pr.body_bed_hits)
    return (f"{song.name:28s} check {'ok  ' if rep.ok else 'FAIL'} F1 {pr.f1:.4f} "
            f"rest {'yes' if still else 'NO '} (|q-rest| {e['rest']:.1e}, start {e['start']:+.1e},"
            f" stop {e['stop']:+.1e}) keys down at ends {down0} wrong {wrong} beds {beds} "
            f"limits {'; '.join(bad) if bad else 'none'}")


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("songs", nargs="+")
    ap.add_argument("--hand", default="default")
    ap.add_argument("--tree", default=str(ROOT))
    a = ap.parse_args(argv)
    tree = Path(a.tree).resolve()
    sys.path.insert(0, str(tree))
    from planner.hand.model import load_hand
    from planner.play import Planner

    hand = load_hand(a.hand)
    rest_q = Planner(hand).rest_q
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHONPATH": str(tree)}
    for song in songs_of(a.songs):
        csv = out / f"{song.stem}.csv"
        r = subprocess.run([sys.executable, str(tree / "cli.py"), "play", str(song), "--hand",
                            a.hand, "-o", str(csv)], capture_output=True, text=True, env=env,
                           check=False)
        if r.returncode not in (0, 1) or not csv.exists():
            print(f"{song.name:28s} play exit {r.returncode}: {r.stderr.strip()[-200:]}")
            continue
        print(judge(csv, song, rest_q, hand), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

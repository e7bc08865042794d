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


def judge(csv: Path, song: Path, rest_q: np.ndarray, hand) -> dict:
    """One plan's facts (``line`` formats them)."""
    from planner.check import check_trajectory

    rep = check_trajectory(str(csv), str(song))
    rp = rep.replay
    e = ends(rp.q, rest_q, hand.jerk, 1.0 / rep.rate_hz)
    pr = rep.play
    return {"song": song.name, "ok": bool(rep.ok), "f1": float(pr.f1), **e,
            "still": e["rest"] <= WRITE_TOL and e["start"] <= 0.0 and e["stop"] <= 0.0,
            "down": int(rp.down[0].sum()) + int(rp.down[-1].sum()),
            "wrong": len(pr.wrong_presses),
            "beds": len(pr.key_bed_hits) + len(pr.body_bed_hits),
            "violations": sum(lc.count for lc in rep.limits),
            "limits": [f"{lc.category} {lc.count} ({lc.worst:.6g}/{lc.limit:.6g} {lc.name} at "
                       f"{lc.time_s:.2f} s)" for lc in rep.limits if lc.count]}


def line(j: dict) -> str:
    return (f"{j['song']:28s} check {'ok  ' if j['ok'] else 'FAIL'} F1 {j['f1']:.4f} "
            f"rest {'yes' if j['still'] else 'NO '} (|q-rest| {j['rest']:.1e}, start "
            f"{j['start']:+.1e}, stop {j['stop']:+.1e}) keys down at ends {j['down']} wrong "
            f"{j['wrong']} beds {j['beds']} limits "
            f"{'; '.join(j['limits']) if j['limits'] else 'none'}")


def totals(js: list[dict]) -> str:
    """The songs together: one table row (the history pages' columns)."""
    if not js:
        return "no song judged"
    return (f"| {len(js)} | {sum(j['ok'] for j in js)} | {sum(j['still'] for j in js)} | "
            f"{max(j['rest'] for j in js):.1e} | {max(j['start'] for j in js):+.1e} / "
            f"{max(j['stop'] for j in js):+.1e} | {sum(j['down'] for j in js)} | "
            f"{sum(j['violations'] for j in js)} | {sum(j['wrong'] for j in js)} | "
            f"{sum(j['beds'] for j in js)} | {np.mean([j['f1'] for j in js]):.4f} "
            f"({min(j['f1'] for j in js):.4f}) |")


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
    judged, failed = [], 0
    for song in songs_of(a.songs):
        csv = out / f"{song.stem}.csv"
        r = subprocess.run([sys.executable, str(tree / "cli.py"), "play", str(song), "--hand",
                            a.hand, "-o", str(csv)], capture_output=True, text=True, env=env,
                           check=False)
        if r.returncode not in (0, 1) or not csv.exists():
            print(f"{song.name:28s} play exit {r.returncode}: {r.stderr.strip()[-200:]}")
            failed += 1
            continue
        judged.append(judge(csv, song, rest_q, hand))
        print(line(judged[-1]), flush=True)
    print(f"\n{failed} songs without a plan\n| songs | check ok | rest to rest | worst \\|q - rest\\| "
          "| slack start / end | keys down at the ends | limit violations (any category) | "
          "wrong presses | bed hits | F1 mean (lowest) |")
    print(totals(judged))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

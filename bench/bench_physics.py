"""Physics as the proof, at scale: every song of a folder planned, checked and replayed in
MuJoCo (full contact), per category: the check's frame F1 (its verdict's rule: the bodies,
spec section 2; an older tree's: the pad points) and the body rule's (an older tree reported
it apart, ``bodies``; nan before it), the physics' frame F1, wrong keys in physics, the
plans `check` fails, the planning's and the replay's real-time factors.

    python bench/bench_physics.py [--corpus DIR] [--tree DIR] [--hand NAME] [--only S]

``--tree DIR``: the planner of another checkout (a worktree of an older revision: ``git
worktree add --detach /tmp/old REV``), so that two revisions are measured by the same
script; run it once per tree and compare the tables. Needs MuJoCo (the physics extra).
Not a test: it prints what this machine measures.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def category(p: Path) -> str:
    return p.stem.split("_")[0]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default=str(ROOT.parent / "shared" / "corpus"))
    ap.add_argument("--tree", default=str(ROOT), help="the checkout whose planner is measured")
    ap.add_argument("--hand", default="default")
    ap.add_argument("--only", default=None, help="only songs whose name holds this")
    a = ap.parse_args()
    sys.path.insert(0, a.tree)
    from planner.check import check_trajectory
    from planner.hand.model import load_hand
    from planner.music.midi import load_song
    from planner.play import Planner, plan_song
    from planner.simulate import simulate_trajectory

    songs = sorted(Path(a.corpus).glob("*.mid"))
    if a.only:
        songs = [s for s in songs if a.only in s.stem]
    hand = load_hand(a.hand)
    pl = Planner(hand)
    rows = []
    print(f"tree {a.tree}")
    print(f"{'song':40s} {'check F1':>8s} {'body F1':>8s} {'phys F1':>8s} {'wrong':>5s} "
          f"{'plan RTF':>8s} {'sim RTF':>7s} check")
    with tempfile.TemporaryDirectory() as d:
        for p in songs:
            out = str(Path(d) / "o.csv")
            song = load_song(p)
            plan = plan_song(song, hand, out, planner=pl)
            rep = check_trajectory(out, str(p))
            body = getattr(rep, "bodies", rep.play)  # (this tree: the verdict is the bodies')
            body_f1 = float("nan") if body is None or body.f1 is None else body.f1
            t0 = time.perf_counter()
            sim = simulate_trajectory(out, str(p))
            sim_s = time.perf_counter() - t0
            song_s = max(n.offset_s for n in song.notes)
            row = (category(p), p.stem, rep.play.f1, sim.play.f1, len(sim.play.wrong_keys),
                   song_s / plan.planning_s, sim.duration_s / sim_s, body_f1, not rep.ok)
            rows.append(row)
            print(f"{p.stem[:40]:40s} {row[2]:8.4f} {row[7]:8.4f} {row[3]:8.4f} {row[4]:5d} "
                  f"{row[5]:7.0f}x {row[6]:6.1f}x {'FAIL' if row[8] else 'ok'}", flush=True)
    by = defaultdict(list)
    for r in rows:
        by[r[0]].append(r)
        by["(all)"].append(r)
    print(f"\n{'category':12s} {'songs':>5s} {'check F1':>8s} {'body F1':>8s} {'phys F1':>8s} "
          f"{'min phys':>8s} {'wrong':>6s} {'fails':>5s} {'plan RTF':>8s} {'sim RTF':>7s}")
    for c, rs in sorted(by.items()):
        print(f"{c:12s} {len(rs):5d} {statistics.mean(r[2] for r in rs):8.4f} "
              f"{statistics.mean(r[7] for r in rs):8.4f} "
              f"{statistics.mean(r[3] for r in rs):8.4f} {min(r[3] for r in rs):8.4f} "
              f"{sum(r[4] for r in rs):6d} {sum(r[8] for r in rs):5d} "
              f"{statistics.median(r[5] for r in rs):7.0f}x "
              f"{statistics.median(r[6] for r in rs):6.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The wide catch grid as a whole (not a test): angles 15-75 deg (step 10) x distances
0.5-4 m (step 0.5) x heights -0.3/0/+0.3 m, tennis ball, vacuum, the soft catch as
``cli.py catch`` plans it. Each throw: feasible or the first reason a hard limit names (out
of reach, too soon, too fast to stop: with its number) or the plan's shortfall; every
feasible plan written, judged by ``planner.check`` and replayed in MuJoCo (full contact,
``cli.py simulate``'s default): held or not, and how far from the palm centre at the end.

    python bench/bench_catch_wide.py [--tree DIR] [--no-physics] [--only ANGLE]

``--tree DIR``: the planner of another checkout (a worktree of an older revision), so that
two revisions are measured by the same script. Needs MuJoCo (the physics extra).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", default=str(ROOT), help="the checkout whose planner is measured")
    ap.add_argument("--no-physics", action="store_true", help="plan and check only")
    ap.add_argument("--only", type=int, default=None, help="only this launch angle (deg)")
    a = ap.parse_args()
    sys.path.insert(0, a.tree)
    from planner.catch.plan.api import get_planner, plan_throw, write_plan
    from planner.catch.plan.reasons import HARD_LIMITS
    from planner.check import check_trajectory
    from planner.errors import InputError

    simulate = None
    if not a.no_physics:
        from planner.simulate import simulate_trajectory as simulate

    pl = get_planner("default")
    angles = [a.only] if a.only is not None else list(range(15, 76, 10))
    counts: Counter[str] = Counter()
    kinds: Counter[str] = Counter()
    lost = []
    t0 = time.perf_counter()
    print(f"tree {a.tree}")
    with tempfile.TemporaryDirectory() as d:
        path = str(Path(d) / "c.csv")
        for h in (-0.3, 0.0, 0.3):
            for ang in angles:
                for dist in np.arange(0.5, 4.01, 0.5):
                    name = f"{h:+.1f} m {ang:2d} deg {dist:.1f} m"
                    try:
                        p = plan_throw(float(ang), float(dist), h, planner=pl)
                    except InputError:
                        counts["no such throw"] += 1
                        continue
                    counts["throws"] += 1
                    if not p.feasible:
                        hard = [r for r in p.reasons if r.kind in HARD_LIMITS]
                        r = hard[0] if hard else p.reasons[0]
                        counts["named" if hard else "other"] += 1
                        kinds[r.kind.value] += 1
                        print(f"{name}: infeasible ({'hard' if hard else 'shortfall'}) {r}",
                              flush=True)
                        continue
                    counts["feasible"] += 1
                    write_plan(p, path)
                    ok = check_trajectory(path).ok
                    counts["check ok"] += ok
                    line = f"{name}: feasible, check {'OK' if ok else 'REJECTS'}"
                    if simulate is not None:
                        c = simulate(path).catch
                        counts["held"] += bool(c.held)
                        if not c.held:
                            lost.append(name)
                        line += (f", physics {'held' if c.held else 'NOT held'} "
                                 f"({1000 * c.end_distance_m:.0f} mm from the palm centre)")
                    print(line, flush=True)
    print(f"\n{counts['throws']} throws ({counts['no such throw']} grid points are no throw): "
          f"feasible {counts['feasible']} ({100 * counts['feasible'] / counts['throws']:.0f} %), "
          f"check OK {counts['check ok']}, held in physics "
          f"{counts['held'] if simulate else 'not run'}; infeasible for a hard limit "
          f"{counts['named']}, for a shortfall {counts['other']}")
    print("infeasible by first reason: " + ", ".join(f"{k} {v}" for k, v in kinds.most_common()))
    if lost:
        print("feasible, not held in physics: " + "; ".join(lost))
    print(f"wall {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

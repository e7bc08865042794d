"""Catch planning latency (not a test).

After import and the one-time setup (hand, IK solver, closing table for the
ball, a few warm-up plans), plans N random throws -- angle U(20, 60) deg,
distance U(1, 3) m, height U(-0.2, 0.2) m -- with ``plan_throw`` (flight,
intercept, IK, timing, rows, force QPs, self-check; no file is written) and
prints p50 / p99 of the per-throw latency and its ratio to the seed's budget:
a 0.42 s flight (30 deg over 1.5 m) less the 300 ms actuation time and the
25 ms signal handling leaves 95 ms for planning.

    /work/.venv/bin/python bench/bench_catch.py [--n 1000] [--hand default] [--ball tennis]

``--grid`` instead: issue 15's envelope, angles 15-75 deg (step 10) x distances 0.5-4 m
(step 0.5) x heights -0.3/0/+0.3 m, planned twice in one run, the palm waiting at rest
(``soft=False``: the catch before issue 15, judged by today's rule) and with the soft catch;
each cell the stopping headroom (%) or why not; the count of throws named with a reason no
motion of the hand overcomes (out of reach, too soon, too fast to stop); the headroom per
motor at 30 deg from 1.5 and 3 m; with ``--check`` every feasible soft plan written and
judged by ``planner.check``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.catch.flight.path import get_ball
from planner.catch.plan.api import get_planner, plan_throw, write_plan
from planner.catch.plan.reasons import HARD_LIMITS, CatchReason
from planner.errors import InputError

BUDGET_S = 0.420 - 0.300 - 0.025  # seed flight time - actuation time - signal handling


_SHORT = {CatchReason.OUT_OF_REACH: "reach", CatchReason.TOO_SOON: "soon",
          CatchReason.TOO_FAST_TO_STOP: "fast"}


def _cell(p) -> str:
    if p is None:
        return "-"
    if p.feasible:
        return f"{100 * p.forces.stop.headroom:.0f}"
    hard = [k for k in p.reason_kinds if k in HARD_LIMITS]
    return _SHORT[hard[0]] if hard else p.reason_kinds[0].value


def grid(pl, ball, check: bool) -> int:
    """The ``--grid`` run (module docstring)."""
    import tempfile

    heights, angles, dists = (-0.3, 0.0, 0.3), range(15, 76, 10), np.arange(0.5, 4.01, 0.5)
    tmp = Path(tempfile.mkdtemp(prefix="bench_catch_"))
    for soft in (False, True):
        counts: Counter[str] = Counter()
        cpu = []
        rejected = []
        print(f"\n{'soft catch' if soft else 'palm at rest (before issue 15)'}: stopping "
              "headroom % (feasible) or why not (reach / soon / fast); '-' no such throw")
        print("  h(m) deg " + " ".join(f"{d:>5.1f}" for d in dists))
        for h in heights:
            for a in angles:
                cells = []
                for d in dists:
                    c = time.process_time()
                    try:
                        p = plan_throw(a, d, h, planner=pl, ball=ball, soft=soft)
                    except InputError:
                        p = None
                    cpu.append(time.process_time() - c)
                    cells.append(_cell(p))
                    if p is None:
                        counts["no such throw"] += 1
                        continue
                    named = bool(set(p.reason_kinds) & HARD_LIMITS)
                    counts["feasible" if p.feasible else "named" if named else "other"] += 1
                    if check and soft and p.feasible:
                        from planner.check import check_trajectory

                        path = tmp / "c.csv"
                        write_plan(p, str(path))
                        rep = check_trajectory(str(path))
                        counts["check ok"] += rep.ok
                        if not rep.ok:
                            rejected.append((a, d, h, rep.problems))
                print(f"  {h:+.1f} {a:3d} " + " ".join(f"{x:>5s}" for x in cells))
        n = sum(counts[k] for k in ("feasible", "named", "other"))
        print(f"  {n} throws: feasible {counts['feasible']}, infeasible for a hard limit "
              f"{counts['named']}, otherwise {counts['other']} ({counts['no such throw']} "
              f"grid points are no throw); planning CPU p50 "
              f"{1000 * np.percentile(cpu, 50):.1f} ms, p99 {1000 * np.percentile(cpu, 99):.1f} ms")
        if check and soft:
            print(f"  check: {counts['check ok']} of {counts['feasible']} feasible plans pass; "
                  f"rejected {rejected[:3]}")
        for d in (1.5, 3.0):
            p = plan_throw(30.0, d, 0.0, planner=pl, ball=ball, soft=soft)
            st = p.forces.stop
            worst = sorted(zip(p.hand.motor_names, st.motor_headroom), key=lambda x: x[1])[:4]
            print(f"  30 deg from {d:g} m: feasible {p.feasible}, stopping {st.force_n:.1f} N, "
                  f"headroom {100 * st.headroom:.1f} % (motor.{st.motor}); least per motor: "
                  + ", ".join(f"{m} {100 * x:.1f} %" for m, x in worst))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--hand", default="default")
    ap.add_argument("--ball", default="tennis")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--grid", action="store_true", help="issue 15's envelope, before/after")
    ap.add_argument("--check", action="store_true", help="with --grid: check every feasible plan")
    a = ap.parse_args(argv)

    t0 = time.perf_counter()
    pl = get_planner(a.hand)
    ball = get_ball(a.ball)
    pl.closing(ball.radius_m)
    setup = time.perf_counter() - t0
    if a.grid:
        return grid(pl, ball, a.check)

    rng = np.random.default_rng(a.seed)
    throws = np.column_stack([rng.uniform(20, 60, a.n), rng.uniform(1, 3, a.n),
                              rng.uniform(-0.2, 0.2, a.n)])
    first = None
    for k in range(a.warmup):
        t = time.perf_counter()
        plan_throw(*throws[k % a.n], planner=pl, ball=ball)
        if first is None:
            first = time.perf_counter() - t
    lat = np.empty(a.n)
    cpu = np.empty(a.n)
    reasons: Counter[str] = Counter()
    feasible = 0
    for k, (ang, dist, hgt) in enumerate(throws):
        c = time.process_time()
        t = time.perf_counter()
        p = plan_throw(ang, dist, hgt, planner=pl, ball=ball)
        lat[k] = time.perf_counter() - t
        cpu[k] = time.process_time() - c
        feasible += p.feasible
        reasons.update({r.kind.value for r in p.reasons})
    p50, p99 = np.percentile(lat, [50, 99])
    ms = 1000.0
    print(f"catch planning latency, hand {a.hand}, ball {a.ball}, {a.n} random throws "
          f"(angle 20-60 deg, dist 1-3 m, height -0.2..0.2 m)")
    print(f"  one-time setup {setup * ms:.1f} ms, first plan {first * ms:.2f} ms "
          f"({a.warmup} warm-up plans not counted)")
    print(f"  p50 {p50 * ms:.2f} ms   p99 {p99 * ms:.2f} ms   mean {lat.mean() * ms:.2f} ms   "
          f"max {lat.max() * ms:.2f} ms")
    c50, c99 = np.percentile(cpu, [50, 99])
    print(f"  CPU time of the planning process (less sensitive to other load on the machine): "
          f"p50 {c50 * ms:.2f} ms   p99 {c99 * ms:.2f} ms")
    if hasattr(os, "getloadavg"):
        print(f"  load average at the end: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs "
              "(other processes stretch the wall-clock numbers)")
    print(f"  budget {BUDGET_S * ms:.0f} ms (420 ms flight - 300 ms actuation - 25 ms signal): "
          f"p50 {p50 / BUDGET_S:.1%}, p99 {p99 / BUDGET_S:.1%} of it; target p99 <= 5 ms: "
          f"{'met' if p99 <= 0.005 else 'NOT met'}")
    print(f"  feasible {feasible}/{a.n}; reasons: "
          + (", ".join(f"{k} x{v}" for k, v in reasons.most_common()) or "none"))
    return 0


if __name__ == "__main__":
    sys.exit(main())

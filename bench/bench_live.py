"""Live catch benchmark (not a test): simulated throws fed to ``CatchSession`` one
observation at a time.

Throws over the envelope -- angle U(20, 60) deg, distance U(1, 2.5) m, height U(-0.2,
0.2) m, a tennis ball with drag (the true flight: ``predict_throw(..., drag=True)``) --
observed from t = 1 / rate with Gaussian noise of 2, 5 and 10 mm per axis at 100 and
500 Hz; the session fits with drag. The 25 ms delay is the session's ``SIGNAL_S``: an
observation seen at t acts on the rows from t + 25 ms + the 5 ms planning budget.

Catch rate: the written trajectory judged by the independent check (``check_trajectory``)
against the TRUE ball (its end marker's estimate replaced by the true flight): the true
ball within 15 mm of the palm at the planned intercept, no fingertip inside it before,
the grasp in time and held, the stopping and holding forces within every motor. Shown
over every throw and over those the planner calls feasible from the true flight (the
others are out of the hand's strength whatever the camera sees). Latency: from an
observation to its new rows (``CatchSession.latencies_s``), after the set-up (hand, IK,
closing table, one warm-up session), p50 and p99.

    /work/.venv/bin/python bench/bench_live.py [--n 20] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.catch.flight import get_ball, predict_throw
from planner.catch.plan import get_planner, plan_throw
from planner.catch.session import CatchSession
from planner.check import check_trajectory
from planner.trajfile import parse_trajectory

NOISES_M = (0.002, 0.005, 0.010)
RATES_HZ = (100.0, 500.0)


def run_throw(pl, ball, angle, dist, height, noise_m, rate_hz, rng):
    """One throw: (caught against the true ball, latencies (s), outcome)."""
    fl = predict_throw(angle, dist, height, ball, drag=True)
    s = CatchSession(dist, height, ball=ball, drag=True, rate_hz=100.0, planner=pl)
    for k in range(1, int(3.0 * rate_hz)):
        t = k / rate_hz
        s.observe(t, fl.position(t) + rng.normal(0.0, noise_m, 3))
        if s.done:
            break
    if not s.done:
        s.finish()
    head, _ = s.text.rstrip("\n").rsplit("\n", 1)
    end = parse_trajectory(s.text).end
    end = dict(end, ball=fl.to_metadata())  # judged against the true ball
    rep = check_trajectory(parse_trajectory(head + "\n# " + json.dumps(end) + "\n"))
    return rep.ok, s.latencies_s, s.outcome, rep.problems


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20, help="throws per noise level and rate")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    pl = get_planner("default")
    ball = get_ball("tennis")
    pl.closing(ball.radius_m)
    rng = np.random.default_rng(a.seed)
    run_throw(pl, ball, 30.0, 1.5, 0.0, 0.005, 100.0, rng)  # warm-up
    setup = time.perf_counter() - t0
    throws = np.column_stack([rng.uniform(20, 60, a.n), rng.uniform(1.0, 2.5, a.n),
                              rng.uniform(-0.2, 0.2, a.n)])
    feasible = np.array([plan_throw(*th, planner=pl, ball=ball, drag=True).feasible
                         for th in throws])
    print(f"live catch, hand default, tennis ball with drag, {a.n} throws (angle 20-60 deg, "
          f"dist 1-2.5 m, height -0.2..0.2 m; {feasible.sum()} feasible from the true flight); "
          f"set-up {setup:.2f} s")
    all_lat = []
    for rate in RATES_HZ:
        for noise in NOISES_M:
            ok, lat, fails = [], [], {}
            for th in throws:
                caught, ls, outcome, problems = run_throw(pl, ball, *th, noise, rate, rng)
                ok.append(caught)
                lat.extend(ls)
                if not caught:
                    key = problems[0].split(":")[0][:50] if problems else outcome
                    fails[key] = fails.get(key, 0) + 1
            ok = np.array(ok)
            lat = np.array(lat)
            all_lat.append(lat)
            p50, p99 = np.percentile(lat, [50, 99]) * 1000
            rate_f = ok[feasible].mean() if feasible.any() else float("nan")
            print(f"  {rate:4.0f} Hz, noise {1000 * noise:4.1f} mm: caught {ok.sum():3d}/{a.n} "
                  f"({ok.mean():.0%}; of the feasible {rate_f:.0%}); latency p50 {p50:.2f} ms, "
                  f"p99 {p99:.2f} ms over {lat.size} observations"
                  + (f"; misses: {fails}" if fails else ""))
    lat = np.concatenate(all_lat)
    p50, p99 = np.percentile(lat, [50, 99]) * 1000
    print(f"  all: latency p50 {p50:.2f} ms, p99 {p99:.2f} ms (target p99 <= 2 ms: "
          f"{'met' if p99 <= 2.0 else 'NOT met'})")
    if hasattr(os, "getloadavg"):
        print(f"  load average at the end: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    return 0


if __name__ == "__main__":
    sys.exit(main())

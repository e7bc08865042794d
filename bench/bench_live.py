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
observation to its new rows (``CatchSession.latencies_s``, wall clock), after the set-up
(hand, IK, closing table, one warm-up session), p50 and p99; beside it the CPU time of
the same span (``CatchSession.cpu_s``: the latency less the time the machine gave other
processes; sessions without it show none).

``--against DIR`` also runs every configuration with the planner of another checkout
(``git worktree add DIR REV``), in a child process (``PYTHONPATH=DIR``, that checkout's
own ``bench/bench_live.py --worker``: its planner with the loop it has) right before this
one's, on the same throws and the same noise: before and after side by side under the
same load.

``--physics``: the physics judge beside the kinematic verdict -- every live catch replayed
in MuJoCo (``simulate``; the TRUE ball in the file's metadata and end marker), held with
every motor within its torque; per configuration: the session's own "held", the check's
verdict against the true ball, held in physics, and the throws the check calls caught that
the physics drops.

    python bench/bench_live.py [--n 20] [--seed 0] [--against DIR] [--physics]
                               [--rates 100,500] [--noises-mm 2,5,10]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
NOISES_M = (0.002, 0.005, 0.010)
RATES_HZ = (100.0, 500.0)
CODE_ENV = "BENCH_LIVE_CODE"  # a worker's checkout (its planner)


def throws_of(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(20, 60, n), rng.uniform(1.0, 2.5, n),
                            rng.uniform(-0.2, 0.2, n)])


def true_ball_text(text: str, flight) -> str:
    """A live file's text with the TRUE ball in its metadata and as its end marker's
    estimate (the intercept time the session's last estimate): what the kinematic check
    and the physics judge the rows against."""
    lines = text.rstrip("\n").split("\n")
    meta, end = json.loads(lines[0][2:]), json.loads(lines[-1][2:])
    meta["ball"] = end["ball"] = flight.to_metadata()
    meta["intercept_t"] = end["intercept_t"]
    return "\n".join(["# " + json.dumps(meta), *lines[1:-1], "# " + json.dumps(end)]) + "\n"


def physics_verdict(text: str) -> tuple[bool, str]:
    """The physics judge: the file replayed in MuJoCo (``simulate``): held with every motor
    within its torque, and the first problem otherwise."""
    from planner.simulate import simulate_trajectory
    from planner.trajfile import parse_trajectory

    rep = simulate_trajectory(parse_trajectory(text))
    return not rep.problems, (rep.problems[0][:60] if rep.problems else "")


SOFT = {"soft_stop": True}  # --still-palm: the palm waiting at rest (``soft_stop=False``)


def run_throw(pl, ball, angle, dist, height, noise_m, rate_hz, rng, physics=False):
    """One throw: (caught against the true ball, wall latencies (s), CPU times (s) or
    None, outcome, the check's problems, the physics' verdict (None without ``physics``))."""
    from planner.catch.flight.camera import observe_throw
    from planner.catch.flight.path import predict_throw
    from planner.catch.live.session import CatchSession
    from planner.check import check_trajectory
    from planner.trajfile import parse_trajectory

    fl = predict_throw(angle, dist, height, ball, drag=True)
    s = observe_throw(CatchSession(dist, height, ball=ball, drag=True, rate_hz=100.0,
                                   planner=pl, **({} if SOFT["soft_stop"]
                                                  else {"soft_stop": False})),
                      fl, noise_m, rate_hz, rng, until_s=3.0)
    head, _ = s.text.rstrip("\n").rsplit("\n", 1)
    end = parse_trajectory(s.text).end
    end = dict(end, ball=fl.to_metadata())  # judged against the true ball
    rep = check_trajectory(parse_trajectory(head + "\n# " + json.dumps(end) + "\n"))
    phys = physics_verdict(true_ball_text(s.text, fl)) if physics else None
    return rep.ok, s.latencies_s, getattr(s, "cpu_s", None), s.outcome, rep.problems, phys


def run_config(pl, ball, throws, rate, noise, seed, physics=False) -> dict:
    """Every throw at one rate and noise level (its noise from its own seed)."""
    rng = np.random.default_rng([seed, int(rate), round(noise * 1e4)])
    ok, lat, cpu, fails, phys, outcomes = [], [], [], {}, [], []
    for th in throws:
        caught, ls, cs, outcome, problems, ph = run_throw(pl, ball, *th, noise, rate, rng,
                                                          physics)
        ok.append(bool(caught))
        outcomes.append(outcome)
        if ph is not None:
            phys.append(ph)
        lat.extend(ls)
        cpu.extend(cs or [])
        if not caught:
            key = problems[0].split(":")[0][:50] if problems else outcome
            fails[key] = fails.get(key, 0) + 1
    return {"ok": ok, "lat": lat, "cpu": cpu, "fails": fails, "phys": phys,
            "outcomes": outcomes}


def setup():
    from planner.catch.flight.path import get_ball
    from planner.catch.plan.api import get_planner

    t0 = time.perf_counter()
    pl = get_planner("default")
    ball = get_ball("tennis")
    pl.closing(ball.radius_m)
    run_throw(pl, ball, 30.0, 1.5, 0.0, 0.005, 100.0, np.random.default_rng(0))  # warm-up
    return pl, ball, time.perf_counter() - t0


def worker(n: int, seed: int, rate: float, noise: float) -> None:
    pl, ball, _ = setup()
    sys.stdout.write(json.dumps(run_config(pl, ball, throws_of(n, seed), rate, noise, seed)))


def run_against(tree: Path, a, rate: float, noise: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), **{CODE_ENV: str(tree)})
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    out = subprocess.run([sys.executable, str(tree / "bench" / "bench_live.py"), "--n", str(a.n),
                          "--seed", str(a.seed), "--worker", f"{rate},{noise}"],
                         cwd=tree, env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def line(label: str, r: dict, feasible: np.ndarray) -> str:
    ok, lat, cpu = np.array(r["ok"]), np.array(r["lat"]), np.array(r["cpu"])
    p50, p99 = np.percentile(lat, [50, 99]) * 1000
    c = (f", CPU p50 {np.percentile(cpu, 50) * 1000:.2f} p99 {np.percentile(cpu, 99) * 1000:.2f}"
         if cpu.size else "")
    rate_f = ok[feasible].mean() if feasible.any() else float("nan")
    return (f"{label}caught {ok.sum():3d}/{ok.size} ({ok.mean():.0%}; of the feasible "
            f"{rate_f:.0%}); latency p50 {p50:.2f} ms, p99 {p99:.2f} ms{c} over {lat.size} "
            "observations" + (f"; misses: {r['fails']}" if r["fails"] else "")
            + physics_line(r))


def physics_line(r: dict) -> str:
    """The physics judge beside the kinematic verdict: held in physics, the session's own
    "held", and the throws the check calls caught that the physics drops."""
    if not r.get("phys"):
        return ""
    held = np.array([h for h, _ in r["phys"]])
    said = np.array([o == "held" for o in r["outcomes"]])
    ok = np.array(r["ok"])
    why: dict[str, int] = {}
    for h, w in r["phys"]:
        if not h:
            key = w.split(":")[0][:40]
            why[key] = why.get(key, 0) + 1
    return (f"\n      session says held {said.sum()}/{said.size}, check (true ball) "
            f"{ok.sum()}/{ok.size}, physics held {held.sum()}/{held.size}; check OK but "
            f"physics drops: {int((ok & ~held).sum())}" + (f"; physics: {why}" if why else ""))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20, help="throws per noise level and rate")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--against", type=Path, default=None, metavar="DIR",
                    help="also run the planner of this checkout, configuration by configuration")
    ap.add_argument("--physics", action="store_true",
                    help="also replay every live catch in MuJoCo (simulate): the physics judge")
    ap.add_argument("--still-palm", action="store_true",
                    help="the palm waiting at rest (CatchSession(soft_stop=False)), the live "
                         "catch before the soft stop")
    ap.add_argument("--rates", default=None, help="e.g. 100 (default: 100,500)")
    ap.add_argument("--noises-mm", default=None, help="e.g. 5 (default: 2,5,10)")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)  # RATE,NOISE: one config
    a = ap.parse_args(argv)
    sys.path.insert(0, os.environ.get(CODE_ENV, str(ROOT)))
    SOFT["soft_stop"] = not a.still_palm
    if a.worker:
        rate, noise = (float(x) for x in a.worker.split(","))
        worker(a.n, a.seed, rate, noise)
        return 0
    from planner.catch.plan.api import plan_throw

    pl, ball, set_up = setup()
    throws = throws_of(a.n, a.seed)
    feasible = np.array([plan_throw(*th, planner=pl, ball=ball, drag=True).feasible
                         for th in throws])
    print(f"live catch, hand default, tennis ball with drag, {a.n} throws (angle 20-60 deg, "
          f"dist 1-2.5 m, height -0.2..0.2 m; {feasible.sum()} feasible from the true flight); "
          f"set-up {set_up:.2f} s" + (f"; before: {a.against}" if a.against else ""))
    all_lat, all_cpu, before, before_cpu = [], [], [], []
    rates = RATES_HZ if a.rates is None else tuple(float(x) for x in a.rates.split(","))
    noises = NOISES_M if a.noises_mm is None else tuple(float(x) / 1000
                                                        for x in a.noises_mm.split(","))
    for rate in rates:
        for noise in noises:
            head = f"  {rate:4.0f} Hz, noise {1000 * noise:4.1f} mm: "
            if a.against:
                b = run_against(a.against.resolve(), a, rate, noise)
                before.append(b["lat"])
                before_cpu.append(b["cpu"])
                print(line(head + "before ", b, feasible))
                head = " " * len(head) + "after  "
            r = run_config(pl, ball, throws, rate, noise, a.seed, a.physics)
            all_lat.append(r["lat"])
            all_cpu.append(r["cpu"])
            print(line(head, r, feasible))
    lat, cpu = np.concatenate(all_lat), np.concatenate(all_cpu)
    p50, p99 = np.percentile(lat, [50, 99]) * 1000
    if before:
        b50, b99 = np.percentile(np.concatenate(before), [50, 99]) * 1000
        bc = np.concatenate(before_cpu)
        bcpu = (f" (CPU p50 {np.percentile(bc, 50) * 1000:.2f}, p99 "
                f"{np.percentile(bc, 99) * 1000:.2f})" if bc.size else "")
        print(f"  all, before: latency p50 {b50:.2f} ms, p99 {b99:.2f} ms{bcpu}")
    c50, c99 = np.percentile(cpu, [50, 99]) * 1000 if cpu.size else (np.nan, np.nan)
    print(f"  all: latency p50 {p50:.2f} ms, p99 {p99:.2f} ms (CPU p50 {c50:.2f}, p99 "
          f"{c99:.2f}); target p99 <= 2 ms: {'met' if p99 <= 2.0 else 'NOT met'}")
    if hasattr(os, "getloadavg"):
        print(f"  load average at the end: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    return 0


if __name__ == "__main__":
    sys.exit(main())

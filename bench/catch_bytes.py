"""The catch's bytes (not a test): every file of the wide grid (angles 15-75 deg step 10 x
distances 0.5-4 m step 0.5 x heights -0.3/0/+0.3 m, planned) and of 30 live sessions (5
throws of ``bench_live.py``'s envelope, seed 0, at 100 and 500 Hz and 2, 5 and 10 mm of
noise, drag) written to DIR, with ``DIR/SHA256SUMS``: a refactoring that changes no plan
leaves every sum as it was (``sha256sum -c OLD/SHA256SUMS`` in the new DIR).

    python bench/catch_bytes.py DIR
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.catch import CatchSession, get_planner, plan_throw, write_plan
from planner.catch.flight.camera import observe_throw
from planner.catch.flight.path import get_ball, predict_throw
from planner.errors import InputError


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description="The catch's files and their sums, to compare "
                                 "two checkouts byte for byte.")
    ap.add_argument("dir", help="folder for the catch files and SHA256SUMS")
    out = Path(ap.parse_args(argv).dir)
    out.mkdir(parents=True, exist_ok=True)
    pl, ball = get_planner("default"), get_ball("tennis")
    for h in (-0.3, 0.0, 0.3):
        for a in range(15, 76, 10):
            for d in np.arange(0.5, 4.01, 0.5):
                try:
                    p = plan_throw(a, d, h, planner=pl, ball=ball)
                except InputError:  # no throw passes through that point
                    continue
                write_plan(p, str(out / f"grid_a{a}_d{d:.1f}_h{h:+.1f}.csv"))
    rng0 = np.random.default_rng(0)
    throws = np.column_stack([rng0.uniform(20, 60, 5), rng0.uniform(1.0, 2.5, 5),
                              rng0.uniform(-0.2, 0.2, 5)])
    for rate in (100.0, 500.0):
        for noise in (0.002, 0.005, 0.010):
            rng = np.random.default_rng([0, int(rate), round(noise * 1e4)])
            for i, (a, d, h) in enumerate(throws):
                fl = predict_throw(a, d, h, ball, drag=True)
                s = observe_throw(CatchSession(d, h, ball=ball, drag=True, rate_hz=100.0,
                                               planner=pl), fl, noise, rate, rng, until_s=3.0)
                (out / f"live_{rate:.0f}_{noise * 1000:.0f}_{i}.csv").write_text(s.text)
    sums = [f"{hashlib.sha256(f.read_bytes()).hexdigest()}  {f.name}\n"
            for f in sorted(out.glob("*.csv"))]
    (out / "SHA256SUMS").write_text("".join(sums))
    print(f"{len(sums)} files -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

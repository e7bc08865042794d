"""planner.catch.flight.tablesums: sums over observations of a drag table's values, kept per
table interval, against the same sums taken observation by observation."""

from __future__ import annotations

import numpy as np
import pytest

from planner.catch.flight.path import BALLS, Flight, predict_throw
from planner.catch.flight.tablesums import IntervalSums

BALL = BALLS["tennis"]


@pytest.mark.parametrize("step_s", [0.01, 0.04])
def test_interval_sums_are_the_sums_over_the_observations(step_s):
    rng = np.random.default_rng(1)
    ts = np.sort(rng.uniform(0.0, 0.7, 301))
    ps = rng.normal(0.0, 1.0, (ts.size, 3))
    sums = IntervalSums(step_s)
    for t, p in zip(ts.tolist(), ps):
        sums.add(t, p)
    # any flight of that step (not the one the observations came from)
    f = Flight(np.array([0.2, 0.1, -0.3]), np.array([4.0, -1.0, 3.0]), BALL, BALL.drag_per_m,
               step_s=step_s)
    got = sums.sums(f.nodes(float(ts[-1])))
    m = f.position(ts) - f.p0  # (ex s, ey s, z)
    s = m[:, 0] / f.nodes(float(ts[-1])).direction[0]
    z = m[:, 2]
    want = {"s": s.sum(), "ts": ts @ s, "pxs": ps[:, 0] @ s, "pys": ps[:, 1] @ s,
            "ss": s @ s, "z": z.sum(), "tz": ts @ z, "pzz": ps[:, 2] @ z, "zz": z @ z}
    for k, v in want.items():
        assert getattr(got, k) == pytest.approx(v, rel=1e-12, abs=1e-12), k


def test_sums_grow_with_the_observations_and_the_table():
    """Observations past the first allocation; a table grown after they were added."""
    sums = IntervalSums(0.01)
    f = predict_throw(20.0, 4.0, ball=BALL, drag=True)
    ts = np.arange(1, 120) / 100.0  # 1.2 s: past the 32 intervals first allocated
    for t in ts.tolist():
        sums.add(t, f.position(t))
    assert sums.n_int > 100  # (grown from 32)
    got = sums.sums(f.nodes(float(ts[-1])))
    s = (f.position(ts) - f.p0)[:, 0] / f.nodes(1.2).direction[0]
    assert got.s == pytest.approx(s.sum(), rel=1e-12)
    assert got.ss == pytest.approx(s @ s, rel=1e-12)

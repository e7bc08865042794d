"""A simulated camera for a live catch: a known flight observed at a fixed rate with
Gaussian noise, fed to a ``CatchSession`` one observation at a time (the loop of
``bench/bench_live.py`` and of the live tests: one definition)."""

from __future__ import annotations

import numpy as np

from planner.catch.flight.path import Flight


def observe_throw(session, flight: Flight, noise_m: float, rate_hz: float,
                  rng: np.random.Generator, until_s: float = 3.0):
    """Feed ``session`` the ball of ``flight`` seen at t = k / ``rate_hz`` (k = 1, 2, ...,
    t < ``until_s``), each position with N(0, ``noise_m``) per axis from ``rng``, until
    the session ends; ``finish`` it if the observations end first. Returns the session."""
    for k in range(1, int(until_s * rate_hz)):
        t = k / rate_hz
        session.observe(t, flight.position(t) + rng.normal(0.0, noise_m, 3))
        if session.done:
            return session
    session.finish()
    return session

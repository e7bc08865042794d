"""The live session's intercept of each newest flight (``session.CatchSession``, step 2):
where to search it, and how often.

* Before the first fit: the intercept of the flight fitted to the observations before it
  (``LiveFit.first_look``), searched along the whole path (``look``); the first fit's
  search starts from it when it is a pose (in reach), so that no observation carries
  the whole search together with the first plan.
* After: ``find_intercept_near`` from the last intercept (``NEAR_S`` around its time).
* An estimate out of reach is searched again along the whole path (~0.4 ms) only once
  per ``REACH_RETRY_S`` of camera time (the cadence, ``LiveSearch.searched_s``); in
  between the out-of-reach intercept is kept (``CatchPlanner.meet`` refines its time on
  the new flight).
"""

from __future__ import annotations

import math

import numpy as np

from planner.catch.flight.path import Flight
from planner.catch.plan.intercept import (
    SEARCH_AFTER_S,
    Intercept,
    Wrist,
    closest_time,
    find_intercept,
    find_intercept_near,
)
from planner.errors import InfeasibleError

NEAR_S = 0.020  # the intercept is searched this close to the previous one first (an
# observation moves it by a few ms: sigma_t of a 5 mm camera late in the flight is ~1 ms)
REACH_RETRY_S = 0.010  # an estimate out of reach is searched again along the whole path
# (~0.4 ms) after this much camera time, not at every observation: the cadence of a 100 Hz
# camera, the slowest the session is for, at which it meets the catch target (bench_live:
# 19-20 of 20 at 2-10 mm noise); a 500 Hz camera's estimate coming back in reach is then
# acted on at most 8 ms later than at once, within the signal delay's 25 ms

TILT_STEPS = 3  # where the tilted palm faces no pose (its deviation beyond the joint's
# range), the largest share of the tilt that does, to 1/8 of it by bisection (0.6-1.3 deg
# of the table's 5-10 deg): the pose then moves with the estimate continuously. The
# untilted palm instead moved the arm's target by the whole tilt whenever the estimates'
# noise took the tilted pose in and out of the deviation's range; the re-aims fell behind
# and the soft stop was given up for a palm at rest off the ball (bench_live 500 Hz / 5 mm,
# 2 of 20 throws)


class LiveSearch:
    """The intercepts of one live throw at the catch point ``C`` (m) for a ball of
    ``radius_m``: ``look`` before the first fit, ``next`` for every fitted flight."""

    def __init__(self, wrist: Wrist, C: np.ndarray, radius_m: float) -> None:
        self.wrist, self.C, self.radius_m = wrist, C, radius_m
        self.prior: Intercept | None = None  # the first look's intercept, when in reach
        self.searched_s = -math.inf  # the last whole-path search from out of reach
        self.tilt = 0.0  # the palm's tilt from facing the ball (rad; ``live.stop.TiltTable``)

    def look(self, flight: Flight | None) -> None:
        """The first look's intercept (the observation before the first fit)."""
        prior = self.search(flight)
        self.prior = prior if prior is not None and prior.reason is None else None

    def next(self, flight: Flight, t_s: float, prev: Intercept | None,
             t_i: float | None) -> Intercept:
        """The intercept of ``flight`` (observed up to ``t_s``) warm-started from ``prev``,
        the last re-plan's (its time ``t_i``; None: the first fit's). The tilted search
        and its untilted retry share the path's samples and the position-only fallback
        (``find_intercept``'s ``memo``: the same flight)."""
        memo: dict = {}
        if self.tilt and prev is not None and prev.reason is None and not prev.aligned:
            prev = None  # a tilted palm's crossing may lie beyond the near window of the
            # position-only intercept: searched along the whole path (as a first fit's)
            self.prior = None
        ic = self._next(flight, t_s, prev, t_i, memo)
        if self.tilt and (ic.reason is not None or not ic.aligned):  # the tilted palm
            tilt, self.tilt = self.tilt, 0.0  # faces no pose: the untilted one (as the
            ic = self._next(flight, t_s, prev, t_i, memo)  # planned catch's tilt search),
            if ic.reason is None and ic.aligned:  # or the palm tilted as far as one faces
                lo, hi = 0.0, 1.0  # a pose (``TILT_STEPS``)
                for _ in range(TILT_STEPS):
                    self.tilt = 0.5 * (lo + hi) * tilt
                    part = self._next(flight, t_s, prev, t_i, memo)
                    if part.reason is None and part.aligned:
                        lo, ic = 0.5 * (lo + hi), part
                    else:
                        hi = 0.5 * (lo + hi)
            self.tilt = tilt
        return ic

    def _next(self, flight: Flight, t_s: float, prev: Intercept | None,
              t_i: float | None, memo: dict | None = None) -> Intercept:
        """``next`` at the tilt ``self.tilt``."""
        if prev is None:
            if self.prior is not None:
                return find_intercept_near(self.wrist, flight, self.C, self.radius_m,
                                           self.prior, self.prior.t, NEAR_S, self.tilt, memo)
            return self.search(flight, memo)
        if prev.reason is not None and t_s < self.searched_s + REACH_RETRY_S - 1e-9:
            flight.integrate_to(t_i + NEAR_S)
            return prev
        # the drag table integrated once, as far as it is needed (from an intercept out of
        # reach, the whole-path search's span)
        flight.integrate_to(t_i + (SEARCH_AFTER_S if prev.reason else NEAR_S))
        ic = find_intercept_near(self.wrist, flight, self.C, self.radius_m, prev, t_i, NEAR_S,
                                 self.tilt, memo)
        if ic.reason is not None:  # (out of reach: the whole path was searched)
            self.searched_s = t_s
        return ic

    def search(self, flight: Flight | None, memo: dict | None = None) -> Intercept | None:
        """The intercept searched along the whole of ``flight`` near the catch point (the
        first look's, or the first fit's without one)."""
        if flight is None:
            return None
        try:
            t_c = float(flight.time_at_x(float(self.C[0])))
        except InfeasibleError:
            t_c = closest_time(flight, self.C)
        return find_intercept(self.wrist, flight, self.C, self.radius_m, t_c, self.tilt, memo)

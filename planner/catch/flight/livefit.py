"""The running fit of a ball's flight to camera observations that arrive one at a time
(``catch --live``): after each, the least-squares state (p0, v0) at t = 0 and its
covariance, in O(1) for a vacuum and in one or two warm-started iterations with drag.

Vacuum (k = 0). The model p(t) = p0 + v0 t + g t^2 / 2 is linear in (p0, v0), so the
least squares of ``observe.fit_observations`` are kept as running sums: per axis the
normal equations M [p0; v0] = [sum y; sum t y] with y = p - g t^2 / 2 and M =
[[N, sum t], [sum t, sum t^2]] (the same M for the three axes). Adding an observation
adds to the sums; the solution is a 2x2 solve. The residual sum of squares comes from
the sums too (sum y^2 - [p0 v0] . [sum y; sum t y]), the noise per axis is sigma^2 =
RSS / (N - 2) and the covariance of (p0, v0) along each axis is sigma^2 M^-1: the
numbers ``fit_observations`` gives for the same observations.

Drag (k > 0, the ball's own k). The drag flight differs from the vacuum one with the
same (p0, v0) by a displacement d(t; p0, v0) = p_drag - p_vac that is small (k |v| t:
about 4 % of the drop for a tennis ball's 0.4 s flight) and slowly varying in the
state, so the fit is the fixed point p0, v0 = LSQ_vacuum(y - d(t; p0, v0)): a chord
iteration (the vacuum's normal matrix for the drag model's), contracting by about
k |v| t per step. Its fixed point solves J_vac^T r = 0 instead of the drag model's
J^T r = 0 (``fit_observations``): the two differ by O(k |v| t) of the residuals'
projection (5 um on a 5 mm-noise tennis throw, tests/test_live.py). The first estimate
iterates from the vacuum fit (to ``CHORD_TOL_M``, at most ``MAX_CHORD_STEPS``): the first
fit's, or, in a session, ``first_look``'s on the observations before it; every later
observation (the first fit after a first look too) takes one step from the previous
estimate, on its flight (integrated already for the plan); the estimate lags the fixed point by the contraction factor times the last observation's
change. The covariance is the vacuum's sigma^2 M^-1 with sigma from the drag model's
residuals (the drag model's sensitivity to the state differs from the vacuum's by the
same O(k |v| t)).

Cost. A step needs sums over the N observations of the flight's drag part at their
times (sum d, sum t d) and, for the residuals, sum p d and sum d^2: kept per interval of
the flight's RK4 table (``tablesums.IntervalSums``: the Hermite weights of an
observation depend on its time only), a step costs a few array operations over the
table's ~30 intervals whatever N (500 Hz: up to ~500), and every other sum is a running
one. The tables take ``LIVE_STEP_FACTOR`` times the planner's RK4 step (error h^4:
4e-8 m), so a new flight integrates in ~15 steps.
"""

from __future__ import annotations

import math

import numpy as np

from planner.catch.flight.observe import FitResult
from planner.catch.flight.path import (
    G_M_S2,
    GRAVITY_M_S2,
    MAX_LAUNCH_SPEED_M_S,
    MAX_OBS_RANGE_M,
    MAX_TIME_S,
    Ball,
    Flight,
    step_for,
)
from planner.catch.flight.tablesums import IntervalSums
from planner.errors import InputError

# ``fit_observations``' minimum number of observations: 3 positions fix the 6 numbers of
# (p0, v0) (with one spare degree of freedom per axis for the noise); its drag fit asks
# for 6, and so does the live one
MIN_OBS_VACUUM = 3
MIN_OBS_DRAG = 6
CHORD_TOL_M = 1e-7  # drag: iterate until the fit moves the ball by less than this
# (0.1 um at the last observation: 20 000 times below a 2 mm camera noise)
MAX_CHORD_STEPS = 2  # ... or at most this many steps at the first estimate (contraction
# ~ k|v|t ~ 0.04: one step gains ~1.4 digits): after 2 a first fit's ball at the palm
# (t = 0.45 s) is 0.5 um or less from the fixed point (throws of 20-60 deg, 1-2.5 m, 6
# observations at 100 or 500 Hz, measured), where those 6 observations leave it
# centimetres uncertain. In a session the 2 steps are ``first_look``'s, on the 5
# observations before the first fit, which then takes one more step as every later one:
# it lags its fixed point by at most 2.3 mm at the catch point, 2.2 % (median 0.16 %) of
# that point's distance from the true ball (120 throws, 20-60 deg, 1-2.5 m, 2-10 mm at
# 100 and 500 Hz, measured)
LIVE_STEP_FACTOR = 4.0  # the fit's drag tables take 4x the planner's RK4 step
# (``flight.step_for``): the error goes as h^4, 256 x the planner's 1.5e-10 m, i.e.
# 4e-8 m in position and 1.5e-7 m/s in velocity over 1.5 s against a 1 ms-step
# reference for tennis-ball throws of 15-75 deg over 1-4 m (measured; tests/test_live.py
# holds it below 1e-6 m), five orders below a 2 mm camera's noise; the table of a
# re-fitted flight then costs a quarter of the integration


# the covariance's entries from minv (r, c) and the axis a: (a + 3 r, a + 3 c), in the
# order of minv's entries, then the axes
_COV_I = np.array([a + 3 * r for r in (0, 1) for c in (0, 1) for a in range(3)])
_COV_J = np.array([a + 3 * c for r in (0, 1) for c in (0, 1) for a in range(3)])


class LiveFit:
    """Observations so far and the flight fitted to them (``fit``), updated by ``add``."""

    def __init__(self, ball: Ball, drag_per_m: float) -> None:
        self.ball = ball
        self.k = float(drag_per_m)
        self.min_obs = MIN_OBS_DRAG if self.k > 0 else MIN_OBS_VACUUM
        self._t = np.empty(256)
        self._p = np.empty((256, 3))
        self.n = 0
        # the running sums, one array (an observation adds one row to it): N, sum t,
        # sum t^2, sum t^3; per axis sum y, sum t y, sum y^2, sum p^2
        self._acc = np.zeros(16)
        self._s = self._acc[0:3]  # N, sum t, sum t^2 (views of _acc)
        self._sy = self._acc[4:10].reshape(2, 3)  # sum y, sum t y
        self._syy = self._acc[10:13]  # sum y^2 (per axis)
        self._spp = self._acc[13:16]  # sum p^2 (per axis)
        self._table_sums: IntervalSums | None = None  # drag: from the first fit on
        self._theta: np.ndarray | None = None
        self._theta_flight: Flight | None = None  # the flight of _theta (integrated already)
        self._step_s: float | None = None
        self.flight: Flight | None = None
        self.result: FitResult | None = None

    @property
    def times(self) -> np.ndarray:
        return self._t[:self.n]

    @property
    def positions(self) -> np.ndarray:
        return self._p[:self.n]

    def check(self, t_s: float, p: np.ndarray) -> None:
        """InputError (one line) unless ``(t_s, p)`` can follow the observations so far:
        finite, 0 <= t <= MAX_TIME_S, after the previous one, within any throw's range."""
        px, py, pz = p.tolist()
        if not (math.isfinite(t_s) and math.isfinite(px) and math.isfinite(py)
                and math.isfinite(pz)):
            raise InputError("an observation must be finite (no NaN or inf)")
        if not 0.0 <= t_s <= MAX_TIME_S:
            raise InputError(f"t = {t_s:.6g} s is outside 0..{MAX_TIME_S:g} s (the ball leaves "
                             "at t = 0, catch frame)")
        if self.n and t_s <= self._t[self.n - 1]:
            raise InputError(f"t = {t_s:.6g} s is not after the previous observation's "
                             f"{self._t[self.n - 1]:.6g} s (times must increase)")
        far = max(abs(px), abs(py), abs(pz))
        if far > MAX_OBS_RANGE_M:
            raise InputError(f"the ball {far:.6g} m off the launch point along an axis, "
                             "farther than any throw reaches")

    def add(self, t_s: float, p: np.ndarray) -> FitResult | None:
        """Add one observation (``check``-ed) and refit; the fit once there are enough."""
        self.check(t_s, p)
        if self.n == len(self._t):
            self._t = np.concatenate([self._t, np.empty(len(self._t))])
            self._p = np.concatenate([self._p, np.empty((len(self._p), 3))])
        self._t[self.n] = t_s
        self._p[self.n] = p
        self.n += 1
        px, py, pz = p.tolist()
        t2 = t_s * t_s
        yz = pz + 0.5 * G_M_S2 * t2  # y = p - g t^2 / 2
        self._acc += (1.0, t_s, t2, t2 * t_s, px, py, yz, t_s * px, t_s * py, t_s * yz,
                      px * px, py * py, yz * yz, px * px, py * py, pz * pz)
        if self._table_sums is not None:
            self._table_sums.add(t_s, p)
        if self.n < self.min_obs:
            return None
        self.result = self._solve()
        self.flight = self.result.flight
        return self.result

    def first_look(self) -> Flight | None:
        """The flight from the observations before the first fit (``min_obs`` - 1 of
        them), for the first plan's intercept search to start from. Drag: the chord from
        their vacuum fit (``MAX_CHORD_STEPS`` steps, as a first fit), kept as the first
        fit's start: that fit then takes one step, as every later one (``_chord``), so no
        observation carries both the first fit's iteration and the first plan. Vacuum: the
        vacuum fit. None before ``MIN_OBS_VACUUM`` observations, or when they move faster
        than any throw (the fit says why)."""
        vac = self.vacuum_flight()
        if vac is None or self.k == 0.0 or self._theta is not None:
            return vac
        if float(np.linalg.norm(vac.v0)) > MAX_LAUNCH_SPEED_M_S:
            return None
        minv = self._minv()
        theta, _ = self._chord(minv, minv @ self._sy)
        self._theta, self._theta_flight = theta, self._flight(theta)
        return self._theta_flight

    def vacuum_flight(self) -> Flight | None:
        """The vacuum least squares of the observations so far (O(1), from the running
        sums), or None before ``MIN_OBS_VACUUM`` of them: a first look at the flight while a
        drag fit still waits for its ``MIN_OBS_DRAG``."""
        if self.n < MIN_OBS_VACUUM:
            return None
        theta = self._minv() @ self._sy
        return Flight(theta[0], theta[1], self.ball, 0.0)

    def _minv(self) -> np.ndarray:
        n, s1, s2 = self._s
        det = n * s2 - s1 * s1
        if not det > 1e-18 * max(n * s2, 1e-300):
            raise InputError("the observations' times do not spread enough to fit a flight")
        return np.array([[s2, -s1], [-s1, n]]) / det

    def _solve(self) -> FitResult:
        minv = self._minv()
        n = self.n
        theta = minv @ self._sy  # (2, 3): p0, v0
        if self.k > 0.0:
            theta, rss = self._chord(minv, theta)
        else:
            rss = np.maximum(self._syy - np.sum(theta * self._sy, axis=0), 0.0)
        speed = float(np.linalg.norm(theta[1]))
        if speed > MAX_LAUNCH_SPEED_M_S:
            raise InputError(f"the observations move at {speed:.4g} m/s at t = 0, faster than "
                             f"any throw (at most {MAX_LAUNCH_SPEED_M_S:g} m/s)")
        self._theta = theta
        sigma = np.sqrt(rss / max(n - 2, 1))
        cov = np.zeros((6, 6))  # per axis a: sigma_a^2 minv at (a, a), (a, 3 + a),
        # (3 + a, a), (3 + a, 3 + a); zero across axes
        cov[_COV_I, _COV_J] = (minv.reshape(4, 1) * (sigma * sigma)).ravel()
        cov.setflags(write=False)
        sigma.setflags(write=False)
        flight = self._theta_flight = self._flight(theta)
        return FitResult(flight, cov, float(math.sqrt(float(rss.sum()) / (3 * n))), sigma, n)

    def _flight(self, theta: np.ndarray) -> Flight:
        if self.k == 0.0:
            return Flight(theta[0], theta[1], self.ball, 0.0)
        if self._step_s is None:  # the table's step from the first fit's speed, then kept
            self._step_s = LIVE_STEP_FACTOR * step_for(self.k, float(np.linalg.norm(theta[1])))
        return Flight(theta[0], theta[1], self.ball, self.k, step_s=self._step_s)

    def _chord(self, minv: np.ndarray, theta_vac: np.ndarray):
        """The drag fit: (p0, v0) = LSQ_vacuum(y - d), d the drag displacement of the
        current estimate at the observations. The first one (``first_look``'s, or the first
        fit's without it) iterates from the vacuum fit until the ball moves by less than
        ``CHORD_TOL_M`` (at most ``MAX_CHORD_STEPS`` steps); later ones take one step from
        the previous estimate, on its flight (already integrated). Every sum over the observations
        of the flight's table comes from ``IntervalSums`` (module docstring). Returns the
        new (p0, v0) and the residual sum of squares per axis against the model of the last
        step."""
        first = self._theta is None
        theta = theta_vac if first else self._theta
        if self._table_sums is None:
            self._flight(theta_vac)  # (fixes the table's step)
            self._table_sums = IntervalSums(self._step_s)
            for t, p in zip(self.times.tolist(), self.positions):
                self._table_sums.add(t, p)
        t_last = float(self._t[self.n - 1])
        for i in range(MAX_CHORD_STEPS if first else 1):
            flight = self._theta_flight if not first and i == 0 else self._flight(theta)
            v_old = theta[1]
            m, m_t, pm, mm = self._table_moments(flight, t_last)
            # sum of d and t d: d = m - v0 t - g t^2 / 2 (p0 cancels)
            n, s1, s2 = self._s
            d_sum = m - v_old * s1 - 0.5 * GRAVITY_M_S2 * s2
            td_sum = m_t - v_old * s2 - 0.5 * GRAVITY_M_S2 * self._acc[3]
            new = minv @ (self._sy - np.stack([d_sum, td_sum]))
            moved = float(np.max(np.abs((new[0] - theta[0]) + (new[1] - theta[1]) * t_last)))
            theta = new
            if moved < CHORD_TOL_M:
                break
        # residual p - (p0 + v0 t + g t^2 / 2 + d) = p - p0 - (v0 - v_old) t - m, squared
        n, s1, s2 = self._s
        c, e = theta[0], theta[1] - v_old
        sp = self._sy[0] + 0.5 * GRAVITY_M_S2 * s2
        stp = self._sy[1] + 0.5 * GRAVITY_M_S2 * self._acc[3]
        rss = (self._spp - 2 * c * sp - 2 * e * stp + c * c * n + 2 * c * e * s1 + e * e * s2
               - 2 * (pm - c * m - e * m_t) + mm)
        return theta, np.maximum(rss, 0.0)

    def _table_moments(self, flight: Flight, t_last: float):
        """The drag part m = (ex s, ey s, z) of ``flight`` (its position less p0) summed
        over the observations, per axis: sum m, sum t m, sum p m, sum m^2."""
        nodes = flight.nodes(t_last)
        S = self._table_sums.sums(nodes)
        ex, ey = nodes.direction
        return (np.array([ex * S.s, ey * S.s, S.z]), np.array([ex * S.ts, ey * S.ts, S.tz]),
                np.array([ex * S.pxs, ey * S.pys, S.pzz]),
                np.array([ex * ex * S.ss, ey * ey * S.ss, S.zz]))

    def sigma_at(self, t_s: float) -> np.ndarray:
        """1-sigma of the fitted ball's position at ``t_s`` per axis (m), from the
        covariance: var = var(p0) + 2 t cov(p0, v0) + t^2 var(v0)."""
        cov = self.result.covariance
        var = np.array([cov[a, a] + 2 * t_s * cov[a, 3 + a] + t_s * t_s * cov[3 + a, 3 + a]
                        for a in range(3)])
        return np.sqrt(np.maximum(var, 0.0))

    def intercept_sigma(self, flight, t_i: float) -> dict[str, float]:
        """The intercept's 1-sigma from the fit (``sigma_at``) on ``flight`` at ``t_i``:
        across the path at the palm, and in time along it (sigma_x / |v_x|)."""
        sig = self.sigma_at(t_i)
        vx = abs(float(flight.velocity(t_i)[0]))
        return {"x_plane_m": float(flight.position(t_i)[0]), "t_s": float(t_i),
                "sigma_t_s": float(sig[0] / vx) if vx > 0 else math.inf,
                "sigma_y_m": float(sig[1]), "sigma_z_m": float(sig[2])}

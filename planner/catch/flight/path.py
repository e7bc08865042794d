"""Ball flight for the catch planner: throws in a vacuum and with drag (fitting a flight to
camera observations: ``planner.catch.flight.observe``).

Catch frame (spec section 5): origin at the ball's launch point, +x horizontal
towards the hand, z up. The ball leaves at t = 0 in the x-z plane at ``angle``
degrees above horizontal. In flight its acceleration is::

    a = g - k |v| v,   g = (0, 0, -9.81) m/s^2,   k = 0.5 rho_air Cd A / m  [1/m]

with rho_air = 1.204 kg/m^3 (dry air, 20 degC, sea level) and k = 0 in a vacuum.

Vacuum flights are closed form. Drag flights are integrated once (``dragtable``) with a
fixed-step RK4 into a table of nodes (position and velocity along the flight);
``position`` and ``velocity`` interpolate the table with cubic Hermite
polynomials (positions with the stored velocities, velocities with the stored
accelerations), so an evaluation costs a few numpy operations. The table grows
on demand when a time outside it is asked for.

Because the acceleration only has components along v and along z, the
horizontal direction of the velocity never changes: a flight is a planar
problem in (s, z), s the horizontal distance travelled along the launch
direction. The table stores (s, z, ds/dt, dz/dt).

Step of the table: ``min(10 ms, 0.005 / (k * max(v, sqrt(g/k))))`` with v the
launch speed (for ``predict_throw``, the vacuum speed of the throw). Against
DOP853 at rtol 1e-13 the interpolated positions are within ~1e-10 m for
hand-speed throws (4-12 m/s) and ~5e-8 m for a tennis ball at 70-95 m/s;
tests/test_flight.py holds it to 1e-6 m. ``predict_throw(drag=True)`` shoots on
the launch speed with these same steps (secant from the vacuum speed, brentq as
a fallback) and hands its last run to the Flight as its table, so a drag throw
costs 4-6 integrations of the flight (~0.3-0.5 ms for a 1-3 m throw).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.balls import BALLS, RHO_AIR, Ball, finite_float, get_ball  # (shared with the check)
from planner.catch.flight.dragtable import (  # (the RK4 table of a drag flight)
    G_M_S2,
    DragNodes,
    RK4Table,
    cross_fraction,
    hermite,
    hermite_np,
    rk4_run,
    step_for,
)
from planner.errors import InfeasibleError, InputError, PlannerError, SolverError

__all__ = [
    "BALLS",
    "GRAVITY_M_S2",
    "G_M_S2",
    "MAX_HEIGHT_M",
    "MAX_LAUNCH_SPEED_M_S",
    "MAX_TIME_S",
    "RHO_AIR",
    "Ball",
    "Flight",
    "flight_time_to",
    "get_ball",
    "predict_throw",
]

GRAVITY_M_S2 = np.array([0.0, 0.0, -G_M_S2])
GRAVITY_M_S2.setflags(write=False)
MAX_LAUNCH_SPEED_M_S = 100.0
"""Fastest launch speed predict_throw will propose, m/s."""
MAX_HEIGHT_M = 10.0
"""|height| of the target point must be below this, m."""
MAX_TIME_S = 100.0
"""Drag flights are only evaluated for |t| <= MAX_TIME_S seconds."""
MAX_OBS_RANGE_M = MAX_LAUNCH_SPEED_M_S * MAX_TIME_S + 0.5 * G_M_S2 * MAX_TIME_S**2
"""The farthest a ball launched at MAX_LAUNCH_SPEED_M_S gets from the launch point within
MAX_TIME_S (vacuum): an observation farther off is no ball of a throw, m."""

_SHOOT_TOL = 1e-9  # m, height miss accepted by the shooting
_HALF_GZ_M_S2 = 0.5 * -G_M_S2  # z of 0.5 * GRAVITY_M_S2
_S_S_Z = np.array([0, 0, 1])  # (s, z) -> (s, s, z)
FD_STEP = 1e-6  # m and m/s, central finite-difference step on [p0, v0]


# --------------------------------------------------------------------------- helpers


def _vec3(name: str, value: Any) -> np.ndarray:
    try:
        a = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be 3 numbers, got {value!r}") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be 3 finite numbers, got {value!r}")
    a.setflags(write=False)
    return a


# --------------------------------------------------------------------------- flight


@dataclass(frozen=True, eq=False)
class Flight:
    """A ball in flight: state (p0, v0) at t = 0 in the catch frame, drag k in 1/m.

    ``drag_per_m`` is the k the flight uses (0 = vacuum), which need not be
    ``ball.drag_per_m`` (a real ball may be planned in a vacuum). ``step_s`` is
    the RK4 step of the drag table; None picks one from v0 and k (see module doc).
    Arrays are read-only copies; equality is identity.
    """

    p0: np.ndarray
    v0: np.ndarray
    ball: Ball
    drag_per_m: float
    step_s: float | None = None
    _table: RK4Table | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "p0", _vec3("p0", self.p0))
        object.__setattr__(self, "v0", _vec3("v0", self.v0))
        if not isinstance(self.ball, Ball):
            raise InputError(f"ball must be a Ball, got {type(self.ball).__name__}")
        k = finite_float("drag_per_m", self.drag_per_m)
        if k < 0:
            raise InputError(f"drag_per_m must be >= 0, got {k}")
        object.__setattr__(self, "drag_per_m", k)
        object.__setattr__(self, "_p0_t", tuple(self.p0.tolist()))
        object.__setattr__(self, "_v0_t", tuple(self.v0.tolist()))
        vx, vy = self._v0_t[0], self._v0_t[1]
        u = math.hypot(vx, vy)
        object.__setattr__(self, "_dir", (vx / u, vy / u) if u > 0 else (1.0, 0.0))
        object.__setattr__(self, "_dir3", np.array([*self._dir, 1.0]))
        if k == 0.0:
            object.__setattr__(self, "step_s", None)
            return
        vx, vy, vz = (float(c) for c in self.v0)
        u0 = math.hypot(vx, vy)
        if self.step_s is None:
            h = step_for(k, math.hypot(u0, vz))
        else:
            h = finite_float("step_s", self.step_s)
            if h <= 0:
                raise InputError(f"step_s must be > 0, got {h}")
        object.__setattr__(self, "step_s", h)
        object.__setattr__(self, "_table", RK4Table(u0, vz, k, h))

    @property
    def speed(self) -> float:
        """Launch speed |v0|, m/s."""
        return float(np.linalg.norm(self.v0))

    def _times(self, t: Any) -> np.ndarray:
        try:
            ta = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"t must be a number or an array of numbers, got {t!r}") from None
        if not np.all(np.isfinite(ta)):
            raise InputError("t must be finite")
        if self._table is not None and ta.size and np.max(np.abs(ta)) > MAX_TIME_S:
            raise InputError(f"t must be within +-{MAX_TIME_S:g} s for a drag flight")
        return ta

    def _lookup(self, ta: np.ndarray) -> tuple:
        tab = self._table
        assert tab is not None
        if ta.size:
            tab.ensure(float(ta.min()), float(ta.max()))
        i_lo, P, D, A = tab.pairs()
        q = ta / tab.h - i_lo
        j = np.minimum(np.maximum(np.floor(q).astype(np.intp), 0), len(P) - 2)
        th = (q - j)[..., None]
        return j, j + 1, th, tab.h, (P, D, A)

    def integrate_to(self, t_s: float) -> None:
        """A drag flight's table made to cover [0, ``t_s``] in one run (a look-up there then
        integrates nothing; growing on demand may integrate up to half again as far)."""
        if self._table is not None:
            self._table.ensure(0.0, min(float(t_s), MAX_TIME_S))

    def nodes(self, t_hi: float) -> DragNodes:
        """A drag flight's table, integrated to cover [0, ``t_hi``] (PlannerError for a
        vacuum flight: it has none)."""
        if self._table is None:
            raise PlannerError("a vacuum flight has no drag table")
        self._table.ensure(0.0, t_hi)
        i_lo, P, D, _ = self._table.pairs()
        return DragNodes(self._table.h, -i_lo, P, D, self._dir)

    def _time1(self, t: float) -> float:
        """``_times`` for one time (a float): the same checks without numpy."""
        if not math.isfinite(t):
            raise InputError("t must be finite")
        if self._table is not None and abs(t) > MAX_TIME_S:
            raise InputError(f"t must be within +-{MAX_TIME_S:g} s for a drag flight")
        return float(t)

    def position1(self, t: float) -> tuple[float, float, float]:
        """``position`` at one time as three floats (the same arithmetic, no arrays: the
        live re-plan evaluates the flight at one time at a time, a few us each)."""
        t = self._time1(t)
        px, py, pz = self._p0_t
        if self._table is None:
            vx, vy, vz = self._v0_t
            return px + vx * t, py + vy * t, pz + vz * t + _HALF_GZ_M_S2 * t * t
        j, th, (_, S, Z, U, W, _, _) = self._table.node1(t)
        h = self._table.h
        s = hermite(S[j], S[j + 1], U[j], U[j + 1], h, th)
        z = hermite(Z[j], Z[j + 1], W[j], W[j + 1], h, th)
        ex, ey = self._dir
        return px + ex * s, py + ey * s, pz + z

    def state1(self, t: float) -> tuple[float, float, float, float, float, float]:
        """``position1`` and ``velocity1`` at one time, from one look-up."""
        t = self._time1(t)
        px, py, pz = self._p0_t
        if self._table is None:
            vx, vy, vz = self._v0_t
            return (px + vx * t, py + vy * t, pz + vz * t + _HALF_GZ_M_S2 * t * t, vx, vy, vz - G_M_S2 * t)
        j, th, (_, S, Z, U, W, AS, AW) = self._table.node1(t)
        h = self._table.h
        s = hermite(S[j], S[j + 1], U[j], U[j + 1], h, th)
        z = hermite(Z[j], Z[j + 1], W[j], W[j + 1], h, th)
        u = hermite(U[j], U[j + 1], AS[j], AS[j + 1], h, th)
        w = hermite(W[j], W[j + 1], AW[j], AW[j + 1], h, th)
        ex, ey = self._dir
        return px + ex * s, py + ey * s, pz + z, ex * u, ey * u, w

    def velocity1(self, t: float) -> tuple[float, float, float]:
        """``velocity`` at one time as three floats."""
        t = self._time1(t)
        if self._table is None:
            vx, vy, vz = self._v0_t
            return vx, vy, vz - G_M_S2 * t
        j, th, (_, _, _, U, W, AS, AW) = self._table.node1(t)
        h = self._table.h
        u = hermite(U[j], U[j + 1], AS[j], AS[j + 1], h, th)
        w = hermite(W[j], W[j + 1], AW[j], AW[j + 1], h, th)
        ex, ey = self._dir
        return ex * u, ey * u, w

    def position(self, t: Any) -> np.ndarray:
        """Ball centre at time(s) t, shape t.shape + (3,)."""
        if isinstance(t, float):
            return np.array(self.position1(t))
        ta = self._times(t)
        if self._table is None:
            tt = ta[..., None]
            return self.p0 + self.v0 * tt + 0.5 * GRAVITY_M_S2 * tt * tt
        j, j1, th, h, (P, D, _) = self._lookup(ta)
        sz = hermite_np(P[j], P[j1], D[j], D[j1], h, th)  # (s, z)
        return self.p0 + sz[..., _S_S_Z] * self._dir3  # (ex s, ey s, z)

    def velocity(self, t: Any) -> np.ndarray:
        """Ball velocity at time(s) t, shape t.shape + (3,)."""
        if isinstance(t, float):
            return np.array(self.velocity1(t))
        ta = self._times(t)
        if self._table is None:
            return self.v0 + GRAVITY_M_S2 * ta[..., None]
        j, j1, th, h, (_, D, A) = self._lookup(ta)
        uw = hermite_np(D[j], D[j1], A[j], A[j1], h, th)  # (u, w)
        return uw[..., _S_S_Z] * self._dir3  # (ex u, ey u, w)

    def time_at_x(self, x: Any) -> Any:
        """Time t >= 0 at which the ball crosses the plane x = ``x`` (float, or array).

        InfeasibleError if it does not cross it at any t in [0, MAX_TIME_S].
        """
        if np.ndim(x):
            xa = np.asarray(x, dtype=float)
            return np.array([self.time_at_x(float(xi)) for xi in xa.reshape(-1)]).reshape(xa.shape)
        xf = finite_float("x", x)
        dx = xf - float(self.p0[0])
        vx = float(self.v0[0])
        if dx == 0.0:
            return 0.0
        if vx == 0.0 or (dx > 0) != (vx > 0):
            raise InfeasibleError(
                f"the ball never reaches the plane x = {xf:g} m (it starts at "
                f"x = {self.p0[0]:g} m moving at vx = {vx:g} m/s)"
            )
        if self._table is None:
            return dx / vx
        tab = self._table
        s_t = dx / self._dir[0]
        S, U = tab.fwd[0], tab.fwd[2]
        while S[-1] < s_t:
            if (len(S) - 1) * tab.h >= MAX_TIME_S:
                raise InfeasibleError(
                    f"the ball does not reach the plane x = {xf:g} m within {MAX_TIME_S:g} s"
                )
            tab.ensure(0.0, min(MAX_TIME_S, 2.0 * (len(S) - 1) * tab.h + 1.0))
        i = int(np.searchsorted(S, s_t, side="left"))
        i = max(i, 1)
        th = cross_fraction(S[i - 1], S[i], U[i - 1], U[i], tab.h, s_t)
        return (i - 1 + th) * tab.h

    def to_metadata(self) -> dict[str, Any]:
        """The trajectory file's ``ball`` entry (spec section 4)."""
        return {
            "p0": [float(c) for c in self.p0],
            "v0": [float(c) for c in self.v0],
            "radius": float(self.ball.radius_m),
            "mass": float(self.ball.mass_kg),
            "drag": float(self.drag_per_m),
        }


# --------------------------------------------------------------------------- throws


def check_throw(angle_deg: Any, dist_m: Any, height_m: Any, prefix: str = ""
                ) -> tuple[float, float, float]:
    """(angle, dist, height) as floats, or InputError: 0 < angle < 90 deg, dist > 0,
    |height| < MAX_HEIGHT_M, all finite. ``prefix`` goes before the names in messages
    (``--`` for the command line)."""
    a = finite_float(f"{prefix}angle", angle_deg)
    if not 0.0 < a < 90.0:
        raise InputError(f"{prefix}angle must be strictly between 0 and 90 degrees, got {a:g}")
    d = finite_float(f"{prefix}dist", dist_m)
    if d <= 0.0:
        raise InputError(f"{prefix}dist must be > 0 m, got {d:g}")
    h = finite_float(f"{prefix}height", height_m)
    if not abs(h) < MAX_HEIGHT_M:
        raise InputError(
            f"{prefix}height must be between -{MAX_HEIGHT_M:g} and {MAX_HEIGHT_M:g} m (exclusive), "
            f"got {h:g}"
        )
    return a, d, h


def _vacuum_speed(a_rad: float, d: float, h: float, angle_deg: float) -> float:
    rise = d * math.tan(a_rad) - h
    if rise <= 0.0:
        raise InputError(
            f"no throw at {angle_deg:g} deg passes through ({d:g}, 0, {h:g}) m: the height "
            f"must be below dist*tan(angle) = {d * math.tan(a_rad):.4g} m"
        )
    c = math.cos(a_rad)
    v = math.sqrt(G_M_S2 * d * d / (2.0 * c * c * rise))
    if v > MAX_LAUNCH_SPEED_M_S:
        raise InputError(
            f"a throw at {angle_deg:g} deg through ({d:g}, 0, {h:g}) m needs {v:.4g} m/s, "
            f"more than {MAX_LAUNCH_SPEED_M_S:g} m/s"
        )
    return v


def _shoot_drag(a_rad: float, d: float, h: float, k: float, v_vac: float, angle_deg: float):
    """Launch speed whose drag flight passes through (d, 0, h); returns (v, step, lists)."""
    ca, sa = math.cos(a_rad), math.sin(a_rad)
    step = step_for(k, v_vac)
    n_max = int(MAX_TIME_S / step) + 1

    z_floor = h - 1.0

    def run(v: float):
        """(miss, lists): z - h where the ball crosses x = d. If it sinks 1 m below h
        first, the miss extrapolated along its path from there (keeps the secant sane)."""
        lists = ([0.0], [0.0], [v * ca], [v * sa])
        S, Z, U, W = lists
        rk4_run(S, Z, U, W, k, step, n_max, d, z_floor)
        if S[-1] >= d:
            th = cross_fraction(S[-2], S[-1], U[-2], U[-1], step, d)
            return hermite(Z[-2], Z[-1], W[-2], W[-1], step, th) - h, lists
        slope = abs(W[-1]) / max(U[-1], 1e-9)
        return Z[-1] - h - slope * (d - S[-1]), lists

    # Secant from the vacuum speed; the first step uses the vacuum dz/dv.
    v1 = v_vac
    f1, lists = run(v1)
    if abs(f1) <= _SHOOT_TOL:
        return v1, step, lists
    v2 = v1 - f1 / (G_M_S2 * d * d / (v1**3 * ca * ca))
    for _ in range(12):
        if not (0.0 < v2 <= 1.5 * MAX_LAUNCH_SPEED_M_S and math.isfinite(v2)):
            break
        f2, lists = run(v2)
        if abs(f2) <= _SHOOT_TOL:
            if v2 > MAX_LAUNCH_SPEED_M_S:
                break
            return v2, step, lists
        if f2 == f1:
            break
        v1, f1, v2 = v2, f2, v2 - f2 * (v2 - v1) / (f2 - f1)

    # Fallback: bracket [v_vac, MAX_LAUNCH_SPEED_M_S] (drag only ever needs more speed).
    f_hi, _ = run(MAX_LAUNCH_SPEED_M_S)
    if f_hi < 0.0:
        raise InputError(
            f"no throw at {angle_deg:g} deg up to {MAX_LAUNCH_SPEED_M_S:g} m/s reaches "
            f"({d:g}, 0, {h:g}) m with drag k = {k:.4g} 1/m"
        )
    f_lo, _ = run(v_vac)
    if f_lo > 0.0:  # cannot happen with k > 0; guard the bracket anyway
        raise SolverError("drag shooting lost its bracket", problem=(angle_deg, d, h, k))
    from scipy.optimize import brentq  # (only here: scipy.optimize takes 0.25 s to import)

    v = brentq(lambda v: run(v)[0], v_vac, MAX_LAUNCH_SPEED_M_S, xtol=1e-13, rtol=1e-15)
    return v, step, run(v)[1]


def predict_throw(
    angle_deg: float,
    dist_m: float,
    height_m: float = 0.0,
    ball: Ball | str | None = None,
    drag: bool = False,
) -> Flight:
    """The throw leaving the origin at ``angle_deg`` that passes through (dist, 0, height).

    ``ball``: a Ball, a name in BALLS, or None (the seed's ball). ``drag=False``
    flies it in a vacuum (k = 0, closed form); ``drag=True`` uses the ball's k and
    shoots for the launch speed. InputError on a bad argument, InfeasibleError
    when no throw at that angle (at most MAX_LAUNCH_SPEED_M_S) reaches the point.
    """
    a, d, h = check_throw(angle_deg, dist_m, height_m)
    b = get_ball(ball)
    a_rad = math.radians(a)
    v = _vacuum_speed(a_rad, d, h, a)
    k = b.drag_per_m if drag else 0.0
    if k == 0.0:
        return Flight(
            np.zeros(3), np.array([v * math.cos(a_rad), 0.0, v * math.sin(a_rad)]), b, 0.0
        )
    v, step, lists = _shoot_drag(a_rad, d, h, k, v, a)
    flight = Flight(
        np.zeros(3),
        np.array([v * math.cos(a_rad), 0.0, v * math.sin(a_rad)]),
        b,
        k,
        step_s=step,
    )
    tab = flight._table
    assert tab is not None
    tab.fwd = lists  # the shooting's last run is this flight's table
    return flight


def flight_time_to(flight: Flight, dist_m: float) -> float:
    """Time at which ``flight`` crosses the plane x = dist_m (the seed's "flight time")."""
    return float(flight.time_at_x(dist_m))

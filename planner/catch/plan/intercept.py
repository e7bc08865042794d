"""Where the palm meets the ball: the wrist's geometry in the reference frame (the catch
point at the origin) and the closed-form intercept it allows (``planner.catch.plan.api``,
step 1): flexion from the ball's direction, the time from its height above the palm
plane, deviation and rail in closed form; the palm's position alone (misaligned) where
no pose faces the ball; out of reach where neither exists."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.catch.flight.path import Flight
from planner.catch.plan.arm import CatchJoints, zero_pose
from planner.catch.plan.geometry import bracketed_secant, rot1, unit
from planner.errors import PlannerError
from planner.hand.model import HandModel
from planner.trajectory import LIMIT_MARGIN

MAX_MISALIGN_DEG = 80.0  # beyond this the ball grazes the palm: out of reach
_N_SEARCH = 46  # samples of the ball's path in the intercept search
_N_NEAR = 5  # ... and in the window of a warm-started one
SEARCH_BEFORE_S, SEARCH_AFTER_S = 0.30, 0.15  # the whole-path search's span around the
# throw's time at the catch point


@dataclass(frozen=True)
class Intercept:
    """The palm's pose meeting the ball: time, wrist flexion and deviation, rail; how far
    the palm normal is off the ball's path; None or why the ball is out of reach."""

    t: float
    theta: float
    dev: float
    rail: float
    misalign: float  # rad
    aligned: bool
    reason: str | None
    reach: float = 0.0  # the rig's reach axis (m): where along the forearm's line the hand is


class Wrist:
    """Wrist geometry in the reference frame at zero flexion, deviation and rail, checked
    against the structure the closed-form intercept assumes (flexion across the rail,
    then deviation about the palm normal, through one point)."""

    def __init__(self, hand: HandModel, joints: CatchJoints) -> None:
        h, q0 = hand, zero_pose(hand)
        self.i_rail = joints.i_rail
        spec = h.spec

        def axis(name: str) -> np.ndarray:
            T = h.frame_pose(q0, name)
            return unit(T[:3, :3] @ np.array(spec.joint(name).axis, dtype=float))

        self.e_f = axis("wrist_flex")
        self.u_d = axis("wrist_dev")
        self.e_r = axis("rail") if joints.i_rail is not None else self.e_f.copy()
        self.e_reach = axis("reach") if "reach" in h.index else np.zeros(3)  # (held or
        # moved: the reference frame's direction of a reach move, the hand's whole)
        self.W = h.frame_pose(q0, "wrist_flex")[:3, 3].copy()
        D = h.frame_pose(q0, "wrist_dev")[:3, 3]
        P = h.palm_pose(q0)
        self.pc0, self.n0 = P[:3, 3].copy(), P[:3, 2].copy()
        self.g0 = self.pc0 - self.W
        ok = (np.linalg.norm(D - self.W) < 1e-9 and abs(abs(self.u_d @ self.n0) - 1.0) < 1e-9
              and abs(self.e_f @ self.n0) < 1e-9 and abs(abs(self.e_r @ self.e_f) - 1.0) < 1e-9)
        if not ok:
            raise PlannerError("catch planner: the wrist must be flexion (across the rail) then "
                               "deviation about the palm normal, through one point")
        self.b0 = unit(np.cross(self.n0, self.e_r))
        self._e_t = tuple(float(x) for x in self.e_f)
        self._n0_t = tuple(float(x) for x in self.n0)
        self._W_t = tuple(float(x) for x in self.W)
        self._e_r_t = tuple(float(x) for x in self.e_r)
        self._circles: dict[float, tuple] = {}  # palm_circles' default rows, per radius
        g0p = self.g0 - (self.g0 @ self.n0) * self.n0
        self._dev_A = float(g0p @ self.b0)
        self._dev_B = float(np.cross(self.u_d, g0p) @ self.b0)
        self._g0n = float(self.g0 @ self.n0)
        e_n = np.cross(self.e_f, self.n0)  # (aligned's projections: e, n0, e x n0)
        self._frame = np.column_stack([self.e_f, self.n0, e_n])
        self._e_n0, self._e_en = float(self.e_f @ self.n0), float(self.e_f @ e_n)
        self.f0 = np.cross(self.n0, self.e_f)  # in the palm's plane, across the flexion axis
        if float(self.g0 @ self.f0) < 0.0:  # (towards the palm centre from the wrist)
            self.f0 = -self.f0
        lo, hi = hand.lower, hand.upper
        i_reach = hand.index.get("reach")
        self.reach_lim = ((float(lo[i_reach]), float(hi[i_reach])) if i_reach is not None
                          else (0.0, 0.0))
        self.flex_lim = (float(lo[joints.i_flex]), float(hi[joints.i_flex]))
        self.dev_lim = (float(lo[joints.i_dev]), float(hi[joints.i_dev]))
        self.rail_lim = ((float(lo[joints.i_rail]), float(hi[joints.i_rail]))
                         if joints.i_rail is not None else (0.0, 0.0))

    def aligned(self, b: np.ndarray, v: np.ndarray, r: float, tilt: float = 0.0
                ) -> tuple[np.ndarray, np.ndarray]:
        """For path samples (positions b, velocities v, reference frame): flexion that
        turns the normal against v (then ``tilt`` rad further about the flexion axis), and
        h = height of the ball above the palm plane minus r. With m = -(v's part across
        the flexion axis e) the flexion is atan2(m . (e x n0), m . n0), and the ball's
        height above the turned palm (b - W) . Rot(e, theta) n0 (Rodrigues): projections
        on e, n0 and e x n0 alone, no rotated points."""
        ve, vn, ven = (v @ self._frame).T
        theta = np.arctan2(-ven + ve * self._e_en, -vn + ve * self._e_n0) + tilt
        we, wn, wen = ((b - self.W) @ self._frame).T
        c = np.cos(theta)
        return theta, c * wn + np.sin(theta) * wen + (1.0 - c) * self._e_n0 * we - (
            self._g0n + r)

    def aligned1(self, flight: Flight, C: np.ndarray, t: float, r: float, tilt: float = 0.0
                  ) -> tuple[float, np.ndarray, float]:
        """``_aligned`` for one time (plain float arithmetic: no numpy call overhead)."""
        px, py, pz, vx, vy, vz = flight.state1(t)
        bx, by, bz = px - float(C[0]), py - float(C[1]), pz - float(C[2])
        ex, ey, ez = self._e_t
        nx, ny, nz = self._n0_t
        wx, wy, wz = self._W_t
        d = -(vx * ex + vy * ey + vz * ez)
        mx, my, mz = -vx - d * ex, -vy - d * ey, -vz - d * ez
        mn = math.sqrt(mx * mx + my * my + mz * mz)
        mx, my, mz = mx / mn, my / mn, mz / mn
        cx, cy, cz = ny * mz - nz * my, nz * mx - nx * mz, nx * my - ny * mx
        th = math.atan2(cx * ex + cy * ey + cz * ez, mx * nx + my * ny + mz * nz) + tilt
        # s = Rot(e, -th) (b - W)
        px, py, pz = bx - wx, by - wy, bz - wz
        c, sn = math.cos(-th), math.sin(-th)
        kx, ky, kz = ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px
        kp = (px * ex + py * ey + pz * ez) * (1.0 - c)
        sx, sy, sz = (px * c + kx * sn + kp * ex, py * c + ky * sn + kp * ey,
                      pz * c + kz * sn + kp * ez)
        h = (sx * nx + sy * ny + sz * nz) - (self._g0n + r)
        return th, np.array([sx, sy, sz]), h

    def dev_rail(self, s: np.ndarray, r: float) -> tuple[float, float] | None:
        """Deviation and rail that put palm_center + r n0 at ``s`` (zero-flexion frame)."""
        rho = math.hypot(self._dev_A, self._dev_B)
        phi = math.atan2(self._dev_B, self._dev_A)
        x = float(s @ self.b0) / rho
        if abs(x) > 1.0:
            return None
        best = None
        lo, hi = self.dev_lim
        for dev in (phi + math.acos(x), phi - math.acos(x)):
            dev = math.atan2(math.sin(dev), math.cos(dev))
            margin = min(dev - lo, hi - dev)
            if margin < 0:
                continue
            rail = self.rail_for(s, dev, r)
            if not (self.rail_lim[0] <= rail <= self.rail_lim[1]):
                continue
            if best is None or margin > best[0]:
                best = (margin, dev, rail)
        return None if best is None else (best[1], best[2])

    def palm_circles(self, r: float, devs: tuple[float, ...] | None = None
                     ) -> tuple[tuple[float, ...], list, list, list]:
        """The palm point (palm centre + r n0) at each deviation of ``devs`` (default five
        across its range: kept per radius, a hand's constants): ``_position_only``'s
        deviations, the points (zero-flexion frame), their parts across the flexion axis,
        and their distances from it (the circles the flexion moves them on)."""
        if devs is None and r in self._circles:
            return self._circles[r]
        lo, hi = self.dev_lim
        ds = devs if devs is not None else (lo, 0.5 * lo, 0.0, 0.5 * hi, hi)
        ex, ey, ez = self._e_t
        A, AP, rho = [], [], []
        for dev in ds:  # (floats: numpy's per-call cost dominates at this size)
            ax, ay, az = (rot1(self.u_d, dev, self.g0) + r * self.n0).tolist()
            d = ax * ex + ay * ey + az * ez
            apx, apy, apz = ax - d * ex, ay - d * ey, az - d * ez
            A.append((ax, ay, az))
            AP.append((apx, apy, apz))
            rho.append(math.sqrt(apx * apx + apy * apy + apz * apz))
        out = (tuple(ds), A, AP, rho)
        if devs is None:
            self._circles[r] = out
        return out

    def rail_for(self, s: np.ndarray, dev: float, r: float) -> float:
        if self.i_rail is None:
            return 0.0
        a = rot1(self.u_d, dev, self.g0) + r * self.n0
        return float((s - a) @ self.e_r)


def find_intercept(wr: Wrist, flight: Flight, C: np.ndarray, r: float, t_c: float,
                   tilt: float = 0.0, memo: dict | None = None) -> Intercept:
    """Where and when the palm meets the ball near ``C`` (``planner.catch.plan.api``, step 1),
    searched around ``t_c`` (the throw's time at the catch point); ``tilt``: the palm
    normal turned this far (rad, about the flexion axis) from facing the ball (the soft
    catch's choice, ``planner.catch.plan.stopping``); 0 faces it. The reach axis at 0.
    ``memo``: a dict kept by the caller for searches of this one flight, ``C`` and ``r``
    at several tilts (the live session's tilted search and its untilted retry): the path's
    samples and the position-only fallback (which faces no tilt) are computed once."""
    key = ("path", t_c)
    if memo is not None and key in memo:
        t, b, v = memo[key]
    else:
        t = np.linspace(max(0.0, t_c - SEARCH_BEFORE_S), t_c + SEARCH_AFTER_S, _N_SEARCH)
        b = flight.position(t) - C
        v = flight.velocity(t)
        if memo is not None:
            memo[key] = (t, b, v)
    _, hgt = wr.aligned(b, v, r, tilt)
    # first crossing of the palm plane (+ before, - after)
    down = np.flatnonzero((hgt[:-1] > 0) & (hgt[1:] <= 0))
    if down.size:
        k = int(down[0])
        ta, tb, fa, fb = float(t[k]), float(t[k + 1]), float(hgt[k]), float(hgt[k + 1])
        # h is smooth (~ the ball's height above the palm plane): a bracketed
        # secant converges in 2-4 steps to 1e-8 m
        ti, (th, s_vec, _) = bracketed_secant(
            lambda tm: wr.aligned1(flight, C, tm, r, tilt), ta, tb, fa, fb)
        sol = wr.dev_rail(s_vec, r)
        if sol is not None and wr.flex_lim[0] <= th <= wr.flex_lim[1]:
            return Intercept(ti, th, sol[0], sol[1], abs(tilt), True, None)
    if memo is None:
        return _position_only(wr, flight, C, r, t, b=b)
    key = ("position only", t_c)
    if key not in memo:
        memo[key] = _position_only(wr, flight, C, r, t, b=b)
    return memo[key]


def find_intercept_square(wr: Wrist, flight: Flight, C: np.ndarray, r: float, t_c: float,
                          tilt: float = 0.0, dev: float = 0.0) -> Intercept | None:
    """The intercept with the wrist's deviation at ``dev`` (0: the palm square to the
    throw, the fingers' cage symmetric about the ball's path) and the rig's reach axis
    putting the palm on the path: at each time the flexion faces the ball (``tilt`` further),
    the reach s moves the hand along its axis (direction ``e_reach``, across the flexion axis)
    until the palm point is the ball's distance from the wrist along the palm (f), and the
    intercept is where the ball's height above the moved palm plane crosses zero (a root in
    t); the rail takes up the part along the flexion axis. None where no such pose lies
    within the reach axis', the flexion's and the rail's ranges (the caller then holds the
    reach at 0 and lets the deviation place the ball)."""
    if not np.any(wr.e_reach) or not wr.reach_lim[0] < wr.reach_lim[1]:
        return None
    g = rot1(wr.u_d, dev, wr.g0) + r * wr.n0  # the palm point from the wrist, zero flexion
    g_f, g_n, g_e = float(g @ wr.f0), float(g @ wr.n0), float(g @ wr.e_f)
    t = np.linspace(max(0.0, t_c - SEARCH_BEFORE_S), t_c + SEARCH_AFTER_S, _N_SEARCH)

    def at(tt: np.ndarray):
        w = flight.position(tt) - C - wr.W
        th, _ = wr.aligned(flight.position(tt) - C, flight.velocity(tt), r, tilt)
        c, sn = np.cos(th)[:, None], np.sin(th)[:, None]
        e = wr.e_f
        n = wr.n0 * c + np.cross(e, wr.n0) * sn + np.outer(np.ones(len(th)), e) * (
            e @ wr.n0) * (1.0 - c)
        f = wr.f0 * c + np.cross(e, wr.f0) * sn + np.outer(np.ones(len(th)), e) * (
            e @ wr.f0) * (1.0 - c)
        rf, rn = f @ wr.e_reach, n @ wr.e_reach
        s = (np.einsum("ij,ij->i", w, f) - g_f) / np.where(np.abs(rf) > 1e-9, rf, 1e-9)
        h = np.einsum("ij,ij->i", w, n) - s * rn - g_n
        return th, s, h, w @ e - g_e

    h = at(t)[2]
    down = np.flatnonzero((h[:-1] > 0) & (h[1:] <= 0))
    if not down.size:
        return None
    k = int(down[0])

    def one(tm: float):
        th1, s1, h1, rail1 = at(np.array([tm]))
        return th1[0], s1[0], rail1[0], h1[0]

    ti, (th_i, s_i, rail_i, _) = bracketed_secant(one, float(t[k]), float(t[k + 1]),
                                                   float(h[k]), float(h[k + 1]))
    pad = 0.5 * (1.0 - LIMIT_MARGIN) * (wr.reach_lim[1] - wr.reach_lim[0])
    lo, hi = wr.reach_lim[0] + pad, wr.reach_lim[1] - pad
    if not (lo <= s_i <= hi and wr.flex_lim[0] <= th_i <= wr.flex_lim[1]
            and wr.rail_lim[0] <= rail_i <= wr.rail_lim[1]):
        return None
    return Intercept(float(ti), float(th_i), float(dev), float(rail_i), abs(tilt), True, None,
                     float(s_i))


def find_intercept_near(wr: Wrist, flight: Flight, C: np.ndarray, r: float, prev: Intercept,
                        t_prev: float, half_width_s: float, tilt: float = 0.0,
                        memo: dict | None = None) -> Intercept:
    """``find_intercept`` warm-started from a previous intercept time ``t_prev`` (a live
    re-plan: the flight moved a little): the palm-plane crossing bracketed within
    ``half_width_s`` of it and found by the same secant, or (no aligned pose) the palm's
    position alone searched on ``_N_NEAR`` samples of that window (at the previous
    deviation only when ``prev`` was such an intercept); the full search when neither
    finds it there. A previous intercept out of reach is no pose to start from (as the
    first plan's ``session._prior``): the full search at once (around ``t_prev``).
    ``tilt``: ``find_intercept``'s (the palm turned from facing the ball; its position-only
    fallback faces none); ``memo``: ``find_intercept``'s."""
    if prev.reason is not None:
        return find_intercept(wr, flight, C, r, t_prev, tilt, memo)
    ta, tb = max(0.0, t_prev - half_width_s), t_prev + half_width_s
    fa, fb = wr.aligned1(flight, C, ta, r, tilt)[2], wr.aligned1(flight, C, tb, r, tilt)[2]
    if fa > 0 >= fb:
        ti, (th, s_vec, _) = bracketed_secant(
            lambda tm: wr.aligned1(flight, C, tm, r, tilt), ta, tb, fa, fb)
        sol = wr.dev_rail(s_vec, r)
        if sol is not None and wr.flex_lim[0] <= th <= wr.flex_lim[1]:
            return Intercept(ti, th, sol[0], sol[1], abs(tilt), True, None)
    devs = (prev.dev,) if not prev.aligned else None
    key = ("near position only", ta, tb, devs)  # (faces no tilt)
    ic = None if memo is None else memo.get(key)
    if ic is None:
        ic = _position_only(wr, flight, C, r, np.linspace(ta, tb, _N_NEAR), devs)
        if ic.reason is not None and devs is not None:
            ic = _position_only(wr, flight, C, r, np.linspace(ta, tb, _N_NEAR))
        if memo is not None:
            memo[key] = ic
    return ic if ic.reason is None else find_intercept(wr, flight, C, r, t_prev, tilt, memo)


def _crossing(wr: Wrist, flight: Flight, C: np.ndarray, rho: float, ta: float, tb: float,
              fa: float, fb: float) -> float:
    """Time in [ta, tb] at which the ball is ``rho`` from the flexion axis (secant)."""
    ex, ey, ez = wr._e_t
    ox, oy, oz = (float(c + w) for c, w in zip(C, wr.W))

    def f(t: float) -> tuple[float]:
        px, py, pz = flight.position1(t)
        wx, wy, wz = px - ox, py - oy, pz - oz
        d = wx * ex + wy * ey + wz * ez
        return (math.sqrt((wx - d * ex) ** 2 + (wy - d * ey) ** 2 + (wz - d * ez) ** 2) - rho,)

    return bracketed_secant(f, ta, tb, fa, fb)[0]


def _position_only(wr: Wrist, flight: Flight, C: np.ndarray, r: float,
                   t: np.ndarray, devs: tuple[float, ...] | None = None,
                   b: np.ndarray | None = None) -> Intercept:
    """No pose faces the ball exactly: put the palm point on the path with the
    deviation at each candidate value (``devs``; default five across its range) and pick
    the least misaligned reachable one. ``b``: the ball at ``t`` less ``C`` when known."""
    if b is None:  # (a few samples: one at a time in floats, ``Flight.position1``)
        b = (np.array([flight.position1(x) for x in t.tolist()]) if len(t) <= _N_NEAR
             else flight.position(t)) - C
    e = wr.e_f
    w = b - wr.W
    w_p = w - np.outer(w @ e, e)
    dist = np.linalg.norm(w_p, axis=1)
    best: Intercept | None = None
    closest = (np.inf, None)
    ex, ey, ez = wr._e_t
    er = wr._e_r_t
    W = wr._W_t
    Cx, Cy, Cz = (float(c) for c in C)
    devs, A, AP, rho = wr.palm_circles(r, devs)
    # every deviation at once: the ball's distance from the flexion axis less the palm
    # point's, its first inward crossing and its nearest sample
    f_all = dist[None, :] - np.array(rho)[:, None]
    cross_in = (f_all[:, :-1] > 0) & (f_all[:, 1:] <= 0)
    k_near = np.abs(f_all).argmin(axis=1).tolist()
    has_in = cross_in.any(axis=1).tolist()
    k_in = cross_in.argmax(axis=1).tolist()
    for i, dev in enumerate(devs):
        f = f_all[i]
        if abs(f[k_near[i]]) < closest[0]:
            closest = (float(abs(f[k_near[i]])), float(t[k_near[i]]))
        if not has_in[i]:
            continue
        ax, ay, az = A[i]
        apx, apy, apz = AP[i]
        k = k_in[i]
        tk = _crossing(wr, flight, C, rho[i], float(t[k]), float(t[k + 1]), float(f[k]),
                       float(f[k + 1]))
        px, py, pz = flight.position1(tk)
        vx, vy, vz = flight.velocity1(tk)
        wx, wy, wz = px - Cx - W[0], py - Cy - W[1], pz - Cz - W[2]
        d = wx * ex + wy * ey + wz * ez
        qx, qy, qz = wx - d * ex, wy - d * ey, wz - d * ez
        # flexion turning a_p onto the ball's offset wk_p about e
        th = math.atan2((apy * qz - apz * qy) * ex + (apz * qx - apx * qz) * ey
                        + (apx * qy - apy * qx) * ez, apx * qx + apy * qy + apz * qz)
        if not wr.flex_lim[0] <= th <= wr.flex_lim[1]:
            continue
        nx, ny, nz = rot1(e, th, wr.n0).tolist()
        mis = math.acos(min(1.0, max(-1.0, -(vx * nx + vy * ny + vz * nz)
                                     / math.sqrt(vx * vx + vy * vy + vz * vz))))
        if wr.i_rail is not None:
            bx, by, bz = rot1(e, th, np.array([ax, ay, az])).tolist()
            rail = (wx - bx) * er[0] + (wy - by) * er[1] + (wz - bz) * er[2]
        else:
            rail = 0.0
        if not (wr.rail_lim[0] <= rail <= wr.rail_lim[1]):
            continue
        if mis > math.radians(MAX_MISALIGN_DEG):
            continue
        if best is None or mis < best.misalign:
            best = Intercept(tk, th, dev, rail, mis, False, None)
    if best is not None:
        return best
    # out of reach: keep the open hand at its reference pose, meet the ball where
    # it passes closest
    tk = closest[1] if closest[1] is not None else float(t[len(t) // 2])
    return Intercept(tk, 0.0, 0.0, 0.0, 0.0, False,
                     f"out of reach: no wrist/rail pose puts the palm on the ball's path "
                     f"facing it (closest {1000 * closest[0]:.0f} mm off the palm's circle)")


def closest_time(flight: Flight, C: np.ndarray) -> float:
    """When the ball passes closest to ``C`` (a throw that never reaches its x)."""
    t = np.linspace(0.0, 3.0, 601)
    d = np.linalg.norm(flight.position(t) - C, axis=1)
    return float(t[int(np.argmin(d))])


def refine_time(flight: Flight, C: np.ndarray, P: np.ndarray, t: float) -> float:
    """The time near ``t`` at which the ball passes closest to ``P`` (Newton steps)."""
    ox, oy, oz = (float(p + c) for p, c in zip(P, C))  # P in the catch frame
    for _ in range(3):
        px, py, pz, vx, vy, vz = flight.state1(float(t))
        step = ((ox - px) * vx + (oy - py) * vy + (oz - pz) * vz) / (vx * vx + vy * vy + vz * vz)
        t += step
        if abs(step) < 1e-9:
            break
    return float(t)

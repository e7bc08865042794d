"""A ball on the moving palm (``planner.check.ballroll``'s roll model): a rigid sphere on
the palm's plane as the rows move it, with gravity, a contact that cannot pull and
Coulomb friction, integrated in small time steps with impulses (velocity-level time
stepping, as rigid-body engines do: D. E. Stewart & J. C. Trinkle, "An implicit
time-stepping scheme for rigid body dynamics with inelastic collisions and Coulomb
friction", Int. J. Numer. Meth. Eng. 39 (1996)).

Each step: gravity; then, where the ball touches the palm (or would pass through it
within the step), the normal impulse that stops its approach and the friction impulse
that brings its contact point to the palm's velocity there (the ball rolls), at most
mu times the normal impulse (it slides). A sphere's contact point moves by the impulse
J over m (1 + 1 / beta) tangentially (J / m of its centre, J R^2 / I of its spin), beta =
I / (m R^2). Between two rows the palm turns at the rows' angular velocity about its
centre and the centre moves at their speed (the replay's servos follow joints moving
linearly from row to row: the pose between rows to second order). Plain floats: the
planner runs it on every turn it tries.
"""

from __future__ import annotations

import math

import numpy as np

from planner.hand.model import GRAVITY_WORLD

ROLL_STEP_S = 1e-3  # the model's time step: on the wide grid's 119 plans the largest roll
# moves by at most 3.6 mm from 1 ms to 0.5 ms (median 0.1 mm)
CONTACT_GAP_M = 2e-3  # a ball this near the palm is judged for contact in the step (its
# approach within the step is at most its speed times the step: 6 mm at 6 m/s, the
# rest caught by the position's projection onto the palm)

_GX, _GY, _GZ = (float(x) for x in GRAVITY_WORLD)


def _rotation_log(R: np.ndarray) -> tuple[float, float, float]:
    """The rotation vector (axis times angle, rad) of the rotation matrix ``R``."""
    c = max(-1.0, min(1.0, (float(R[0, 0] + R[1, 1] + R[2, 2]) - 1.0) / 2.0))
    th = math.acos(c)
    if th < 1e-12:
        return 0.0, 0.0, 0.0
    f = th / (2.0 * math.sin(th))
    return (f * float(R[2, 1] - R[1, 2]), f * float(R[0, 2] - R[2, 0]),
            f * float(R[1, 0] - R[0, 1]))


def _rotate(w: tuple[float, float, float], tau: float, v: tuple[float, float, float]
            ) -> tuple[float, float, float]:
    """``v`` turned by the rotation vector ``w`` tau (Rodrigues)."""
    wx, wy, wz = w
    th = math.sqrt(wx * wx + wy * wy + wz * wz) * tau
    if th < 1e-12:
        return v
    s = tau / th
    kx, ky, kz = wx * s, wy * s, wz * s
    vx, vy, vz = v
    c, sn = math.cos(th), math.sin(th)
    d = (kx * vx + ky * vy + kz * vz) * (1.0 - c)
    return (vx * c + (ky * vz - kz * vy) * sn + kx * d,
            vy * c + (kz * vx - kx * vz) * sn + ky * d,
            vz * c + (kx * vy - ky * vx) * sn + kz * d)


class BallOnPalm:
    """The ball's state (centre p, velocity v, spin w: world) on the palm of the rows."""

    def __init__(self, radius_m: float, inertia_ratio: float, mu: float) -> None:
        self.r, self.beta, self.mu = radius_m, inertia_ratio, mu
        self.t = 0.0
        self.p = self.v = self.w = (0.0, 0.0, 0.0)
        self._seg = -1
        self._od = self._om = self._o0 = self._n0 = self._y0 = (0.0, 0.0, 0.0)
        self._t0 = 0.0

    def _segment(self, palm: np.ndarray, t_s: np.ndarray, k: int) -> None:
        """The palm's motion from row ``k`` to row ``k + 1``."""
        if self._seg == k:
            return
        dt = float(t_s[k + 1] - t_s[k])
        P0, P1 = palm[k], palm[k + 1]
        self._od = tuple(float(x) for x in (P1[:3, 3] - P0[:3, 3]) / dt)
        om = _rotation_log(P1[:3, :3] @ P0[:3, :3].T)
        self._om = (om[0] / dt, om[1] / dt, om[2] / dt)
        self._o0 = tuple(float(x) for x in P0[:3, 3])
        self._n0 = tuple(float(x) for x in P0[:3, 2])
        self._y0 = tuple(float(x) for x in P0[:3, 1])
        self._t0, self._seg = float(t_s[k]), k

    def _plane(self, t: float):
        """The palm's centre, normal and +y at ``t`` (in the current segment)."""
        tau = t - self._t0
        o0, od = self._o0, self._od
        o = (o0[0] + od[0] * tau, o0[1] + od[1] * tau, o0[2] + od[2] * tau)
        return o, _rotate(self._om, tau, self._n0), _rotate(self._om, tau, self._y0)

    def land(self, palm: np.ndarray, t_s: np.ndarray, k: int, t_land: float,
             v_ball: np.ndarray) -> None:
        """The ball meets the palm target at ``t_land`` (between rows ``k`` and ``k + 1``)
        at ``v_ball``, without spin."""
        self._segment(palm, t_s, k)
        o, n, _ = self._plane(t_land)
        r = self.r
        self.p = (o[0] + r * n[0], o[1] + r * n[1], o[2] + r * n[2])
        self.v = tuple(float(x) for x in v_ball)
        self.w = (0.0, 0.0, 0.0)
        self.t = t_land

    def step_to(self, palm: np.ndarray, t_s: np.ndarray, k: int) -> float:
        """Moves the ball on to row ``k``; its place along the palm's +y from the palm
        target there (m)."""
        self._segment(palm, t_s, k - 1)
        t_end = float(t_s[k])
        while self.t < t_end - 1e-12:
            h = min(ROLL_STEP_S, t_end - self.t)
            self._step(h)
            self.t += h
        P = palm[k]
        r = self.r
        c = P[:3, 3] + r * P[:3, 2]
        return float((np.array(self.p) - c) @ P[:3, 1])

    def along_speed(self, palm: np.ndarray) -> float:
        """The ball's speed along the palm's +y relative to the palm target (m/s), at the
        end of the segment last stepped (row ``k`` of ``step_to``), ``palm`` its rows."""
        P = palm[self._seg + 1]
        od, om, r = np.array(self._od), np.array(self._om), self.r
        target_v = od + np.cross(om, r * P[:3, 2])
        return float((np.array(self.v) - target_v) @ P[:3, 1])

    def _step(self, h: float) -> None:
        r, beta, mu = self.r, self.beta, self.mu
        o, n, y = self._plane(self.t)
        px, py, pz = self.p
        vx, vy, vz = self.v[0] + _GX * h, self.v[1] + _GY * h, self.v[2] + _GZ * h
        wx, wy, wz = self.w
        nx, ny, nz = n
        gap = (px - o[0]) * nx + (py - o[1]) * ny + (pz - o[2]) * nz - r
        if gap < 0.0:  # (the palm moved into the ball: onto its surface)
            px, py, pz = px - gap * nx, py - gap * ny, pz - gap * nz
            gap = 0.0
        if gap <= CONTACT_GAP_M:
            qx, qy, qz = px - r * nx - o[0], py - r * ny - o[1], pz - r * nz - o[2]
            om, od = self._om, self._od
            # the palm's velocity at the contact point, and the ball's there
            ux = vx + (wy * -r * nz - wz * -r * ny) - (od[0] + om[1] * qz - om[2] * qy)
            uy = vy + (wz * -r * nx - wx * -r * nz) - (od[1] + om[2] * qx - om[0] * qz)
            uz = vz + (wx * -r * ny - wy * -r * nx) - (od[2] + om[0] * qy - om[1] * qx)
            un = ux * nx + uy * ny + uz * nz
            jn = max(0.0, -(un + gap / h))  # per unit mass: no approach past the palm
            tx, ty, tz = ux - un * nx, uy - un * ny, uz - un * nz
            s = beta / (1.0 + beta)  # the share of the slip a stick impulse takes
            jx, jy, jz = -s * tx, -s * ty, -s * tz
            jt = math.sqrt(jx * jx + jy * jy + jz * jz)
            if jt > mu * jn:  # Coulomb: it slides
                f = mu * jn / jt
                jx, jy, jz = jx * f, jy * f, jz * f
            vx, vy, vz = vx + jn * nx + jx, vy + jn * ny + jy, vz + jn * nz + jz
            k = -r / (beta * r * r)  # (-R n) x J / (beta R^2), per unit mass
            wx += k * (ny * jz - nz * jy)
            wy += k * (nz * jx - nx * jz)
            wz += k * (nx * jy - ny * jx)
        px, py, pz = px + vx * h, py + vy * h, pz + vz * h
        # the palm's cup and the fingers: not past the palm target towards the fingers
        cx, cy, cz = o[0] + r * nx - px, o[1] + r * ny - py, o[2] + r * nz - pz
        along = -(cx * y[0] + cy * y[1] + cz * y[2])
        if along < 0.0:
            px, py, pz = px - along * y[0], py - along * y[1], pz - along * y[2]
            od, om = self._od, self._om  # the palm target's velocity: od + om x (R n)
            ex = od[0] + r * (om[1] * nz - om[2] * ny)
            ey = od[1] + r * (om[2] * nx - om[0] * nz)
            ez = od[2] + r * (om[0] * ny - om[1] * nx)
            vy_rel = (vx - ex) * y[0] + (vy - ey) * y[1] + (vz - ez) * y[2]
            if vy_rel < 0.0:
                vx, vy, vz = vx - vy_rel * y[0], vy - vy_rel * y[1], vz - vy_rel * y[2]
        self.p, self.v, self.w = (px, py, pz), (vx, vy, vz), (wx, wy, wz)

"""The least motor load any stop of a throw needs: a bound, not a plan.

The planner's stop (``planner.catch.plan.stopping``) searches one family of motions; where
none of them keeps every motor within its capacity the throw is "too fast to stop". This
module asks the wider question by a linear programme (``scipy.optimize.linprog``, HiGHS)
over every motion of the arm in a time grid: the least share ``s`` of their capacity that
the arm's motors (rail, reach, wrist flexion and deviation) must reach in any stop of the
ball within these rules:

* the arm (its joints ``StopDynamics.arm``) starts at rest, puts the palm's target (the
  ball's centre on the palm) on the ball when it arrives, and ends at rest with the ball
  at rest on the palm; every joint within its speed and acceleration limits (the hand
  file's, without the planner's margins), the wrist's joints within their range about the
  intercept pose and the rig's prismatic axes (rail, reach: the dynamics do not depend on
  where along them the hand is) within their travel's length wherever the intercept is;
* the ball, from its touch on, stays on the pad: its centre at most the pad's give
  (the hand's pad, ``HandModel.pad_give_m``) into the palm along the palm's normal (a ball that leaves the palm is
  dropped by the check's rule), across the palm within its half width (the palm link's
  box) and towards the wrist within the check's roll room (``ROLL_ROOM_M``); the palm's
  force on it anywhere in the pyramid around the friction cone (``PALM_MU``), any profile
  in time (a spring pad gives one of them);
* the motors' torques: the arm's joint torques (its mass matrix at the intercept pose,
  gravity, the pad's force through the palm centre's Jacobian) through the motor map.

What makes it a bound (every simplification widens the set of motions): the forces are
free within the cone and the pad's give, the fingers' motors and the jerk bounds are left
out, the intercept may lie anywhere along the rig's axes. What makes it a model: the
mass matrix, gravity and Jacobians are the intercept pose's (the wrist turns 0.1-0.3 rad
during a stop), the speeds' Coriolis terms are left out, the fingers are rigid in their
pose, and the time grid holds the accelerations and forces constant over each step
(``BoundGrid.dt_s``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy import sparse
from scipy.optimize import linprog

from planner.catch.plan.arm import palm_target
from planner.catch.plan.reasons import CatchReason, Reason
from planner.catch.plan.stopping import StopDynamics
from planner.check.ballroll import ROLL_ROOM_M
from planner.check.ballstop import PALM_MU
from planner.check.motormap import motor_torque_matrix

GRAVITY_M_S2 = np.array([0.0, 0.0, -9.81])  # the catch frame's z is up (spec section 5)
_FD = 1e-6  # finite-difference step of the Jacobians (rad or m)


@dataclass(frozen=True)
class BoundGrid:
    """The linear programme's time grid: ``pre_s`` before the ball's touch (the arm starts
    at rest at its start), ``post_s`` after it (the arm and the ball at rest at its end),
    steps of ``dt_s``."""

    dt_s: float = 0.005  # (0 m / 75 deg / 3.0 m: 0.207; without the ball's place across
    # the palm bounded, 0.1995 at 1 and at 2 ms steps, where the programme takes 3-25 s of
    # CPU against 0.3 s here)
    pre_s: float = 0.15
    post_s: float = 0.25


@dataclass(frozen=True)
class StopBound:
    """The least share of its capacity the most loaded arm motor reaches in any stop of the
    throw (``share``; inf: no stop at all within the joints' limits), that motor's name and
    torque (N m), and the optimum's motion: the arm's accelerations ``acc`` (steps x arm
    joints), the palm's force on the ball ``force_n`` (steps after the touch x 3)."""

    share: float
    motor: str
    torque_nm: float
    capacity_nm: float
    acc: np.ndarray
    force_n: np.ndarray
    grid: BoundGrid


@dataclass(frozen=True)
class PoseTerms:
    """What the programme reads of the intercept pose: the arm's mass matrix ``H`` and
    gravity torques ``g``, the palm centre's and the palm target's Jacobians over the arm
    (3 x k, catch frame), the palm's normal ``n``, its axes across (``x``) and towards the
    wrist (``y``) and its half width (m), the arm motors' map ``Mm`` (motors x k) with their
    names and capacities."""

    H: np.ndarray
    g: np.ndarray
    J_centre: np.ndarray
    J_target: np.ndarray
    n: np.ndarray
    x: np.ndarray
    y: np.ndarray
    half_width_m: float
    Mm: np.ndarray
    motors: tuple[str, ...]
    cap: np.ndarray
    pad_give_m: float  # the palm pad's give (``HandModel.pad_give_m``)


def pose_terms(dyn: StopDynamics, q: np.ndarray, radius_m: float) -> PoseTerms:
    """``PoseTerms`` of the pose ``q`` for a ball of ``radius_m``."""
    hand, arm = dyn.hand, list(dyn.arm)
    m, data = hand.pin_model, hand.pin_model.createData()
    idx = np.array([m.idx_qs[m.getJointId(nm)] for nm in hand.joint_names])
    qp = np.zeros(m.nq)
    qp[idx] = q
    H_full = pin.crba(m, data, qp)
    H_full = np.triu(H_full) + np.triu(H_full, 1).T
    ia = idx[arm]
    H = H_full[np.ix_(ia, ia)]
    z = np.zeros(len(arm))
    g = dyn.joint_torques(q, z, z)[arm]
    J_c, J_t = np.empty((3, len(arm))), np.empty((3, len(arm)))
    c0, t0 = palm_target(hand, q, 0.0), palm_target(hand, q, radius_m)
    for c, i in enumerate(arm):
        dq = q.copy()
        dq[i] += _FD
        J_c[:, c] = (palm_target(hand, dq, 0.0) - c0) / _FD
        J_t[:, c] = (palm_target(hand, dq, radius_m) - t0) / _FD
    P = hand.palm_pose(q)
    palm = next(link for link in hand.spec.links if link.name == "palm")
    M_all = motor_torque_matrix(hand, q)[:, arm]
    rows = np.flatnonzero(np.abs(M_all).sum(axis=1) > 1e-12)  # the arm's motors
    cap = dyn.cap[rows]
    names = tuple(hand.motor_names[r] for r in rows)
    return PoseTerms(H, g, J_c, J_t, P[:3, 2], P[:3, 0], P[:3, 1], 0.5 * palm.size_m[0],
                     M_all[rows], names, cap, hand.pad_give_m)


class Layout:
    """Column offsets of the programme's variables (``StopProgram.layout``)."""

    def __init__(self, n_pre: int, n_post: int, k: int) -> None:
        n_steps = n_pre + n_post
        self.k, self.N, self.P, self.pre = k, n_steps, n_post, n_pre
        self.a = 0                          # arm accelerations, N x k
        self.v = self.a + n_steps * k       # arm speeds at the N + 1 knots
        self.p = self.v + (n_steps + 1) * k  # arm positions (about the intercept pose)
        self.f = self.p + (n_steps + 1) * k  # force on the ball, P x 3
        self.u = self.f + n_post * 3        # ball velocity at the P + 1 knots after touch
        self.b = self.u + (n_post + 1) * 3  # ball position (about the touch)
        self.lo = self.b + (n_post + 1) * 3  # each prismatic axis' lowest position
        self.s = self.lo + k                # the load share
        self.total = self.s + 1


class SparseRows:
    """Sparse rows of a programme, one kind (equalities or upper bounds; also the stop
    optimised on the rows', ``planner.catch.plan.stoprows``)."""

    def __init__(self) -> None:
        self.r: list[int] = []
        self.c: list[int] = []
        self.v: list[float] = []
        self.rhs: list[float] = []

    def add(self, cols_vals: list[tuple[int, float]], rhs: float) -> None:
        row = len(self.rhs)
        for c, v in cols_vals:
            self.r.append(row)
            self.c.append(c)
            self.v.append(v)
        self.rhs.append(rhs)

    def both(self, cols_vals: list[tuple[int, float]], base: float, bound: float) -> None:
        """|base + cols_vals . x| <= bound (two upper-bound rows)."""
        self.add(cols_vals, bound - base)
        self.add([(c, -v) for c, v in cols_vals], bound + base)

    def matrix(self, n_cols: int) -> sparse.csr_matrix:
        return sparse.csr_matrix((self.v, (self.r, self.c)), shape=(len(self.rhs), n_cols))


@dataclass(frozen=True)
class StopProgram:
    """The linear programme of one throw (``stop_program``): minimise ``c @ x`` subject to
    ``A_ub x <= b_ub``, ``A_eq x = b_eq`` and ``bounds``; ``layout`` names the columns,
    ``terms`` the pose's."""

    c: np.ndarray
    A_ub: sparse.csr_matrix
    b_ub: np.ndarray
    A_eq: sparse.csr_matrix
    b_eq: np.ndarray
    bounds: tuple
    layout: Layout
    terms: PoseTerms
    grid: BoundGrid


def _integrators(eq: SparseRows, V: Layout, dt: float, v_ball: np.ndarray, mass_kg: float) -> None:
    """The arm (a double integrator per joint: at rest at both ends, at the intercept pose
    at the touch, knot ``V.pre``) and the ball after its touch (the palm's force and
    gravity: it arrives at the target with ``v_ball`` and ends at rest)."""
    k, N = V.k, V.N
    for j in range(k):
        eq.add([(V.v + j, 1.0)], 0.0)
        eq.add([(V.v + N * k + j, 1.0)], 0.0)
        eq.add([(V.p + V.pre * k + j, 1.0)], 0.0)
        for s in range(N):
            a, v0, v1 = V.a + s * k + j, V.v + s * k + j, V.v + (s + 1) * k + j
            p0, p1 = V.p + s * k + j, V.p + (s + 1) * k + j
            eq.add([(v1, 1.0), (v0, -1.0), (a, -dt)], 0.0)
            eq.add([(p1, 1.0), (p0, -1.0), (v0, -dt), (a, -0.5 * dt * dt)], 0.0)
    g = GRAVITY_M_S2
    for x in range(3):
        eq.add([(V.u + x, 1.0)], float(v_ball[x]))
        eq.add([(V.b + x, 1.0)], 0.0)
        for s in range(V.P):
            f, u0, u1 = V.f + s * 3 + x, V.u + s * 3 + x, V.u + (s + 1) * 3 + x
            b0, b1 = V.b + s * 3 + x, V.b + (s + 1) * 3 + x
            eq.add([(u1, 1.0), (u0, -1.0), (f, -dt / mass_kg)], g[x] * dt)
            eq.add([(b1, 1.0), (b0, -1.0), (u0, -dt), (f, -0.5 * dt * dt / mass_kg)],
                   0.5 * g[x] * dt * dt)
        eq.add([(V.u + V.P * 3 + x, 1.0)], 0.0)


def cone_tangents(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents of the palm's normal ``n``, orthogonal to it and each other."""
    t1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1)


def _contact(ub: SparseRows, V: Layout, T: PoseTerms) -> None:
    """The ball on the pad (0 <= n . (target - ball) <= the pad's give, |x . (ball -
    target)| <= the palm's half width, y . (ball - target) <= the roll room, at every knot
    after the touch) and the force in the pyramid around the cone (|f . t_i| <= mu f . n)."""
    k, n = V.k, T.n
    for s in range(1, V.P + 1):
        for axis, lo, hi in ((n, 0.0, T.pad_give_m), (-T.x, -T.half_width_m, T.half_width_m),
                             (-T.y, None, ROLL_ROOM_M)):
            cols = [(V.p + (V.pre + s) * k + j, float(axis @ T.J_target[:, j]))
                    for j in range(k)]
            cols += [(V.b + s * 3 + x, -float(axis[x])) for x in range(3)]
            ub.add(cols, hi)
            if lo is not None:
                ub.add([(c, -v) for c, v in cols], -lo)
    tangents = cone_tangents(n)
    for s in range(V.P):
        fc = [V.f + s * 3 + x for x in range(3)]
        ub.add([(fc[x], -float(n[x])) for x in range(3)], 0.0)
        for t in tangents:
            for sg in (1.0, -1.0):
                ub.add([(fc[x], float(sg * t[x] - PALM_MU * n[x])) for x in range(3)], 0.0)


def _motors(ub: SparseRows, V: Layout, T: PoseTerms) -> None:
    """|Mm (H a + g + J_c^T f)| <= s cap at every step (the force from the touch on)."""
    k = V.k
    MH, MJ, Mg = T.Mm @ T.H, T.Mm @ T.J_centre.T, T.Mm @ T.g
    for s in range(V.N):
        post = s - V.pre
        for r in range(len(T.motors)):
            cols = [(V.a + s * k + j, float(MH[r, j])) for j in range(k)]
            if post >= 0:
                cols += [(V.f + post * 3 + x, float(MJ[r, x])) for x in range(3)]
            ub.add(cols + [(V.s, -float(T.cap[r]))], -float(Mg[r]))
            ub.add([(c, -v) for c, v in cols] + [(V.s, -float(T.cap[r]))], float(Mg[r]))


def _limits(ub: SparseRows, V: Layout, dyn: StopDynamics, q: np.ndarray) -> list:
    """The joints' speed and acceleration limits (bounds), the wrist's range about the pose
    (bounds) and the prismatic axes' travel's length (rows); the bounds' list."""
    hand, arm, k = dyn.hand, list(dyn.arm), V.k
    bounds: list = [(None, None)] * V.total
    vel, acc = hand.velocity[arm], hand.acceleration[arm]
    for j, i in enumerate(arm):
        for s in range(V.N):
            bounds[V.a + s * k + j] = (-float(acc[j]), float(acc[j]))
        prismatic = hand.joint_names[i] in hand.rig_joints
        for s in range(V.N + 1):
            bounds[V.v + s * k + j] = (-float(vel[j]), float(vel[j]))
            p = V.p + s * k + j
            if prismatic:
                ub.add([(V.lo + j, 1.0), (p, -1.0)], 0.0)
                ub.add([(p, 1.0), (V.lo + j, -1.0)], float(hand.upper[i] - hand.lower[i]))
            else:
                bounds[p] = (float(hand.lower[i] - q[i]), float(hand.upper[i] - q[i]))
    bounds[V.s] = (0.0, None)
    return bounds


def stop_program(dyn: StopDynamics, q: np.ndarray, v_ball: np.ndarray, mass_kg: float,
                 radius_m: float, grid: BoundGrid = BoundGrid()) -> StopProgram:
    """The linear programme of ``least_stop_load`` (see the module docstring)."""
    T = pose_terms(dyn, q, radius_m)
    dt = grid.dt_s
    V = Layout(round(grid.pre_s / dt), round(grid.post_s / dt), len(dyn.arm))
    eq, ub = SparseRows(), SparseRows()
    _integrators(eq, V, dt, np.asarray(v_ball, dtype=float), mass_kg)
    _contact(ub, V, T)
    _motors(ub, V, T)
    bounds = _limits(ub, V, dyn, q)
    c = np.zeros(V.total)
    c[V.s] = 1.0
    return StopProgram(c, ub.matrix(V.total), np.array(ub.rhs), eq.matrix(V.total),
                       np.array(eq.rhs), tuple(bounds), V, T, grid)


def solve_program(P: StopProgram, c: np.ndarray | None = None):
    """``linprog``'s result for ``P`` (its own objective, or ``c``)."""
    return linprog(P.c if c is None else c, A_ub=P.A_ub, b_ub=P.b_ub, A_eq=P.A_eq,
                   b_eq=P.b_eq, bounds=list(P.bounds), method="highs")


def least_stop_load(dyn: StopDynamics, q: np.ndarray, v_ball: np.ndarray, mass_kg: float,
                    radius_m: float, grid: BoundGrid = BoundGrid()) -> StopBound:
    """The least load share of the arm's motors over every stop of a ball arriving with
    velocity ``v_ball`` (catch frame) where the hand in pose ``q`` has its palm's target on
    it (see the module docstring)."""
    P = stop_program(dyn, q, v_ball, mass_kg, radius_m, grid)
    V, T = P.layout, P.terms
    res = solve_program(P)
    if res.status == 2:  # infeasible: no stop within the joints' limits at all
        return StopBound(math.inf, "", math.inf, 0.0, np.zeros((V.N, V.k)),
                         np.zeros((V.P, 3)), grid)
    if res.status != 0:
        raise RuntimeError(f"stop bound: linprog failed ({res.message})")
    acc_x, f_x = motion_of(P, res.x)
    loads = motor_loads(T, acc_x, f_x, V.pre)
    worst = int(np.argmax(np.abs(loads).max(axis=0) / T.cap))
    return StopBound(float(res.x[V.s]), T.motors[worst], float(np.abs(loads[:, worst]).max()),
                     float(T.cap[worst]), acc_x, f_x, grid)


def motion_of(P: StopProgram, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The arm's accelerations (steps x k) and the palm's force on the ball (steps after
    the touch x 3) of the programme's solution ``x``."""
    V = P.layout
    return (x[V.a:V.a + V.N * V.k].reshape(V.N, V.k).copy(),
            x[V.f:V.f + V.P * 3].reshape(V.P, 3).copy())


def motor_loads(T: PoseTerms, acc: np.ndarray, force_n: np.ndarray, n_pre: int
                ) -> np.ndarray:
    """The arm motors' torques (steps x motors) of a motion: accelerations ``acc`` (steps x
    k), the palm's force on the ball ``force_n`` from step ``n_pre`` on."""
    tau = acc @ T.H.T + T.g
    tau[n_pre:] += force_n @ T.J_centre
    return tau @ T.Mm.T


def bounded_reasons(reasons: tuple[Reason, ...], dyn: StopDynamics, q: np.ndarray,
                    v_ball: np.ndarray, mass_kg: float, radius_m: float
                    ) -> tuple[Reason, ...]:
    """``reasons`` with its "too fast to stop" judged by the stop bound at the intercept
    pose ``q`` (ball arriving with ``v_ball``): a hard limit, its number the bound's, where
    every stop needs more than a motor's capacity; else the planner's shortfall
    (``CatchReason.NO_STOP``), the bound's number beside the planner's."""
    out = []
    for r in reasons:
        if r.kind is not CatchReason.TOO_FAST_TO_STOP:
            out.append(r)
            continue
        b = least_stop_load(dyn, q, v_ball, mass_kg, radius_m)
        if math.isinf(b.share):
            out.append(Reason(r.kind, (
                f"{r.detail}; no stop of the arm within its joints' speed, acceleration and "
                "travel keeps the ball on the pad (the stop bound)")))
        elif b.share > 1.0:
            out.append(Reason(r.kind, (
                f"{r.detail}; any stop of the arm needs motor.{b.motor} at {b.torque_nm:.2f} "
                f"N m or more > its {b.capacity_nm:.2f} N m (the stop bound)")))
        else:
            out.append(Reason(CatchReason.NO_STOP, (
                f"no stop found, not a hard limit: {r.detail}; a stop of the arm within "
                f"every motor's capacity is not excluded (the stop bound: motor.{b.motor} at "
                f"{b.share:.2f} of its {b.capacity_nm:.2f} N m, the hand's inertia about the "
                "wrist taking the ball's push)")))
    return tuple(out)

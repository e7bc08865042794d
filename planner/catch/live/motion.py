"""The motion of a live catch (``planner.catch.live.session``): the hand at rest, the move to
the open pose, the arm re-aimed at every newer intercept, the fingers' closing move.

* Fingers: a min-jerk phase from the rest pose to the open one (``trajectory.Phase``;
  the open fingers are the same for every throw of a ball size) starting at ``t_move``,
  then the closing phase from ``close_start_s``: the catch planner's moves.
* Arm (rail, wrist flexion and deviation): a ``Quintic`` from the state (q, dq, ddq) it
  has at ``t0`` to the newest intercept pose, at rest, at ``t0 + duration``. The first
  one starts at rest at ``t_move`` (a min-jerk move, as the planner's) and lasts as long
  as the fingers' phase; each re-plan replaces it by one from the state of the rows
  already written, so the rows stay twice continuously differentiable and the written
  rows never change. Its duration: the longer of the old one's remaining time and the
  min-jerk duration of the change (``trajectory.phase_duration``), lengthened (up to
  ``GROW ** MAX_GROW`` times, by bisection) until its speed, acceleration and position stay within every arm joint's
  limits, and its accelerations keep every motor within ``STOP_SHARE`` of its capacity
  as it moves the hand's inertia (``StopDynamics.accel_room``: the rule of the planner's
  own moves), on a grid of ``VERIFY_STEP_S`` (a quintic that starts moving may
  overshoot); and it must end, the arm at rest, by ``rest_by_s`` (the check judges the
  stopping of the ball on the rows with the hand's inertia, ``planner.check.ball``: an
  arm still re-aiming when the ball arrives adds its acceleration's torque to the
  pad's). When none does, the arm goes part of the way (``PART_SHARES``), or keeps
  the old target.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from planner.catch.plan.arm import move_time as move_in_time
from planner.catch.plan.stopping import StopDynamics
from planner.hand.model import HandModel
from planner.trajectory import min_jerk, phase_duration

GROW = 1.25  # a re-aim that leaves the limits may last up to GROW^MAX_GROW (~6x) its
MAX_GROW = 8  # shortest duration ...
BISECT = 3  # ... the shortest that holds found to 1/8 of the span by bisection
VERIFY_STEP_S = 0.001  # the limits are verified on this grid (rows are 2-10 ms apart)
PART_SHARES = (1.0, 0.5, 0.25)  # a re-aim that cannot reach its target in time goes this
# share of the way (the arm closer to the newest estimate than the older target)
STILL_MARGIN_S = 0.002  # the arm at rest this much before the rows the check reads at the
# intercept: 2 sigma of the intercept time late in the flight (~1 ms for a 5 mm camera),
# which later estimates may move


def rest_by_s(t_i: float, dt: float) -> float:
    """When the arm must be at rest for a ball meeting the palm at ``t_i`` on rows ``dt``
    apart: the check's stopping load (``planner.check.ball.ball_loads``) takes the arm's
    speed from the rows around ``t_i`` and its accelerations from their central
    differences, the first of them at the row at or before ``t_i`` (its neighbours with
    it); so the arm holds still from the row before that one (``STILL_MARGIN_S``
    earlier)."""
    return (math.floor((t_i - STILL_MARGIN_S) / dt + 1e-9) - 1) * dt


@dataclass(frozen=True)
class Quintic:
    """A move of the arm joints from (q0, v0, a0) at ``t0`` to (q1, 0, 0) at ``t0 +
    duration_s``, held there after (q(t) = q0 + v0 tau + a0 tau^2 / 2 + c3 tau^3 + c4
    tau^4 + c5 tau^5, tau = t - t0; the boundary conditions fix c3..c5)."""

    t0: float
    duration_s: float
    q0: np.ndarray
    v0: np.ndarray
    a0: np.ndarray
    q1: np.ndarray
    c: np.ndarray  # (3, k): c3, c4, c5

    @classmethod
    def between(cls, t0: float, duration_s: float, q0: np.ndarray, v0: np.ndarray,
                a0: np.ndarray, q1: np.ndarray) -> Quintic:
        D = float(duration_s)
        return cls(float(t0), D, q0, v0, a0, q1, _coefficients(D, np.stack([q1 - q0, v0, a0])))

    @classmethod
    def hold(cls, q: np.ndarray) -> Quintic:
        z = np.zeros_like(q)
        return cls(0.0, 1.0, q, z, z, q, np.zeros((3, len(q))))

    @property
    def end_s(self) -> float:
        return self.t0 + self.duration_s

    def state(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, speeds and accelerations (T, k) at times ``t_s`` (clamped to the move:
        q0 before it, q1 after)."""
        tau = np.clip(np.asarray(t_s, dtype=float) - self.t0, 0.0, self.duration_s)[:, None]
        c3, c4, c5 = self.c
        q = self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))
        v = self.v0 + tau * (self.a0 + tau * (3 * c3 + tau * (4 * c4 + tau * 5 * c5)))
        a = self.a0 + tau * (6 * c3 + tau * (12 * c4 + tau * 20 * c5))
        after = (np.asarray(t_s) >= self.end_s)[:, None]
        return q, np.where(after, 0.0, v), np.where(after, 0.0, a)

    def state1(self, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``state`` at one time (k,) each, with the time's arithmetic in floats."""
        tau = min(max(t_s - self.t0, 0.0), self.duration_s)
        c3, c4, c5 = self.c
        q = self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))
        if t_s >= self.end_s:
            z = np.zeros_like(q)
            return q, z, z
        v = self.v0 + tau * (self.a0 + tau * (3 * c3 + tau * (4 * c4 + tau * 5 * c5)))
        a = self.a0 + tau * (6 * c3 + tau * (12 * c4 + tau * 20 * c5))
        return q, v, a

    def position1(self, t_s: float) -> np.ndarray:
        """``positions`` at one time (k,), the time's arithmetic in floats (the same
        numbers: the same operations on the same doubles)."""
        tau = min(max(t_s - self.t0, 0.0), self.duration_s)
        c3, c4, c5 = self.c
        return self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))

    def positions(self, t_s: np.ndarray) -> np.ndarray:
        """``state``'s positions alone (what a row needs)."""
        tau = np.minimum(np.maximum(t_s - self.t0, 0.0), self.duration_s)[:, None]
        c3, c4, c5 = self.c
        return self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))

    def within(self, lo: np.ndarray, hi: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
               step_s: float, motors: np.ndarray | None = None,
               room: np.ndarray | None = None) -> bool:
        """Positions in [lo, hi], |speed| <= v_max, |acceleration| <= a_max on a grid of
        ``step_s`` over the move (both ends included); ``motors`` (m, k), ``room`` (m,):
        also |motors @ acceleration| <= room there (``LiveMotion.reaim``'s motor rule)."""
        return self.within_bounds(*quintic_bounds(lo, hi, v_max, a_max, room), step_s, motors)

    def within_bounds(self, lb: np.ndarray, ub: np.ndarray, step_s: float,
                      motors: np.ndarray | None = None) -> bool:
        """``within`` with its bounds as two rows (``quintic_bounds``: positions, speeds,
        accelerations, then the motors' torques): ``MoveCheck.holds`` of this move."""
        return MoveCheck(self.q0, self.v0, self.a0, self.q1, lb, ub, step_s, motors).holds(
            self.duration_s, self.c)


def _coefficients(D: float, X: np.ndarray) -> np.ndarray:
    """(c3, c4, c5) (3, k) of the quintic lasting ``D`` with the boundary conditions ``X``
    = [q1 - q0; v0; a0]: B(D) X, their solution, one product for the k joints."""
    D2, D3 = D * D, D * D * D
    B = np.array([[10.0 / D3, -6.0 / D2, -1.5 / D],
                  [-15.0 / (D3 * D), 8.0 / D3, 1.5 / D2],
                  [6.0 / (D3 * D2), -3.0 / (D3 * D), -0.5 / D3]])
    return B @ X


class MoveCheck:
    """The grid check of the arm's moves from (q0, v0, a0) to rest at q1, whatever their
    duration (``LiveMotion.reaim`` tries several): positions, speeds, accelerations and
    ``motors`` @ accelerations within [lb, ub] (``quintic_bounds``) on a grid of ``step_s`` over
    the move (both ends included). Every quantity on the grid is a polynomial in tau of
    degree <= 5, so the grid's powers of u = tau / D (one table per number of points,
    ``_unit_grid``) times one coefficient matrix (6, 3k + m) give all of them in one
    product; the start's part of it (q0, v0, a0) is set once."""

    def __init__(self, q0: np.ndarray, v0: np.ndarray, a0: np.ndarray, q1: np.ndarray,
                 lb: np.ndarray, ub: np.ndarray, step_s: float,
                 motors: np.ndarray | None = None) -> None:
        self.ends = (q0, v0, a0, q1)
        self.X = np.stack([q1 - q0, v0, a0])  # the boundary conditions (``_coefficients``)
        self.rows = np.empty((6, len(q0)))  # (q0, v0, a0, c3, c4, c5)
        self.rows[0], self.rows[1], self.rows[2] = q0, v0, a0
        self.lb, self.ub, self.step_s, self.motors = lb, ub, step_s, motors
        self.held: tuple[float, np.ndarray] | None = None  # the last move that held: D, c

    def move(self, t0: float) -> Quintic:
        """The last move that held, from ``t0`` (``Quintic.between``'s: the same c)."""
        D, c = self.held
        return Quintic(float(t0), D, *self.ends, c)

    def holds(self, D: float, c: np.ndarray | None = None) -> bool:
        """Whether the move lasting ``D`` (its (c3, c4, c5) ``c``, else computed as
        ``Quintic.between`` does) stays within the bounds on its grid."""
        c = _coefficients(D, self.X) if c is None else c
        self.rows[3:] = c
        k = self.rows.shape[1]
        # the coefficients of u^0..5 of q, v and a (3 blocks of 6 rows): _POWERS times
        # (q0, v0, a0, c3, c4, c5), row p times D^p
        D2 = D * D
        qva = ((_POWERS @ self.rows).reshape(3, 6, k)
               * np.array([1.0, D, D2, D2 * D, D2 * D2, D2 * D2 * D])[:, None])
        cols = [qva[0], qva[1], qva[2]]
        if self.motors is not None:
            cols.append(qva[2] @ self.motors.T)
        P = _unit_grid(max(2, math.ceil(D / self.step_s) + 1)) @ np.concatenate(cols, axis=1)
        if np.all(P >= self.lb) and np.all(P <= self.ub):
            self.held = (D, c)
            return True
        return False


# (q0, v0, a0, c3, c4, c5) -> the coefficients of tau^0..5 in q, then v, then a
_POWERS = np.zeros((18, 6))
_POWERS[[0, 1, 2, 3, 4, 5], [0, 1, 2, 3, 4, 5]] = (1.0, 1.0, 0.5, 1.0, 1.0, 1.0)
_POWERS[[6, 7, 8, 9, 10], [1, 2, 3, 4, 5]] = (1.0, 1.0, 3.0, 4.0, 5.0)
_POWERS[[12, 13, 14, 15], [2, 3, 4, 5]] = (1.0, 6.0, 12.0, 20.0)


@functools.lru_cache(maxsize=256)
def _unit_grid(n: int) -> np.ndarray:
    """The powers u^0..5 of n points evenly over [0, 1] (n, 6), read-only: a re-aim's
    grid of any duration (``Quintic.within_bounds``); kept per n (a grid of 1 ms steps:
    a move of up to 0.25 s has one of 256 sizes)."""
    T = np.vander(np.linspace(0.0, 1.0, n), 6, increasing=True)
    T.setflags(write=False)
    return T


def _min_jerk1(u: float) -> float:
    """``trajectory.min_jerk`` of one float (its arithmetic, no array)."""
    u = min(max(u, 0.0), 1.0)
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


def quintic_bounds(lo: np.ndarray, hi: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
            room: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``Quintic.within_bounds``' rows: positions in [lo, hi] (1e-12 rad of rounding),
    speeds and accelerations within +-their limits, motor torques within +-``room``."""
    up = [hi + 1e-12, v_max, a_max] + ([room] if room is not None else [])
    down = [lo - 1e-12, -v_max, -a_max] + ([-room] if room is not None else [])
    return np.concatenate(down), np.concatenate(up)


class LiveMotion:
    """The rows' motion: rest, the fingers' phases, the arm's newest ``Quintic``."""

    def __init__(self, hand: HandModel, arm: tuple[int, ...], q_rest: np.ndarray,
                 q_open_fingers: np.ndarray, q_closed_fingers: np.ndarray,
                 dyn: StopDynamics) -> None:
        self.hand, self.dyn = hand, dyn
        self.arm = np.array(arm, dtype=int)
        self.q_rest = q_rest.copy()
        fingers = np.array([i for i in range(hand.n) if i not in arm], dtype=int)
        self._open = np.zeros(hand.n)
        self._open[fingers] = (q_open_fingers - q_rest)[fingers]
        self._close = np.zeros(hand.n)
        self._close[fingers] = (q_closed_fingers - q_open_fingers)[fingers]
        self._lo, self._hi = hand.lower[self.arm], hand.upper[self.arm]
        self._v, self._a = hand.velocity[self.arm], hand.acceleration[self.arm]
        self.seg = Quintic.hold(q_rest[self.arm])
        self.t_move = math.inf
        self.open_s = 0.0
        self.close_start_s = math.inf
        self.close_s = 0.0
        dyn.accel_room(self.q_rest)  # (kept by q: the first move's start, set up here)

    @property
    def moving(self) -> bool:
        return math.isfinite(self.t_move)

    @property
    def fingers_open_s(self) -> float:
        """When the fingers reach the open pose (inf before the move is planned)."""
        return self.t_move + self.open_s

    def start(self, t_s: float, q_open: np.ndarray, duration_s: float) -> None:
        """The move to the open pose ``q_open`` from ``t_s``, lasting ``duration_s``."""
        self.t_move, self.open_s = float(t_s), float(duration_s)
        q0 = self.q_rest[self.arm]
        z = np.zeros_like(q0)
        self.seg = Quintic.between(t_s, duration_s, q0, z, z, q_open[self.arm].copy())

    def set_closing(self, start_s: float, duration_s: float) -> None:
        self.close_start_s, self.close_s = float(start_s), float(duration_s)

    def reaim(self, t_s: float, q_target: np.ndarray, rest_by: float = math.inf) -> float:
        """The arm re-aimed at ``q_target``'s arm joints from its state at ``t_s``, at rest
        by ``rest_by`` (s): the shortest quintic (see the module docstring) within the
        limits and the motors' room. When none reaches the target in time, the arm goes
        as far towards it as one does (``PART_SHARES`` of the change of target). Returns
        the share of the change made (0: the old target kept)."""
        q1 = q_target[self.arm]
        if np.array_equal(q1, self.seg.q1):
            return 1.0
        q, v, a = self.seg.state1(t_s)
        D_max = rest_by - t_s
        # every motor at either end of the move (rows: the start's, then the end's)
        MH, room = (np.concatenate(x) for x in zip(*self._ends(self.row1(t_s, q), q_target)))
        # (the acceleration it starts with is the move's it replaces: allowed as it is)
        lb, ub = quintic_bounds(self._lo, self._hi, self._v, self._a, np.maximum(room, np.abs(MH @ a)))

        for share in PART_SHARES:
            goal = self.seg.q1 + share * (q1 - self.seg.q1)
            # no sooner than the move it replaces would end (unless that is too late)
            D = max(min(self.seg.end_s - t_s, D_max), VERIFY_STEP_S,
                    phase_duration(goal - q, self._v, self._a) if np.any(goal != q) else 0.0)
            if D > D_max + 1e-12:
                continue
            check = MoveCheck(q, v, a, goal, lb, ub, VERIFY_STEP_S, MH)
            if not check.holds(D):  # the longest allowed, then the shortest between that holds
                hi = min(D * GROW ** MAX_GROW, D_max)
                if not (hi > D and check.holds(hi)):
                    continue
                for _ in range(BISECT):
                    mid = 0.5 * (D + hi)
                    if check.holds(mid):
                        hi = mid
                    else:
                        D = mid
            self.seg = check.move(t_s)  # (the last that held: D, or the bisection's hi)
            return share
        return 0.0

    def _ends(self, q_from: np.ndarray, q_to: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """The motors' room for the arm's accelerations at either end of a move
        (``StopDynamics.accel_room``; the arm's columns: the fingers' own phases are not
        the arm's to bound, as in the check's stopping load)."""
        return [(MH[:, self.arm], room) for MH, room in map(self.dyn.accel_room, (q_from, q_to))]

    def move_time(self, q_from: np.ndarray, q_to: np.ndarray) -> float:
        """The first move's duration (min-jerk, from rest): the planner's
        (``StopDynamics.move_time``), the arm's accelerations alone within the motors' room
        too, as every re-aim's (``_ends``), so that a re-aim can start from it; within
        the joints' jerk bounds (``arm.move_time``)."""
        return move_in_time(self.dyn, q_from, q_to, arm_alone=True)

    def row1(self, t_s: float, q_arm: np.ndarray) -> np.ndarray:
        """``rows`` at one time whose arm joints are at ``q_arm`` (the newest move's
        ``Quintic.state1`` there), the fingers' phases in floats: the same numbers."""
        Q = self.q_rest + _min_jerk1((t_s - self.t_move) / (self.open_s or 1.0)) * self._open
        Q += _min_jerk1((t_s - self.close_start_s) / (self.close_s or 1.0)) * self._close
        Q[self.arm] = q_arm
        return self.hand.apply_couplings(Q)

    def rows(self, t_s: np.ndarray, seg: Quintic | None = None, t_new_s: float = math.inf
             ) -> np.ndarray:
        """Joint positions at times ``t_s`` (couplings applied): the fingers' phases
        (``trajectory.sample``'s sum, on the finger joints) and the arm on ``seg`` (the arm's
        move to use instead of the newest) up to ``t_new_s``, on the newest after it. One
        time (a live observation's usual row) in floats, ``row1``: the same numbers."""
        if len(t_s) == 1:
            t = float(t_s[0])
            arm_seg = seg if seg is not None and t <= t_new_s else self.seg
            return self.row1(t, arm_seg.position1(t))[None, :]
        Q = self.q_rest + min_jerk((t_s - self.t_move) / (self.open_s or 1.0))[:, None] * self._open
        Q += min_jerk((t_s - self.close_start_s) / (self.close_s or 1.0))[:, None] * self._close
        arm = self.seg.positions(t_s)
        if seg is not None:
            old = t_s <= t_new_s
            if old.any():
                arm[old] = seg.positions(t_s[old])
        Q[:, self.arm] = arm
        return self.hand.apply_couplings(Q)

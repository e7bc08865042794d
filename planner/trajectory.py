"""Keyframes -> a timed, smooth trajectory within the hand's speed and acceleration limits.

The motion between two held configurations is a chain of *phases*; each
phase moves every joint from ``q_a`` to ``q_b`` along the quintic
minimum-jerk profile s(u) = 10u^3 - 15u^4 + 6u^5 (zero speed and
acceleration at both ends). Its duration is the shortest that keeps every
joint within its speed and acceleration limit: peak |ds/du| = 15/8 and peak
|d2s/du2| = 10/sqrt(3), so T >= 1.875 |dq|/v_max and T >= sqrt(5.7735 |dq| /
a_max). Joint position limits hold because every sample is a convex
combination of two configurations inside them; linear couplings hold
because they are linear.

*When* each phase runs is a quadratic programme (``solve_timing``, OSQP):
phases run one after the other (start of phase p+1 >= end of phase p), and
each phase has an anchor (the moment a key goes down or comes up, at a
known fraction of the phase) that should fall on its ideal time (a note's
onset or release). Minimising the weighted squared anchor errors gives the
start times; where the motors are too slow for the song, the QP spreads
the lateness over the neighbouring notes and the planner reports it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import osqp
import scipy.sparse as sp

from planner.errors import SolverError

PEAK_VEL = 15.0 / 8.0
PEAK_ACC = 10.0 / np.sqrt(3.0)
MIN_PHASE_S = 0.010
LIMIT_MARGIN = 0.98  # plan at 98 % of every speed and acceleration limit


def min_jerk(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


def min_jerk_inverse(s: float) -> float:
    """The u in [0, 1] with min_jerk(u) = s (bisection; s in [0, 1])."""
    lo, hi = 0.0, 1.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if min_jerk(np.array(mid)) < s:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def phase_duration(dq: np.ndarray, v_max: np.ndarray, a_max: np.ndarray, floor_s: float = MIN_PHASE_S) -> float:
    """Shortest duration (s) of a min-jerk move ``dq`` within speed/acceleration limits."""
    adq = np.abs(dq)
    t_v = PEAK_VEL * adq / (LIMIT_MARGIN * v_max)
    t_a = np.sqrt(PEAK_ACC * adq / (LIMIT_MARGIN * a_max))
    return float(max(floor_s, t_v.max(initial=0.0), t_a.max(initial=0.0)))


@dataclass(frozen=True)
class Phase:
    """A move from ``q_a`` to ``q_b`` lasting ``duration_s``; its ``anchor`` fraction
    of the duration should fall at ``ideal_s`` (weight ``weight``)."""

    q_a: np.ndarray
    q_b: np.ndarray
    duration_s: float
    anchor: float
    ideal_s: float
    weight: float = 1.0
    earliest_s: float = 0.0


@dataclass(frozen=True)
class TimingProblem:
    durations: np.ndarray
    anchors: np.ndarray
    ideals: np.ndarray
    weights: np.ndarray
    earliest: np.ndarray
    t0: float


def build_timing(phases: list[Phase], t0: float) -> TimingProblem:
    return TimingProblem(
        np.array([p.duration_s for p in phases]), np.array([p.anchor for p in phases]),
        np.array([p.ideal_s for p in phases]), np.array([p.weight for p in phases]),
        np.array([max(p.earliest_s, t0) for p in phases]), t0)


def solve_timing(prob: TimingProblem) -> np.ndarray:
    """Start times (s) of the phases: min sum w (start + a T - ideal)^2, phases in sequence.

    Variables x_p = start of phase p. Constraints: x_p >= earliest_p (and
    >= t0), x_{p+1} - x_p >= T_p. Solved with OSQP (tight tolerances, then
    polished); the result is made exactly feasible by a forward pass that
    only ever delays a phase by the solver's residual.
    """
    n = len(prob.durations)
    if n == 0:
        return np.zeros(0)
    target = prob.ideals - prob.anchors * prob.durations
    P = sp.diags(prob.weights, format="csc")
    q = -prob.weights * target
    rows = [sp.eye(n, format="csc")]
    lo = [prob.earliest]
    hi = [np.full(n, np.inf)]
    if n > 1:
        D = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n), format="csc")
        rows.append(D)
        lo.append(prob.durations[:-1])
        hi.append(np.full(n - 1, np.inf))
    A = sp.vstack(rows, format="csc")
    solver = osqp.OSQP()
    solver.setup(P=P, q=q, A=A, l=np.concatenate(lo), u=np.concatenate(hi), verbose=False,
                 eps_abs=1e-9, eps_rel=1e-9, max_iter=20000, polishing=True)
    res = solver.solve()
    if res.info.status not in ("solved", "solved inaccurate") or res.x is None:
        raise SolverError(f"timing QP failed: {res.info.status}", problem=prob)
    x = np.array(res.x, dtype=float)
    # exact feasibility (the QP is accurate to ~1e-9 s)
    x[0] = max(x[0], prob.earliest[0])
    for p in range(1, n):
        x[p] = max(x[p], x[p - 1] + prob.durations[p - 1], prob.earliest[p])
    return x


def sample(phases: list[Phase], starts: np.ndarray, t_s: np.ndarray, q_hold: np.ndarray) -> np.ndarray:
    """Joint positions at times ``t_s``: inside a phase its min-jerk blend, between phases the
    configuration last reached (``q_hold`` before the first phase)."""
    out = np.empty((len(t_s), len(q_hold)))
    if not phases:
        out[:] = q_hold
        return out
    idx = np.searchsorted(starts, t_s, side="right") - 1
    Qa = np.array([p.q_a for p in phases])
    Qb = np.array([p.q_b for p in phases])
    T = np.array([p.duration_s for p in phases])
    before = idx < 0
    k = np.clip(idx, 0, len(phases) - 1)
    u = (t_s - starts[k]) / T[k]
    s = min_jerk(u)[:, None]
    out[:] = Qa[k] + (Qb[k] - Qa[k]) * s
    out[before] = q_hold
    return out

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
phases that move a common joint run one after the other, phases on
disjoint joints (two fingers) may overlap and their motions add; each
phase has an anchor (the moment a key goes down or comes up, at a
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
ADAPTIVE_RHO_INTERVAL = 25  # OSQP iterations between rho updates (fixed: deterministic)
LIMIT_MARGIN = 0.98  # plan at 98 % of every speed and acceleration limit


def min_jerk(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


def min_jerk_rates(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ds/du and d2s/du2 of the min-jerk profile (0 outside [0, 1])."""
    inside = (u >= 0.0) & (u <= 1.0)
    w = np.where(inside, u * (1.0 - u), 0.0)
    return 30.0 * w * w, np.where(inside, 60.0 * w * (1.0 - 2.0 * u), 0.0)


def phase_duration(dq: np.ndarray, v_max: np.ndarray, a_max: np.ndarray, floor_s: float = MIN_PHASE_S) -> float:
    """Shortest duration (s) of a min-jerk move ``dq`` within speed/acceleration limits."""
    adq = np.abs(dq)
    t_v = PEAK_VEL * adq / (LIMIT_MARGIN * v_max)
    t_a = np.sqrt(PEAK_ACC * adq / (LIMIT_MARGIN * a_max))
    return float(max(floor_s, t_v.max(initial=0.0), t_a.max(initial=0.0)))


@dataclass(frozen=True)
class Phase:
    """A move of some joints by ``delta`` (the others do not move) lasting ``duration_s``.

    Its ``anchor`` fraction of the duration should fall at ``ideal_s``
    (weight ``weight``; 0 for a move without a timing wish). Phases that
    move a common joint run one after the other, in list order; phases on
    disjoint joints may overlap, and the motion is their sum.
    """

    delta: np.ndarray
    duration_s: float
    anchor: float
    ideal_s: float
    weight: float = 1.0
    earliest_s: float = 0.0
    order_joints: np.ndarray | None = None  # joints it is ordered on, if not the ones it moves
    # (k, lag_s): start at least lag_s after phase k (an earlier one) starts, even without
    # a common joint: a motion that may overlap the end of another, but not all of it
    follows: tuple[tuple[int, float], ...] = ()
    # may start blend_s before the end of phase blend_after (an earlier phase on its joints,
    # the last one before it on every one of them): the two motions add in the overlap,
    # which whoever builds the phase has checked within every limit for any overlap up
    # to blend_s (at most blend_after's duration less its own blend_s, so no three
    # motions of a joint overlap)
    blend_s: float = 0.0
    blend_after: int = -1

    @property
    def joints(self) -> np.ndarray:
        return np.flatnonzero(np.abs(self.delta) > 0.0)


@dataclass(frozen=True)
class TimingProblem:
    """min sum w (x_p + a_p T_p - ideal_p)^2  s.t.  x_p >= earliest_p,
    x_q - x_p >= lag_pq for every (p, q) in ``after`` (q moves a joint p moved before:
    lag T_p, less q's blend if it blends with p; or q follows p by a given lag)."""

    durations: np.ndarray
    anchors: np.ndarray
    ideals: np.ndarray
    weights: np.ndarray
    earliest: np.ndarray
    after: np.ndarray  # (m, 2) pairs (p, q), p < q
    lags: np.ndarray  # (m,) s
    t0: float


def build_timing(phases: list[Phase], t0: float) -> TimingProblem:
    last: dict[int, int] = {}
    lag: dict[tuple[int, int], float] = {}
    for q, ph in enumerate(phases):
        js = ph.joints if ph.order_joints is None else ph.order_joints
        for j in js.tolist():
            if j in last:
                p = last[j]
                lag[(p, q)] = phases[p].duration_s - (ph.blend_s if p == ph.blend_after else 0.0)
            last[j] = q
        for p, lag_s in ph.follows:
            if not 0 <= p < q:
                raise ValueError(f"phase {q} follows phase {p}: not an earlier phase")
            lag[(p, q)] = max(lag.get((p, q), -np.inf), float(lag_s))
    pairs = sorted(lag)
    return TimingProblem(
        np.array([p.duration_s for p in phases]), np.array([p.anchor for p in phases]),
        np.array([p.ideal_s for p in phases]), np.array([p.weight for p in phases]),
        np.array([max(p.earliest_s, t0) for p in phases]),
        np.array(pairs, dtype=int).reshape(-1, 2), np.array([lag[pq] for pq in pairs], dtype=float), t0)


def solve_timing(prob: TimingProblem) -> np.ndarray:
    """Start times (s) of the phases, by OSQP (tight tolerances; no polishing: it prints to stdout).

    Phases with weight 0 get a tiny pull to start as early as they may, so
    the problem is strictly convex. The solution is then made exactly
    feasible by a pass in list order (precedence pairs always point forward)
    that only delays a phase by the solver's residual (~1e-9 s).
    """
    n = len(prob.durations)
    if n == 0:
        return np.zeros(0)
    w = np.maximum(prob.weights, 1e-4)
    target = np.where(prob.weights > 0, prob.ideals - prob.anchors * prob.durations, prob.earliest)
    P = sp.diags(w, format="csc")
    q = -w * target
    rows = [sp.eye(n, format="csc")]
    lo = [prob.earliest]
    m = len(prob.after)
    if m:
        r = np.repeat(np.arange(m), 2)
        c = prob.after.ravel()
        v = np.tile([-1.0, 1.0], m)
        rows.append(sp.csc_matrix((v, (r, c)), shape=(m, n)))
        lo.append(prob.lags)
    A = sp.vstack(rows, format="csc")
    l_vec = np.concatenate(lo)
    # OSQP's default rho adaptation is timed by its own set-up time: results (at the
    # 1e-9 level, enough to flip a printed digit) would depend on the machine's load.
    # A fixed interval keeps the same input giving the same bytes.
    # The problem is strictly convex and always feasible (lower bounds on starts and on
    # differences of starts that point forward), so OSQP's infeasibility certificates
    # can only be false alarms: their tolerances are set far below reach. Polishing
    # is off: it prints to stdout (which would break ``-o -``).
    # (tight first; then looser; and at last the last iterate of the loosest, if finite: the
    # pass below makes any start times feasible, only the timing wishes suffer)
    for scaling, eps in ((10, 1e-9), (0, 1e-9), (10, 1e-6)):
        solver = osqp.OSQP()
        solver.setup(P=P, q=q, A=A, l=l_vec, u=np.full(len(l_vec), np.inf), verbose=False,
                     eps_abs=eps, eps_rel=eps, eps_prim_inf=1e-15, eps_dual_inf=1e-15,
                     max_iter=20000, polishing=False, scaling=scaling,
                     adaptive_rho_interval=ADAPTIVE_RHO_INTERVAL)
        res = solver.solve(raise_error=False)
        if res.info.status in ("solved", "solved inaccurate") and res.x is not None:
            break
    else:
        if (res.info.status != "maximum iterations reached" or res.x is None
                or not np.all(np.isfinite(res.x))):
            raise SolverError(f"timing QP failed: {res.info.status}", problem=prob)
    x = np.maximum(np.array(res.x, dtype=float), prob.earliest)
    for (p, qq), lag in zip(prob.after, prob.lags):  # sorted by p, and p < q
        x[qq] = max(x[qq], x[p] + lag)
    # one more pass in case a delayed phase pushes a later one
    for (p, qq), lag in zip(prob.after, prob.lags):
        x[qq] = max(x[qq], x[p] + lag)
    return x


def sample(phases: list[Phase], starts: np.ndarray, t_s: np.ndarray, q_hold: np.ndarray) -> np.ndarray:
    """Joint positions at times ``t_s``: ``q_hold`` plus every phase's delta times its
    min-jerk progress (0 before the phase, 1 after it)."""
    out = np.tile(q_hold, (len(t_s), 1))
    for ph, x in zip(phases, starts):
        u = (t_s - x) / ph.duration_s
        js = ph.joints
        if js.size:
            out[:, js] += min_jerk(u)[:, None] * ph.delta[js]
    return out

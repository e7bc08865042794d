"""The contact speeds' QP: the arm's joint speeds with which the palm meets the ball
(``planner.catch.plan.stopping``'s soft stop, the live stop of ``planner.catch.live.stop``).

Minimise |W^1/2 (v_ball - J qd)|^2 (J the palm target's Jacobian over the arm joints): the
ball's speed relative to the palm, and with it the pad's force (its square), within every
arm joint's speed bound; with ``give`` the palm target never moves into the ball along the
palm's normal (``giving_speeds``).

Holding the ball (``docs/history/physics-replay.md``, "Catch"): nothing on the palm's wrist side
stops a ball rolling there, so (1) the QP weighs the relative speed along the palm
``ROLL_WEIGHT`` times its normal part (a tangential speed is not absorbed by the pad: the
ball keeps 5/7 of it as a roll), and (2) once the grasp is made the wrist turns the closed
hand (``planner.catch.plan.holdturn``) until the palm faces up with its downhill towards
the fingers: the ball rolls into the closed fingers and the palm carries its weight.
"""

from __future__ import annotations

import numpy as np

ROLL_WEIGHT = 30.0  # the contact-speed QP weighs the ball's speed along the palm this many
# times its speed into it: the pad absorbs the normal part (its force grows with its square),
# nothing absorbs the tangential part -- a sphere keeps 5/7 of it as a roll (rolling, no
# friction stops it) that leaves the open wrist side before the fingers close. Measured
# (bench_simulate.py --catch-grid, held of 25, the planner as committed): weight 1 -> 15,
# 10 -> 18, 30 -> 23, 100 -> 18 (100 gives up the soft catch's normal speed as well)


def contact_qp(J: np.ndarray, v_ball: np.ndarray, normal: np.ndarray,
               roll_weight: float = ROLL_WEIGHT) -> tuple[np.ndarray, np.ndarray]:
    """The contact speeds' QP objective (P, c) of x^T P x / 2 + c^T x: |W^1/2 (v_ball -
    J x)|^2 + 1e-6 |x|^2, W weighting the relative velocity's part along the palm
    ``roll_weight`` times its part along the palm's ``normal``."""
    k = J.shape[1]
    n = normal / np.linalg.norm(normal)
    W = roll_weight * np.eye(3) + (1.0 - roll_weight) * np.outer(n, n)
    return 2.0 * (J.T @ W @ J + 1e-6 * np.eye(k)), -2.0 * J.T @ W @ v_ball


def contact_speeds(J: np.ndarray, v_ball: np.ndarray, bound: np.ndarray,
                   normal: np.ndarray, roll_weight: float = ROLL_WEIGHT, give: bool = False
                   ) -> np.ndarray:
    """The QP (``contact_qp``) within -bound <= x <= bound, by OSQP (zeros when unsolved):
    a solver set up for this problem alone, so that the speeds are a function of the
    arguments. ``give``: and the palm target never moving into the ball along the palm's
    ``normal`` (n . J x <= 0, n facing the arriving ball): the ball's speed into the palm
    is then at most its own. (A solver kept between solves keeps its adapted step size rho even without
    warm starting: the next problem's answer then depended on the plans before it, and
    one throw, 75 deg from 1.0 m, was feasible or not by what had been planned before.)"""
    from planner.qp import DenseQp  # (the planned catch's: a live session solves by ``box_qp``)

    k = J.shape[1]
    P, c = contact_qp(J, v_ball, normal, roll_weight)
    qp = DenseQp(eps_abs=1e-9, eps_rel=1e-9, max_iter=4000, polishing=True,
                 warm_starting=False)
    if give:
        A = np.vstack([np.eye(k), normal / np.linalg.norm(normal) @ J])
        res = qp.solve(P, c, A, np.append(-bound, -np.inf), np.append(bound, 0.0))
    else:
        res = qp.solve(P, c, np.eye(k), -bound, bound)
    if not res.solved:
        return np.zeros(k)
    return np.clip(res.x, -bound, bound)


def giving_speeds(J: np.ndarray, v_ball: np.ndarray, bound: np.ndarray, normal: np.ndarray,
                  roll_weight: float = ROLL_WEIGHT) -> np.ndarray:
    """``contact_speeds`` with the palm giving with the ball (``give``)."""
    return contact_speeds(J, v_ball, bound, normal, roll_weight, give=True)

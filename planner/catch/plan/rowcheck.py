"""The catch's self-check: the independent check's criteria (``planner.check.criteria``)
on the planned rows, with its own forward kinematics: the palm on the ball at the
intercept, no fingertip inside the ball before it and no finger's body in its flight
(``planner.check.ballbodies``, the check's rule), the grasp within its window and held
to the end."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from planner.catch.flight.path import Flight
from planner.catch.plan.arm import palm_target
from planner.catch.plan.geometry import interp_row
from planner.catch.plan.reasons import CatchReason, Reason
from planner.check.criteria import GRASP_MIN_TIPS, GRASP_TOL_M, GRASP_WINDOW_S, INTERCEPT_TOL_M
from planner.check.kinematics import Kinematics
from planner.hand.bodies import collision_bodies
from planner.hand.model import HandModel
from planner.hand.spec import PALM_FRAME


@dataclass(frozen=True)
class RowVerdict:
    """The self-check of a catch's rows: the palm's distance from the ball at the intercept,
    the least fingertip clearance before it, the grasp's time and fingers (None, () without
    one), and the reasons the rows fail (each made where it is found)."""

    error_m: float
    clearance_m: float
    grasp_t: float | None
    grasp_fingers: tuple[str, ...]
    reasons: tuple[Reason, ...]


class RowCheck:
    """The criteria for one reference-mounted hand (``T_ref``: its root pose; ``near_m``:
    no fingertip reaches farther than this from the palm centre)."""

    def __init__(self, hand: HandModel, T_ref: np.ndarray, near_m: float) -> None:
        self.hand, self.T_ref, self.near_m = hand, T_ref, near_m
        m = hand.pin_model
        self._pin_idx = np.array([m.idx_qs[m.getJointId(n)] for n in hand.joint_names])
        self._tip_ids = [m.getFrameId(f"{f}_tip") for f in hand.fingers]
        self._palm_id = m.getFrameId(PALM_FRAME)
        self._pin_data = m.createData()
        self._kin = Kinematics(hand, T_ref)  # the check's, for the fingers' bodies
        self._bodies = collision_bodies(hand.spec)

    def frames(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Fingertips (T, 5, 3) and palm poses (T, 4, 4), reference frame, one FK per row."""
        model, data = self.hand.pin_model, self._pin_data
        T = self.T_ref
        qp = np.zeros(model.nq)
        tips = np.empty((len(Q), len(self._tip_ids), 3))
        palm = np.empty((len(Q), 4, 4))
        for k, q in enumerate(Q):
            qp[self._pin_idx] = q
            pin.framesForwardKinematics(model, data, qp)
            for j, fid in enumerate(self._tip_ids):
                tips[k, j] = data.oMf[fid].translation
            palm[k] = data.oMf[self._palm_id].homogeneous
        tips = tips @ T[:3, :3].T + T[:3, 3]
        palm = np.einsum("ij,tjk->tik", T, palm)
        return tips, palm


    def check(self, flight: Flight, C: np.ndarray, r: float, t: np.ndarray, Q: np.ndarray,
              t_i: float, t_static: float, rate_hz: float, grasp_known_bad: bool = False):
        """The independent check's catch criteria on the rows ``Q`` at times ``t``: the
        intercept error, the least fingertip clearance before it, the grasp's time and
        fingers, and the reasons it fails (if any): a ``RowVerdict``."""
        reasons = []
        h = self.hand
        qi = interp_row(t, Q, t_i)
        P = palm_target(h, qi, r)
        err = float(np.linalg.norm(flight.position(t_i) - C - P))
        if err > INTERCEPT_TOL_M:
            reasons.append(Reason(CatchReason.MISS, f"the palm misses the ball by "
                                  f"{1000 * err:.0f} mm at t = {t_i:.3f} s"))
        # rows that matter: before the intercept those in which the ball is within
        # ``near_m`` of the palm target (no fingertip reaches farther); after it, rows until
        # the hand stops moving (``t_static``; later rows repeat the last), and the last row
        b_all = flight.position(t) - C
        pre = (t < t_i) & (np.linalg.norm(b_all - P, axis=1) < self.near_m + 2.0 * r)
        post = (t >= t_i) & (t <= t_static + 1.5 / rate_hz)  # static afterwards
        post[-1] = t[-1] >= t_i
        idx = np.flatnonzero(pre | post)
        tips, palm = self.frames(Q[idx])
        tt = t[idx]
        before = tt < t_i
        clear = np.inf
        if before.any():
            b = b_all[idx][before]
            d = np.linalg.norm(tips[before] - b[:, None, :], axis=-1) - r
            clear = float(d.min())
            if clear < 0:
                k, f = np.unravel_index(int(np.argmin(d)), d.shape)
                reasons.append(Reason(CatchReason.FINGERS, (
                    f"fingers in the way: {h.fingers[f]} tip inside the ball at "
                    f"t = {tt[before][k]:.3f} s, before the intercept")))
        # (first used by the ending of a live session: not imported at its start)
        from planner.check.ballbodies import finger_hit, finger_hit_problem

        hit = finger_hit(self._bodies, self._kin.link_poses, t, Q, t_i,
                         lambda ts: flight.position(ts) - C, r)
        hit_reason = finger_hit_problem(hit)
        if hit_reason is not None:
            reasons.append(Reason(CatchReason.FINGERS, hit_reason))
        after = ~before
        centre = palm[after, :3, 3] + r * palm[after, :3, 2]
        d = np.linalg.norm(tips[after] - centre[:, None, :], axis=-1)
        closed = d <= r + GRASP_TOL_M
        thumb = h.fingers.index("thumb")
        ok = closed[:, thumb] & (closed.sum(axis=1) >= GRASP_MIN_TIPS)
        ta = tt[after]
        g_t, g_f = None, ()
        first = np.flatnonzero(ok & (ta <= t_i + GRASP_WINDOW_S + 1e-9))
        if first.size:
            k = int(first[0])
            g_t = float(ta[k])
            g_f = tuple(f for j, f in enumerate(h.fingers) if closed[k, j])
            if not ok[k:].all():
                lost = k + int(np.argmin(ok[k:]))
                reasons.append(Reason(CatchReason.GRASP, f"grasp lost at t = {ta[lost]:.3f} s"))
        elif not grasp_known_bad:
            k = int(np.argmax(ok)) if ok.any() else None
            when = (f"only at t = {ta[k]:.3f} s ({1000 * (ta[k] - t_i):.0f} ms after the "
                    "intercept)" if k is not None else "never")
            reasons.append(Reason(CatchReason.GRASP, (
                f"too slow to close: the grasp (thumb + {GRASP_MIN_TIPS - 1} "
                f"fingertips within radius + {1000 * GRASP_TOL_M:g} mm) holds {when}"
                f", limit {1000 * GRASP_WINDOW_S:g} ms")))
        return RowVerdict(err, clear, g_t, tuple(g_f), tuple(reasons))

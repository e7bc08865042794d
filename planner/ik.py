"""Whole-hand inverse kinematics: placo (on Pinocchio) QP, iterated to convergence.

With ``planner.placo_hand`` (the solver: robot, limits, couplings, joint tasks), the
only modules of the planner that import placo. One ``solve(True)`` of a
placo ``KinematicsSolver`` is one Newton step of a QP; ``HandIK.solve``
iterates it until every pressing fingertip is within tolerance (1 mm, the
seed's precision requirement) of its target.

Per step the QP holds:
- pressing fingertips: position tasks at their key's press point at full dip
  (soft, weight 1e3; the y coordinate may slide within the key's allowed
  press range, see ``PressTarget``);
- hovering fingertips: at least ``hover_clearance_m`` above the top of every
  key they are over or near, as joint-space half-spaces ``A q <= b``
  re-linearised at each step;
- couplings: linear ones as hard placo gear tasks, nonlinear ones as
  re-linearised equality half-space pairs;
- joint limits (placo's, hard);
- a posture task toward a natural hand shape (soft, small weight), which
  also picks the rail and wrist position among the many that reach.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.errors import InputError
from planner.music import keyboard as kb
from planner.placo_hand import PlacoHand

PRESS_TOL_M = 1e-3  # seed: precision 1 mm
PREPARE_HEIGHT_M = 0.0055  # a finger about to press waits this far above its key (>= 5 mm)
MIN_CLEARANCE_M = 0.005  # spec: a hovering tip 5 mm above the keys at least (a solve's
# success; to 1e-9 m, the solver's rounding)
HOVER_CLEARANCE_M = 0.007  # spec: 5 mm above the keys, plus 2 mm for linearisation
_NEAR_M = 0.006  # keys within this distance (x, y) of a hovering tip count as under it


@dataclass(frozen=True)
class PressTarget:
    """A fingertip pressing a key: target point (m, keyboard frame), y allowed in ``y_range_m``."""

    finger: str
    pitch: int
    point_m: tuple[float, float, float]
    y_range_m: tuple[float, float]


@dataclass(frozen=True)
class IKResult:
    q: np.ndarray
    converged: bool
    iterations: int
    press_error_m: float  # worst pressing-tip distance to its target
    hover_clearance_m: float  # smallest height of a hovering tip above the keys near it


FRONT_Y_MAX_M = kb.BLACK_Y0_M - 0.010  # a pad point pressing a white key's front stays this
# far in front of the black keys (the pad reaches about its radius' half beyond its point:
# docs/history/play-second-design.md, "y 4-50 mm for the pads' points"); the atlas's body
# rule decides the rest
THUMB_BLACK_EDGE_M = 0.008  # the thumb presses a black key at least this far behind its front


def press_target(finger: str, pitch: int, depth_m: float = kb.KEY_DIP_M,
                 front: bool = False) -> PressTarget:
    """Where ``finger`` presses key ``pitch``: ``depth_m`` below its top (default: full dip),
    centred on the part of the key it can touch.

    The thumb presses white keys in front of the black keys; the long fingers
    press white keys behind the black keys' front (between them), where the
    exposed part of the key is centred at ``exposed_center_x``. Black keys
    are pressed 30 mm behind their front end, sliding between 15 mm behind it
    (the thumb: ``THUMB_BLACK_EDGE_M``, as far as it reaches back) and 25 mm
    before their back end. ``front``: a long finger presses white keys in front of the
    black keys too, as the thumb does (a finger wider than a white key between two black
    keys: the atlas of a hand with a ``[play]`` posture whose tips rest there).
    """
    k = kb.key(pitch)
    z = k.top_z_m - depth_m
    if k.black:
        y0 = kb.BLACK_Y0_M + 0.030
        # the thumb (short, reaching back from the front) may press nearer the front edge
        lo = kb.BLACK_Y0_M + (THUMB_BLACK_EDGE_M if finger == "thumb" else 0.015)
        return PressTarget(finger, pitch, (k.center_x_m, y0, z), (lo, kb.BLACK_Y1_M - 0.025))
    if finger == "thumb":
        return PressTarget(finger, pitch, (k.center_x_m, 0.012, z), (0.004, 0.025))
    if front:
        return PressTarget(finger, pitch, (k.center_x_m, 0.030, z), (0.004, FRONT_Y_MAX_M))
    x = exposed_center_x(pitch)
    return PressTarget(finger, pitch, (x, 0.095, z), (kb.BLACK_Y0_M + 0.012, kb.WHITE_LENGTH_M - 0.020))


def press_x_range(finger: str, pitch: int, inset_m: float, front: bool = False
                  ) -> tuple[float, float]:
    """x range (m) of the part of key ``pitch`` that ``press_target`` has ``finger`` press,
    ``inset_m`` in from each side: a black key, or a white key in front of the black keys
    (the thumb's), across its whole width; a white key between the black keys (the long
    fingers'), between its black neighbours (``exposed_range_x``)."""
    k = kb.key(pitch)
    whole = k.black or finger == "thumb" or front  # (``front``: as ``press_target``'s)
    lo, hi = (k.x_min_m, k.x_max_m) if whole else exposed_range_x(pitch)
    return lo + inset_m, hi - inset_m


def exposed_range_x(pitch: int) -> tuple[float, float]:
    """x range (m) of the part of a key no other key overhangs: for a white key, between
    its black neighbours; for a black key, the key itself."""
    k = kb.key(pitch)
    lo, hi = k.x_min_m, k.x_max_m
    if k.black:
        return lo, hi
    if pitch - 1 >= kb.LOWEST_PITCH and kb.is_black(pitch - 1):
        lo = max(lo, kb.key(pitch - 1).x_max_m)
    if pitch + 1 <= kb.HIGHEST_PITCH and kb.is_black(pitch + 1):
        hi = min(hi, kb.key(pitch + 1).x_min_m)
    return lo, hi


def exposed_center_x(pitch: int) -> float:
    """Centre (x, m) of the part of a white key between its black neighbours."""
    lo, hi = exposed_range_x(pitch)
    return 0.5 * (lo + hi)


def surface_near(x: float, y: float) -> float:
    """Highest resting key top a hovering tip at (x, y) could meet moving sideways: the black
    keys' top anywhere over the black keys' band (y >= their front - ``_NEAR_M``), the white
    keys' top elsewhere over the keyboard, -inf off it."""
    t = kb.key_table()
    if not (t["x_min"][0] - _NEAR_M <= x <= t["x_max"][-1] + _NEAR_M
            and -_NEAR_M <= y <= kb.WHITE_LENGTH_M + _NEAR_M):
        return -np.inf
    return kb.BLACK_TOP_Z_M if y >= kb.BLACK_Y0_M - _NEAR_M else 0.0


def surfaces_under(x: np.ndarray, y: np.ndarray, inflate_m: float) -> np.ndarray:
    """Highest resting key top (m) whose footprint, grown by ``inflate_m`` on every side,
    holds each point (x, y); -inf off the keys. Exact, unlike ``surface_near``: a tip
    over the exposed part of a white key is over the white key only."""
    t = kb.key_table()
    x = np.asarray(x, dtype=float)[:, None]
    y = np.asarray(y, dtype=float)[:, None]
    inside = ((t["x_min"] - inflate_m <= x) & (x <= t["x_max"] + inflate_m)
              & (t["y_min"] - inflate_m <= y) & (y <= t["y_max"] + inflate_m))
    return np.where(inside, t["top_z"][None, :], -np.inf).max(axis=1)


class HandIK(PlacoHand):
    """The IK's tasks on a hand's placo solver (``PlacoHand``), built once and reused for
    every keyframe: fingertips pressing keys with the others hovering above them
    (``solve``), one finger alone (``solve_finger``), and the palm at a pose (``solve_palm``)."""

    # -------------------------------------------------------------- solve
    def solve(self, presses: list[PressTarget], q_start: np.ndarray, posture: np.ndarray,
              hover: tuple[str, ...] | None = None, max_iter: int = 60,
              tol_m: float = PRESS_TOL_M) -> IKResult:
        """Place the pressing tips on their targets, the others above the keys.

        ``q_start``: initial configuration (joint order of the hand).
        ``posture``: the natural configuration the posture task pulls toward
        (weight 1e-4); a second task (1e-2) keeps the joints near ``q_start``
        and the arm task (10) keeps the rail at ``posture``'s rail and the
        wrist where it is, so that the hand moves only what the task needs.
        ``hover``: fingers that must clear the keys (default: all not pressing).
        Returns the configuration reached; ``converged`` says whether every
        pressing tip is within ``tol_m`` and every hovering tip clears the
        keys by the spec's 5 mm.
        """
        fingers = self.hand.fingers
        pressing = {p.finger for p in presses}
        if len(pressing) != len(presses):
            raise InputError("one finger cannot press two keys")
        if hover is None:
            hover = tuple(f for f in fingers if f not in pressing)
        arm_q = np.array(q_start, dtype=float)
        if "rail" in self.hand.index:
            arm_q[self.hand.index["rail"]] = posture[self.hand.index["rail"]]
        self._set_joint_tasks(posture, q_start, arm_q)
        self.set_q(q_start)
        self._drop_tasks()
        for p in presses:
            t = self.solver.add_position_task(f"{p.finger}_tip", np.array(p.point_m))
            t.configure(f"press_{p.finger}", "soft", 1e5)
            self._tasks[p.finger] = t
        err, clearance, it = self._iterate(presses, hover, max_iter, tol_m)
        q = self.hand.apply_couplings(np.clip(self.get_q(), self.lower, self.upper))
        self._clear_half_spaces()
        return IKResult(q, bool(err <= tol_m and clearance >= MIN_CLEARANCE_M - 1e-9), it,
                        float(err), float(clearance))

    def _iterate(self, presses: list[PressTarget], hover: tuple[str, ...], max_iter: int,
                 tol_m: float) -> tuple[float, float, int]:
        """``solve``'s Newton steps from the robot's configuration: (press error,
        clearance, iterations) of the configuration they end at (the robot left there).

        A step is a function of the configuration alone (the targets' y and the
        half-spaces are set from it; the solver keeps nothing between steps), so once a
        configuration comes back bit for bit, the steps cycle through the same ones: the
        configuration the ``max_iter``-th step reaches is known without taking it. (The
        catch's closed pose, whose fingertip targets are partly out of reach, comes back
        after 38-59 of its 80-150 steps, a cycle of 3-18 at rounding level:
        ``planner.catch.closing``.)"""
        seen: dict[bytes, int] = {}  # a configuration -> the step that reached it
        states: list[tuple[np.ndarray, float, float]] = []  # after step 1, 2, ...
        tips = {p.finger: self._tip(p.finger) for p in presses}
        err = clearance = np.inf
        for it in range(1, max_iter + 1):
            # slide each target's y within its range to the tip's current y
            for p in presses:
                y = min(max(float(tips[p.finger][1]), p.y_range_m[0]), p.y_range_m[1])
                self._tasks[p.finger].target_world = np.array([p.point_m[0], y, p.point_m[2]])
            self._set_hover(hover)
            stuck = False
            try:
                self.solver.solve(True)
            except RuntimeError:
                # an infeasible linearisation: drop the half-spaces for this step
                self._clear_half_spaces()
                try:
                    self.solver.solve(True)
                except RuntimeError:
                    # infeasible without them too (the joint limits from here): no step
                    # is possible, the configuration stays where it is
                    stuck = True
            self.robot.update_kinematics()
            tips = {p.finger: self._tip(p.finger) for p in presses}
            err = self._press_error(presses, tips)
            clearance = self._clearance(hover)
            if stuck or (err <= tol_m and clearance >= MIN_CLEARANCE_M - 1e-9):
                return err, clearance, it
            q = self.robot.state.q
            key = q.tobytes()
            if key in seen:  # a cycle of it - seen[key] steps, none converged
                j = seen[key]
                q_end, err, clearance = states[j - 1 + (max_iter - j) % (it - j)]
                self.robot.state.q = q_end
                self.robot.update_kinematics()
                return err, clearance, max_iter
            seen[key] = it
            states.append((q.copy(), err, clearance))
        return err, clearance, max_iter

    @staticmethod
    def _press_error(presses: list[PressTarget], tips: dict[str, np.ndarray]) -> float:
        e = 0.0
        for p in presses:
            tip = tips[p.finger]
            y = min(max(float(tip[1]), p.y_range_m[0]), p.y_range_m[1])
            e = max(e, float(np.linalg.norm(tip - np.array([p.point_m[0], y, p.point_m[2]]))))
        return e

    def _clearance(self, hover) -> float:
        c = np.inf
        for f in hover:
            tip = self._tip(f)
            s = surface_near(tip[0], tip[1])
            if np.isfinite(s):
                c = min(c, float(tip[2] - s))
        return c

    def _set_hover(self, hover) -> None:
        """Linearised ``z_tip(q) >= surface + clearance`` for hovering tips (with the
        nonlinear couplings: ``PlacoHand._set_half_spaces``)."""
        # placo wants A with one column per configuration entry (floating base ignored)
        rows, rhs = [], []
        q_now = self.get_q()
        for f in hover:
            tip = self._tip(f)
            s = surface_near(tip[0], tip[1])
            if not np.isfinite(s):
                continue
            Jv = self._tip_jacobian_z(f)
            Jz = np.zeros(self._nq)
            Jz[self._q_off] = Jv[self._v_off]
            # z + Jz (q - q0) >= s + c   <=>   -Jz q <= z - s - c - Jz q0
            rows.append(-Jz)
            rhs.append(tip[2] - s - HOVER_CLEARANCE_M - Jv[self._v_off] @ q_now)
        self._set_half_spaces(rows, rhs)

    # -------------------------------------------------------------- one finger
    def solve_finger(self, target: PressTarget, q_base: np.ndarray,
                     tol_m: float = PRESS_TOL_M) -> IKResult:
        """Move only ``target.finger``'s joints (rail, wrist and other fingers locked at
        ``q_base``) to put its tip on the target. The result is ``q_base`` with that
        finger's joints replaced."""
        own = set(self.hand.spec.joints_of(target.finger))
        # lock every other joint; a coupled joint of another finger stays free but is
        # held by its (hard) coupling to its locked source, so that no equality row is
        # empty and the solver's tasks stay the same (results do not depend on history)
        followers = {self._names[c.dep] for c in self.hand.couplings}
        locked = [n for n in self._names if n not in own and n not in followers]
        for n in locked:
            self.solver.mask_dof(n)
        try:
            r = self.solve([target], q_base, q_base, hover=(), tol_m=tol_m)
        finally:
            for n in locked:
                self.solver.unmask_dof(n)
        q = q_base.copy()
        js = self.hand.joint_slice(target.finger)
        q[js] = r.q[js]
        return IKResult(self.hand.apply_couplings(q), r.converged, r.iterations, r.press_error_m,
                        r.hover_clearance_m)

    # ============================================================== catch: palm pose task
    # (added for planner.catch; independent of the keyboard machinery above)

    def solve_palm(self, point_m, normal, q_start: np.ndarray, posture: np.ndarray | None = None,
                   offset_m: float = 0.0, locked: tuple[str, ...] = (), max_iter: int = 20,
                   tol_m: float = PRESS_TOL_M, tol_rad: float = 0.01,
                   normal_weight: float = 1e2) -> IKResult:
        """Put ``palm_center + offset_m * n`` at ``point_m`` with the palm normal n (+z of
        ``palm_center``) along ``normal`` (world frame of this solver's hand).

        Position task on ``palm_center`` (soft, 1e3) at ``point_m - offset_m * normal``
        and an axis-align task of its +z on ``normal`` (soft, ``normal_weight``); the
        posture and stay tasks of ``solve`` stay in place, the arm task pulls the rail and
        wrist towards ``posture``'s (posture defaults to ``q_start``); ``locked`` joints
        are masked. No keyboard constraint applies.
        ``press_error_m`` of the result is the distance of ``palm_center + offset_m * n``
        from ``point_m`` (``hover_clearance_m`` is inf: nothing hovers); ``converged``
        also needs the normal within ``tol_rad`` of ``normal``.
        """
        point = np.asarray(point_m, dtype=float)
        nrm = np.asarray(normal, dtype=float)
        nrm = nrm / np.linalg.norm(nrm)

        def errors(T: np.ndarray | None = None) -> tuple[float, float]:
            T = self.robot.get_T_world_frame("palm_center") if T is None else T
            z = T[:3, 2]
            d = T[:3, 3] + offset_m * z - point
            return math.sqrt(float(d @ d)), math.acos(min(1.0, max(-1.0, float(z @ nrm))))

        # q_start meeting the task already (a warm start usually does: the catch's closed
        # form) needs no iteration, so no solver set-up: the hand model's forward kinematics
        # (the same URDF and mount) tell
        err, ang = errors(self.hand.frame_pose(q_start, "palm_center"))
        if err <= tol_m and ang <= tol_rad:
            q = self.hand.apply_couplings(np.clip(q_start, self.lower, self.upper))
            return IKResult(q, True, 0, err, float(np.inf))
        self.set_q(q_start)
        err, ang = errors()
        posture = q_start if posture is None else posture
        # the arm (rail, wrist) is pulled towards ``posture``'s, not held where it is
        self._set_joint_tasks(posture, q_start, posture)
        self._drop_tasks()
        pos = self.solver.add_position_task("palm_center", point - offset_m * nrm)
        pos.configure("palm_position", "soft", 1e3)
        ax = self.solver.add_axisalign_task("palm_center", np.array([0.0, 0.0, 1.0]), nrm)
        ax.configure("palm_normal", "soft", float(normal_weight))
        for n in locked:
            self.solver.mask_dof(n)
        it = 0
        try:
            for it in range(1, max_iter + 1):
                if err <= tol_m and ang <= tol_rad:
                    it -= 1
                    break
                if self._nonlinear:
                    self._set_half_spaces([], [])
                try:
                    self.solver.solve(True)
                except RuntimeError:  # a rank-deficient step: return what we have
                    break
                self.robot.update_kinematics()
                err, ang = errors()
        finally:
            for n in locked:
                self.solver.unmask_dof(n)
            self.solver.remove_task(pos)
            self.solver.remove_task(ax)
            self._clear_half_spaces()
        q = self.hand.apply_couplings(np.clip(self.get_q(), self.lower, self.upper))
        return IKResult(q, bool(err <= tol_m and ang <= tol_rad), it, err, float(np.inf))

"""Whole-hand inverse kinematics: placo (on Pinocchio) QP, iterated to convergence.

The only module of the planner that imports placo. One ``solve(True)`` of a
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

import os
import tempfile
from dataclasses import dataclass

import numpy as np
import placo

from planner.errors import InputError
from planner.hand.model import HandModel
from planner.music import keyboard as kb

PRESS_TOL_M = 1e-3  # seed: precision 1 mm
PREPARE_HEIGHT_M = 0.008  # a finger about to press waits this far above its key
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


def press_target(finger: str, pitch: int) -> PressTarget:
    """Where ``finger`` presses key ``pitch``: at full dip, centred on the part of the key it can touch.

    The thumb presses white keys in front of the black keys; the long fingers
    press white keys behind the black keys' front (between them), where the
    exposed part of the key is centred at ``exposed_center_x``. Black keys
    are pressed 30 mm behind their front end by every finger.
    """
    k = kb.key(pitch)
    z = k.top_z_m - kb.KEY_DIP_M
    if k.black:
        y0 = kb.BLACK_Y0_M + 0.030
        return PressTarget(finger, pitch, (k.center_x_m, y0, z), (kb.BLACK_Y0_M + 0.015, kb.BLACK_Y1_M - 0.025))
    if finger == "thumb":
        return PressTarget(finger, pitch, (k.center_x_m, 0.012, z), (0.004, 0.025))
    x = exposed_center_x(pitch)
    return PressTarget(finger, pitch, (x, 0.095, z), (kb.BLACK_Y0_M + 0.012, kb.WHITE_LENGTH_M - 0.020))


def exposed_center_x(pitch: int) -> float:
    """Centre (x, m) of the part of a white key between its black neighbours."""
    k = kb.key(pitch)
    lo, hi = k.x_min_m, k.x_max_m
    if pitch - 1 >= kb.LOWEST_PITCH and kb.is_black(pitch - 1):
        lo = max(lo, kb.key(pitch - 1).x_max_m)
    if pitch + 1 <= kb.HIGHEST_PITCH and kb.is_black(pitch + 1):
        hi = min(hi, kb.key(pitch + 1).x_min_m)
    return 0.5 * (lo + hi)


def surface_near(x: float, y: float) -> float:
    """Highest resting key top within ``_NEAR_M`` of (x, y); -inf where no key is near."""
    t = kb.key_table()
    near = (t["x_min"] - _NEAR_M <= x) & (x <= t["x_max"] + _NEAR_M) & \
        (t["y_min"] - _NEAR_M <= y) & (y <= t["y_max"] + _NEAR_M)
    return float(t["top_z"][near].max()) if near.any() else -np.inf


class HandIK:
    """A placo kinematics solver for one hand, built once and reused for every keyframe."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        fd, path = tempfile.mkstemp(suffix=".urdf")
        try:
            with os.fdopen(fd, "w") as f:
                f.write(hand.urdf)
            self.robot = placo.RobotWrapper(path, placo.Flags.ignore_collisions)
        finally:
            os.unlink(path)
        self.robot.set_T_world_fbase(hand.T_world_root)
        self._names = hand.joint_names
        self._v_off = np.array([self.robot.get_joint_v_offset(n) for n in self._names])
        self._q_off = np.array([self.robot.get_joint_offset(n) for n in self._names])
        self._nq = self.robot.model.nq
        self.solver = placo.KinematicsSolver(self.robot)
        self.solver.mask_fbase(True)
        self.solver.enable_joint_limits(True)
        for c in hand.couplings:
            if c.kind == "linear":
                g = self.solver.add_gear_task()
                g.set_gear(self._names[c.dep], self._names[c.src], float(c.ratio))
                g.configure(f"coupling_{self._names[c.dep]}", "hard", 1.0)
        self._nonlinear = [c for c in hand.couplings if c.kind != "linear"]
        self.posture = self.solver.add_joints_task()
        self.posture.configure("posture", "soft", 1e-3)
        # the rail holds its planned position unless reaching needs it to move
        self.rail_task = self.solver.add_joints_task() if "rail" in hand.index else None
        if self.rail_task is not None:
            self.rail_task.configure("rail", "soft", 1e-1)
        self._tasks: dict[str, object] = {}
        self._half = None

    # -------------------------------------------------------------- state
    def set_q(self, q: np.ndarray) -> None:
        for n, v in zip(self._names, q):
            self.robot.set_joint(n, float(v))
        self.robot.update_kinematics()

    def get_q(self) -> np.ndarray:
        return np.array([self.robot.get_joint(n) for n in self._names])

    def _tip(self, finger: str) -> np.ndarray:
        return self.robot.get_T_world_frame(f"{finger}_tip")[:3, 3]

    def _tip_jacobian_z(self, finger: str) -> np.ndarray:
        J = self.robot.frame_jacobian(f"{finger}_tip", "local_world_aligned")
        return J[2]

    # -------------------------------------------------------------- solve
    def solve(self, presses: list[PressTarget], q_start: np.ndarray, posture: np.ndarray,
              hover: tuple[str, ...] | None = None, max_iter: int = 60,
              tol_m: float = PRESS_TOL_M, prepare: list[PressTarget] = ()) -> IKResult:
        """Place the pressing tips on their targets, the others above the keys.

        ``q_start``: initial configuration (joint order of the hand).
        ``posture``: the natural configuration the posture task pulls toward.
        ``hover``: fingers that must clear the keys (default: all not pressing).
        ``prepare``: fingers that wait ``PREPARE_HEIGHT_M`` above the key they
        press next (soft target), so that they can go straight down.
        Returns the configuration reached; ``converged`` says whether every
        pressing tip is within ``tol_m`` and every hovering tip clears the
        keys by the spec's 5 mm.
        """
        fingers = self.hand.fingers
        pressing = {p.finger for p in presses}
        if len(pressing) != len(presses):
            raise InputError("one finger cannot press two keys")
        prepare = [p for p in prepare if p.finger not in pressing]
        if hover is None:
            waiting = {p.finger for p in prepare}
            hover = tuple(f for f in fingers if f not in pressing and f not in waiting)
        self.posture.set_joints({n: float(v) for n, v in zip(self._names, posture)})
        if self.rail_task is not None:
            self.rail_task.set_joints({"rail": float(posture[self.hand.index["rail"]])})
        self.set_q(q_start)
        for f in list(self._tasks):
            self.solver.remove_task(self._tasks.pop(f))
        for p in presses:
            t = self.solver.add_position_task(f"{p.finger}_tip", np.array(p.point_m))
            t.configure(f"press_{p.finger}", "soft", 1e3)
            self._tasks[p.finger] = t
        for p in prepare:
            x, y, z = p.point_m
            t = self.solver.add_position_task(f"{p.finger}_tip", np.array([x, y, z + kb.KEY_DIP_M + PREPARE_HEIGHT_M]))
            t.configure(f"prepare_{p.finger}", "soft", 1e1)
            self._tasks[p.finger] = t
        err = np.inf
        clearance = np.inf
        it = 0
        for it in range(1, max_iter + 1):
            # slide each target's y within its range to the tip's current y
            for p in presses:
                y = float(np.clip(self._tip(p.finger)[1], *p.y_range_m))
                self._tasks[p.finger].target_world = np.array([p.point_m[0], y, p.point_m[2]])
            self._set_half_spaces(hover)
            try:
                self.solver.solve(True)
            except RuntimeError:
                # an infeasible linearisation: drop the half-spaces for this step
                self._clear_half_spaces()
                self.solver.solve(True)
            self.robot.update_kinematics()
            err = self._press_error(presses)
            clearance = self._clearance(hover)
            if err <= tol_m and clearance >= 0.005 - 1e-9:
                break
        q = self.hand.apply_couplings(np.clip(self.get_q(), self.hand.lower, self.hand.upper))
        self._clear_half_spaces()
        return IKResult(q, bool(err <= tol_m and clearance >= 0.005 - 1e-9), it, float(err), float(clearance))

    def _press_error(self, presses: list[PressTarget]) -> float:
        e = 0.0
        for p in presses:
            tip = self._tip(p.finger)
            y = float(np.clip(tip[1], *p.y_range_m))
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

    def _clear_half_spaces(self) -> None:
        if self._half is not None:
            self.solver.remove_constraint(self._half)
            self._half = None

    def _set_half_spaces(self, hover) -> None:
        """Linearised ``z_tip(q) >= surface + clearance`` for hovering tips, and nonlinear couplings."""
        self._clear_half_spaces()
        # placo wants A with one column per configuration entry (floating base ignored)
        nq = self._nq
        rows, rhs = [], []
        q_now = self.get_q()
        for f in hover:
            tip = self._tip(f)
            s = surface_near(tip[0], tip[1])
            if not np.isfinite(s):
                continue
            Jv = self._tip_jacobian_z(f)
            Jz = np.zeros(nq)
            Jz[self._q_off] = Jv[self._v_off]
            # z + Jz (q - q0) >= s + c   <=>   -Jz q <= z - s - c - Jz q0
            rows.append(-Jz)
            rhs.append(tip[2] - s - HOVER_CLEARANCE_M - Jv[self._v_off] @ q_now)
        for c in self._nonlinear:
            a = np.zeros(nq)
            qs = q_now[c.src]
            slope = float(c.slope(qs))
            a[self._q_off[c.dep]] = 1.0
            a[self._q_off[c.src]] = -slope
            val = float(c.value(qs)) - slope * qs
            rows += [a, -a]
            rhs += [val + 1e-9, -val + 1e-9]
        if rows:
            self._half = self.solver.add_joint_space_half_spaces_constraint(np.array(rows), np.array(rhs))
            self._half.configure("hover", "hard", 1.0)

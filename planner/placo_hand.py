"""One hand in a placo ``KinematicsSolver``: the solver the IK's tasks are set on.

Holds what every IK task shares and nothing of a task itself: the robot built from the
hand's URDF text, its joint limits (placo's, hard), its couplings (linear ones as hard
placo gear tasks, nonlinear ones as re-linearised equality half-space pairs), three
joint tasks (a posture toward a natural hand shape, weight 1e-4; ``stay`` near the
configuration the hand comes from, 1e-2; ``arm``, holding the rail and the wrist, 10)
and the configuration in and out. ``planner.ik.HandIK`` puts the keyboard's and the
palm's tasks on it. With ``planner.ik``, the only modules of the planner that import placo.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from planner.hand.model import HandModel


class PlacoHand:
    """A placo kinematics solver for one hand, built once, on first use (``build``), and
    reused for every solve. Until then nothing of placo is loaded: the live catch's palm
    poses are confirmed by the hand model's forward kinematics where the warm start meets
    the task already (``HandIK.solve_palm``), and its start (``catch --live``) is ready
    for the first observation ~0.03 s of CPU sooner without placo's import and robot."""

    def __init__(self, hand: HandModel, limits: tuple[np.ndarray, np.ndarray] | None = None
                 ) -> None:
        """``limits``: the joints' (lower, upper) bounds the solutions keep to (default
        the hand's hard stops; ``play``'s atlas: ``HandModel.plan_lower``/``plan_upper``)."""
        self.hand = hand
        self.lower, self.upper = (hand.lower, hand.upper) if limits is None else limits

    def __getattr__(self, name: str) -> Any:
        """A name not set yet (but a special one) before the solver is built: whatever
        ``build`` sets is a part of the solver, so the solver is built now (once; the same
        objects in the same order as when built at once) and the name asked again; a name
        the built solver lacks is no attribute."""
        d = self.__dict__
        if not name.startswith("__") and "hand" in d and "robot" not in d:
            self.build()
            return getattr(self, name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def build(self) -> None:
        """The placo robot from the hand's URDF, its solver, limits, couplings and joint
        tasks."""
        import placo

        hand = self.hand
        # the URDF text is passed directly: no temporary file
        self.robot = placo.RobotWrapper("", placo.Flags.ignore_collisions, hand.urdf)
        self.robot.set_T_world_fbase(hand.T_world_root)
        self._names = hand.joint_names
        self._v_off = np.array([self.robot.get_joint_v_offset(n) for n in self._names])
        self._q_off = np.array([self.robot.get_joint_offset(n) for n in self._names])
        self._nq = self.robot.model.nq
        self.solver = placo.KinematicsSolver(self.robot)
        self.solver.mask_fbase(True)
        for n, lo, hi in zip(hand.joint_names, self.lower, self.upper):
            self.robot.set_joint_limits(n, float(lo), float(hi))
        self.solver.enable_joint_limits(True)
        self._gears: dict[str, object] = {}
        for c in hand.couplings:
            if c.kind == "linear":
                self._add_gear(c)
        self._nonlinear = [c for c in hand.couplings if c.kind != "linear"]
        self.posture = self.solver.add_joints_task()
        self.posture.configure("posture", "soft", 1e-4)
        # minimal motion: stay near the configuration the hand comes from
        self.stay = self.solver.add_joints_task()
        self.stay.configure("stay", "soft", 1e-2)
        # the arm (rail at its planned position, wrist where it is) moves only
        # when reaching needs it: the fingers do the local work
        self._arm = [n for n in ("rail", "wrist_flex", "wrist_dev") if n in hand.index]
        self.arm_task = self.solver.add_joints_task()
        self.arm_task.configure("arm", "soft", 1e1)
        self._tasks: dict[str, object] = {}
        self._half = None

    def _add_gear(self, c) -> None:
        g = self.solver.add_gear_task()
        g.set_gear(self._names[c.dep], self._names[c.src], float(c.ratio))
        g.configure(f"coupling_{self._names[c.dep]}", "hard", 1.0)
        self._gears[self._names[c.dep]] = (g, c)

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

    def _set_joint_tasks(self, posture: np.ndarray, q_start: np.ndarray, arm_q: np.ndarray
                         ) -> None:
        """The posture task toward ``posture``, ``stay`` at ``q_start`` and the arm task at
        ``arm_q``'s rail and wrist."""
        self.posture.set_joints({n: float(v) for n, v in zip(self._names, posture)})
        self.stay.set_joints({n: float(v) for n, v in zip(self._names, q_start)})
        self.arm_task.set_joints({n: float(arm_q[self.hand.index[n]]) for n in self._arm})

    def _drop_tasks(self) -> None:
        """Remove the previous solve's own tasks (``_tasks``)."""
        for f in list(self._tasks):
            self.solver.remove_task(self._tasks.pop(f))

    # -------------------------------------------------------------- half-spaces
    def _clear_half_spaces(self) -> None:
        if self._half is not None:
            self.solver.remove_constraint(self._half)
            self._half = None

    def _set_half_spaces(self, rows: list[np.ndarray], rhs: list[float]) -> None:
        """The joint-space half-spaces ``rows q <= rhs`` (one column per configuration
        entry, floating base ignored) and the nonlinear couplings re-linearised at the
        robot's configuration, as one soft constraint in place of the previous one."""
        self._clear_half_spaces()
        rows, rhs = list(rows), list(rhs)
        q_now = self.get_q()
        for c in self._nonlinear:
            a = np.zeros(self._nq)
            qs = q_now[c.src]
            slope = float(c.slope(qs))
            a[self._q_off[c.dep]] = 1.0
            a[self._q_off[c.src]] = -slope
            val = float(c.value(qs)) - slope * qs
            rows += [a, -a]
            rhs += [val + 1e-9, -val + 1e-9]
        if rows:
            self._half = self.solver.add_joint_space_half_spaces_constraint(np.array(rows), np.array(rhs))
            self._half.configure("hover", "soft", 1e4)

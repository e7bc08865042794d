"""Contact forces on a caught ball: a small QP (OSQP) with friction cones and motor limits.

The hand touches the ball at its fingertip pads and at the palm centre. Each
contact c pushes on the ball with a force ``f_c`` (N, world frame). The QP:

    minimise    sum_c |f_c|^2  +  REG * sum_m (tau_m / cap_m)^2
    subject to  sum_c f_c = F_req                           (force balance)
                sum_c (p_c - centre) x f_c = 0              (moment balance, optional)
                n_c . f_c >= 0                              (contacts push, never pull)
                (t_k - mu' n_c) . f_c <= 0,  k = 1..FACETS  (linearised friction cone)
                -cap_m <= tau_m <= cap_m                    (every motor within its capacity)

* Friction cone: an inscribed pyramid of ``FACETS`` (8) faces with the rubber
  pads' coefficient mu = 0.8 (seed, David), mu' = mu cos(pi / FACETS), so a
  force inside the pyramid is always inside the true cone.
* Motor torques: with the ball pushing back on the hand with -f_c at p_c, the
  joints must supply ``tau_joint = g(q) + sum_c J_c^T f_c`` (g = gravity
  torques, J_c the contact point's position Jacobian), and the motors
  ``tau_motor = hand.motor_torques(q, tau_joint)`` (virtual work through the
  couplings, tendon efficiency). That map is linear in f: its matrix is built
  column by column from unit forces, so the limits are linear constraints.
* Capacity: ``cap_m`` = min(motor peak torque, tendon design force x spool radius)
  (``planner.hand.tendon.actuator_capacity``): a tendon's tension at its spool is
  its motor's torque over the spool radius, so the cable's 40 N (seed 000) is a
  bound on the same row.
* The regularisation (``REG`` = 1e-2) slightly prefers force splits that load
  the motors less; it does not change feasibility.

Required force (``stop_force`` / ``hold_force``):

* stopping: the ball arrives at speed v and the padded palm gives
  the hand's pad (``HandModel.pad_give_m``, the hand file's ``[palm]``); a constant deceleration over that distance is
  a = v^2 / (2 d) against the arrival velocity, so
  ``F_req = m a (-v/|v|) - m g`` (``g`` the gravity vector). The impact is
  brief, so the ball may spin: no moment balance.
* holding: ``F_req = -SAFETY * m g`` with the seed's safety factor 1.5 on the
  grip (David: "a safety factor of 1.5"), with moment balance.

OSQP settings: eps_abs = eps_rel = 1e-6 (N), no polishing, a solver set up for each
problem (cold: a solver kept and warm-started from the previous throw's problem
answered within the tolerance but with digits that depended on the throws planned
before); the result is accepted only if every motor is within 1e-4 of its capacity.

``build_grasp_problem`` assembles the QP (pure data); ``solve_grasp`` solves it
and raises ``InfeasibleError`` (primal infeasible: no force split keeps every
motor within its capacity inside the friction cones) or ``SolverError``, both
carrying the problem. The result reports the torque headroom (min over
motors of 1 - |tau| / capacity), the motor that limits it and its limiting part
(motor torque, tendon force, gear).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from planner.check.motormap import motor_torque_matrix
from planner.errors import InfeasibleError, InputError, SolverError
from planner.hand.model import GRAVITY_WORLD, HandModel
from planner.hand.spec import PALM_FRAME
from planner.hand.tendon import actuator_capacity

MU_RUBBER = 0.8  # seed (David): rubber pads
FACETS = 8
HOLD_SAFETY = 1.5  # seed (David): safety factor on the grip
REG = 1e-2
_EPS = 1e-6  # OSQP absolute/relative tolerances (N)
ADAPTIVE_RHO_INTERVAL = 25  # OSQP iterations between rho updates: fixed, not timed by its set-up (same bytes)


@dataclass(frozen=True)
class Contact:
    """A contact: ``point`` (m, world), unit ``normal`` pointing into the ball (the
    direction the hand pushes), position Jacobian of the point (3, n)."""

    name: str
    point: np.ndarray
    normal: np.ndarray
    jacobian: np.ndarray


@dataclass(frozen=True)
class GraspProblem:
    """The QP ``min 1/2 x'Px + c'x  s.t.  l <= A x <= u`` over x = stacked contact forces,
    and what it was built from (for reports and for errors)."""

    case: str
    contacts: tuple[Contact, ...]
    required_force: np.ndarray
    centre: np.ndarray
    mu: float
    facets: int
    moment_balance: bool
    tau_offset: np.ndarray  # motor torques with no contact force (gravity), N m
    tau_map: np.ndarray  # (n_motor, 3 C): motor torques per unit contact force
    motor_names: tuple[str, ...]
    capacity: np.ndarray  # each motor's capacity (N m): min(peak torque, tendon force x radius)
    parts: tuple[str, ...]  # what sets each capacity (planner.hand.tendon)
    P: np.ndarray  # (3 C, 3 C) dense, the QP's Hessian
    c: np.ndarray
    A: np.ndarray  # (rows, 3 C) dense
    lower: np.ndarray
    upper: np.ndarray


@dataclass(frozen=True)
class GraspResult:
    problem: GraspProblem
    forces: np.ndarray  # (C, 3) N, force of each contact on the ball
    motor_torques: np.ndarray  # (n_motor,) N m
    headroom: float  # min over motors of 1 - |tau| / capacity
    limiting_motor: str
    status: str
    limiting_part: str = ""  # "motor torque", "tendon force" or "gear"

    @property
    def total_force(self) -> np.ndarray:
        return self.forces.sum(axis=0)

    def normal_forces(self) -> np.ndarray:
        return np.array([f @ c.normal for f, c in zip(self.forces, self.problem.contacts)])

    def cone_margin(self) -> float:
        """min over contacts of mu |f_n| - |f_t| (N); >= 0 inside every true cone."""
        m = np.inf
        for f, c in zip(self.forces, self.problem.contacts):
            fn = float(f @ c.normal)
            ft = float(np.linalg.norm(f - fn * c.normal))
            m = min(m, self.problem.mu * fn - ft)
        return float(m)


# ------------------------------------------------------------------ required forces


def stop_force(mass_kg: float, v_arrival: np.ndarray,
               stop_distance_m: float) -> np.ndarray:
    """Total contact force (N) that stops a ball arriving at ``v_arrival`` over
    ``stop_distance_m`` at constant deceleration, against gravity as well."""
    v = np.asarray(v_arrival, dtype=float)
    speed = float(np.linalg.norm(v))
    if not (mass_kg > 0 and stop_distance_m > 0 and np.isfinite(speed)):
        raise InputError("stop_force needs mass > 0, stop distance > 0 and a finite velocity")
    a = -(speed * speed / (2.0 * stop_distance_m)) * (v / speed if speed > 0 else v)
    return mass_kg * (a - GRAVITY_WORLD)


def hold_force(mass_kg: float, safety: float = HOLD_SAFETY) -> np.ndarray:
    """Total contact force (N) holding a ball still against gravity, times ``safety``."""
    return -safety * mass_kg * GRAVITY_WORLD


def stop_time(v_arrival: np.ndarray, stop_distance_m: float) -> float:
    """Duration (s) of the constant deceleration: 2 d / v."""
    speed = float(np.linalg.norm(v_arrival))
    return 2.0 * stop_distance_m / speed if speed > 0 else 0.0


# ------------------------------------------------------------------ contacts


def _pin_index(hand: HandModel) -> np.ndarray:
    model = hand.pin_model
    return np.array([model.idx_qs[model.getJointId(n)] for n in hand.joint_names])


def _kinematics(hand: HandModel, q: np.ndarray, frames: list[str]):
    """World poses (4x4) and world position Jacobians (3, n) of ``frames``, one FK pass."""
    model, data = hand.pin_model, hand.pin_data
    idx = _pin_index(hand)
    qp = np.zeros(model.nq)
    qp[idx] = q
    pin.computeJointJacobians(model, data, qp)
    pin.updateFramePlacements(model, data)
    T, R = hand.T_world_root, hand.T_world_root[:3, :3]
    poses, jacs = [], []
    for f in frames:
        fid = model.getFrameId(f)
        poses.append(T @ data.oMf[fid].homogeneous)
        J = pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        jacs.append(R @ J[:3, idx])
    return poses, jacs


def palm_jacobian(hand: HandModel, q: np.ndarray) -> np.ndarray:
    """World-frame position Jacobian (3, n) of ``palm_center`` in the hand's joint order."""
    return _kinematics(hand, q, [PALM_FRAME])[1][0]


def ball_contacts(hand: HandModel, q: np.ndarray, centre: np.ndarray, radius: float,
                  tip_tol_m: float, palm: bool = True) -> list[Contact]:
    """Contacts of a ball of ``radius`` centred at ``centre`` with the hand at ``q``:
    the palm centre (normal = palm +z) and every fingertip within ``radius + tip_tol_m``
    of the centre (normal from the tip towards the centre)."""
    centre = np.asarray(centre, dtype=float)
    frames = [PALM_FRAME, *hand.tip_frames]
    poses, jacs = _kinematics(hand, q, frames)
    out: list[Contact] = []
    if palm:
        T = poses[0]
        out.append(Contact("palm", T[:3, 3].copy(), T[:3, 2].copy(), jacs[0]))
    for k, f in enumerate(hand.fingers):
        tip = poses[k + 1][:3, 3]
        d = centre - tip
        dist = float(np.linalg.norm(d))
        if dist <= radius + tip_tol_m and dist > 1e-9:
            out.append(Contact(f, tip.copy(), d / dist, jacs[k + 1]))
    return out


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _tangents(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = _cross(n, a)
    e1 /= np.linalg.norm(e1)
    return e1, _cross(n, e1)


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


# ------------------------------------------------------------------ the QP


def build_grasp_problem(hand: HandModel, q: np.ndarray, contacts: list[Contact],
                        required_force: np.ndarray, centre: np.ndarray, case: str = "hold",
                        mu: float = MU_RUBBER, facets: int = FACETS,
                        moment_balance: bool = True) -> GraspProblem:
    """Assemble the force QP (see the module docstring); nothing is solved here."""
    if not contacts:
        raise InputError("a grasp needs at least one contact")
    if not 4 <= facets <= 8:
        raise InputError(f"friction pyramid facets must be 4..8, got {facets}")
    if not mu > 0:
        raise InputError(f"friction coefficient must be > 0, got {mu}")
    q = np.asarray(q, dtype=float)
    centre = np.asarray(centre, dtype=float)
    F = np.asarray(required_force, dtype=float)
    nc = len(contacts)
    nx = 3 * nc
    # motor torques: offset (gravity) and one column per unit contact force
    M = motor_torque_matrix(hand, q)
    tau_offset = M @ hand.gravity_torques(q)
    # column 3c + a: motor torques for a unit force along axis a at contact c (J_c^T e_a)
    tau_map = M @ np.concatenate([ct.jacobian for ct in contacts], axis=0).T
    cap = actuator_capacity(hand)
    cap_nm = cap.torque_nm

    # force balance (equalities)
    eq = [np.tile(np.eye(3), nc)]
    eq_b = [F]
    if moment_balance:
        # moments about the centre, divided by the contacts' largest lever arm (rows of
        # the same scale as the force rows; the constraint is the same)
        arms = np.array([ct.point - centre for ct in contacts])
        lever = float(np.linalg.norm(arms, axis=1).max()) or 1.0
        eq.append(np.hstack([_skew(a) for a in arms]) / lever)
        eq_b.append(np.zeros(3))
    rows = np.vstack(eq)
    lo = hi = np.concatenate(eq_b)
    # friction pyramids: n . f >= 0 and (t_k - mu' n) . f <= 0
    mu_in = mu * np.cos(np.pi / facets)
    ang = 2.0 * np.pi * np.arange(facets) / facets
    cos_k, sin_k = np.cos(ang)[:, None], np.sin(ang)[:, None]
    cone_rows = np.zeros((nc * (facets + 1), nx))
    cone_lo = np.tile(np.concatenate([[0.0], np.full(facets, -np.inf)]), nc)
    cone_hi = np.tile(np.concatenate([[np.inf], np.zeros(facets)]), nc)
    for c, ct in enumerate(contacts):
        n = ct.normal / np.linalg.norm(ct.normal)
        e1, e2 = _tangents(n)
        r0 = c * (facets + 1)
        cone_rows[r0, 3 * c:3 * c + 3] = n
        cone_rows[r0 + 1:r0 + 1 + facets, 3 * c:3 * c + 3] = cos_k * e1 + sin_k * e2 - mu_in * n
    A_dense = np.vstack([rows, cone_rows, tau_map])
    lower = np.concatenate([lo, cone_lo, -cap_nm - tau_offset])
    upper = np.concatenate([hi, cone_hi, cap_nm - tau_offset])
    # objective: |f|^2 + REG sum (tau/cap)^2  (tau affine in f)
    W = tau_map / cap_nm[:, None]
    P = 2.0 * (np.eye(nx) + REG * W.T @ W)
    cvec = 2.0 * REG * W.T @ (tau_offset / cap_nm)
    return GraspProblem(case, tuple(contacts), F, centre, float(mu), int(facets),
                        bool(moment_balance), tau_offset, tau_map, tuple(hand.motor_names), cap_nm,
                        tuple(cap.limiting(m) for m in range(len(cap_nm))), P, cvec, A_dense,
                        lower, upper)


_SETTINGS = {"eps_abs": _EPS, "eps_rel": _EPS, "eps_prim_inf": 1e-6, "eps_dual_inf": 1e-6,
                 "max_iter": 20000, "polishing": False, "warm_starting": False,
                 "adaptive_rho_interval": ADAPTIVE_RHO_INTERVAL}


class GraspTorqueError(InfeasibleError):
    """The grasp QP: a force split inside the friction cones exists, but it needs a motor
    beyond its capacity (the message names the motor and its torque)."""


class GraspFrictionError(InfeasibleError):
    """The grasp QP: no force split over the contacts lies inside their friction cones."""


def _osqp_solve(prob: GraspProblem):
    """OSQP on ``prob``, set up for it alone (cold): the answer a function of the problem.
    (A solver kept per size and warm-started from the previous solution answered to the
    solver tolerance, and that last digit depended on what had been solved before.)"""
    # (first used by the ending of a live session: not imported at its start)
    from planner.qp import DenseQp

    return DenseQp(**_SETTINGS).solve(prob.P, prob.c, prob.A, prob.lower, prob.upper)


def solve_grasp(prob: GraspProblem) -> GraspResult:
    """Solve the force QP with OSQP; InfeasibleError / SolverError carry ``prob``."""
    # a motor already past its capacity with no contact force at all (gravity alone)
    over = np.abs(prob.tau_offset) > prob.capacity
    res = _osqp_solve(prob)
    status = res.status
    if res.primal_infeasible or (not res.solved and over.any()):
        raise _infeasible(prob)
    if not res.solved:
        raise SolverError(f"grasp QP ({prob.case}) failed: {status}", problem=prob)
    x = res.x
    tau = prob.tau_offset + prob.tau_map @ x
    ratio = np.abs(tau) / prob.capacity
    m = int(np.argmax(ratio))
    if ratio[m] > 1.0 + 1e-4:  # "solved inaccurate" that is not really inside the limits
        raise _infeasible(prob)
    return GraspResult(prob, x.reshape(-1, 3), tau, float(1.0 - ratio[m]), prob.motor_names[m],
                       status, prob.parts[m])


def _infeasible(prob: GraspProblem) -> InfeasibleError:
    """Which motor is short (``GraspTorqueError``): the motor whose capacity is exceeded in
    the least-torque force split that satisfies the balance and cone constraints alone; or
    no split inside the cones at all (``GraspFrictionError``)."""
    F = np.linalg.norm(prob.required_force)
    where = ", ".join(c.name for c in prob.contacts)
    try:
        nx = prob.A.shape[1]
        n_motor = len(prob.capacity)
        A = prob.A[:-n_motor]
        W = prob.tau_map / prob.capacity[:, None]
        P = 2.0 * (W.T @ W + 1e-6 * np.eye(nx))
        c = 2.0 * W.T @ (prob.tau_offset / prob.capacity)
        # (first used by the ending of a live session: not imported at its start)
        from planner.qp import DenseQp

        solver = DenseQp(eps_abs=_EPS, eps_rel=_EPS, max_iter=20000,
                         adaptive_rho_interval=ADAPTIVE_RHO_INTERVAL)
        res = solver.solve(P, c, A, prob.lower[:-n_motor], prob.upper[:-n_motor])
        if not res.solved:
            return GraspFrictionError(f"{prob.case}: no force split of {F:.1f} N over {where} "
                                      f"lies inside the friction cones (mu {prob.mu:g})",
                                      problem=prob)
        tau = prob.tau_offset + prob.tau_map @ res.x
        ratio = np.abs(tau) / prob.capacity
        m = int(np.argmax(ratio))
        return GraspTorqueError(f"{prob.case}: {F:.1f} N over {where} needs motor."
                                f"{prob.motor_names[m]} at {abs(tau[m]):.2f} N m > its "
                                f"{prob.parts[m]} limit {prob.capacity[m]:.2f} N m", problem=prob)
    except (ValueError, RuntimeError, SolverError):  # pragma: no cover - diagnostics only
        return GraspTorqueError(f"{prob.case}: {F:.1f} N over {where} exceeds a motor's "
                                "capacity", problem=prob)


def grasp_forces(hand: HandModel, q: np.ndarray, centre: np.ndarray, radius: float,
                 required_force: np.ndarray, case: str = "hold", tip_tol_m: float = 0.010,
                 moment_balance: bool = True, mu: float = MU_RUBBER,
                 facets: int = FACETS) -> GraspResult:
    """Contacts at ``q`` (palm + fingertips within ``radius + tip_tol_m``), build, solve."""
    contacts = ball_contacts(hand, q, centre, radius, tip_tol_m)
    prob = build_grasp_problem(hand, q, contacts, required_force, centre, case, mu, facets,
                               moment_balance)
    return solve_grasp(prob)

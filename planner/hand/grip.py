"""The hand's grip on a cylinder: where each finger closes on it, and the largest
squeeze its motors and tendons hold (a small LP on OSQP).

The cylinder (seed 000, line 128: "gripping a ball with a diameter of 2.5 inches";
a cylinder here, so that all four fingers, side by side, close on it) lies on the palm:
its axis runs across the palm (the palm frame's x), ``radius`` off the palm's surface.
Where along the palm: from ``palm_center`` towards the knuckles in steps of
``PLACE_STEP_M``, the place where the grip is largest (of equals the one with the most
fingers touching, then the first; at the
palm centre the 1.5x palm is too long for any finger of the shipped hands to curl back
onto it).

Closing: each finger (and the thumb) curls from straight, every tendon-driven flexion
joint at the same fraction ``s`` of its upper limit (abduction 0), until its pad point
first reaches the cylinder's surface (``s`` by sampling, then bisection to 1e-9). A
finger that never reaches it, or whose other joints would be inside the cylinder
first, does not grip.

Grip force: contacts at the touching pads and, for each, on the palm where the
cylinder's side lies on it, across from the pad (the cylinder touches the palm along a
line; one point of it per finger), each force inside its friction pyramid (the catch's: mu = 0.8, seed 000 David, 8 facets),
the forces and their moments about the cylinder's centre balanced (no load on the
cylinder but the hand's), every motor within its capacity (``planner.hand.tendon``)
for the joint torques ``sum_c J_c^T f_c``; the hand's own weight is not counted (a
property of the hand, not of its mount). Maximise the palm's normal force, which is
what a dynamometer between palm and fingers reads: the grip force. The constraint rows
are the grasp QP's (``planner.catch.grasp.build_grasp_problem``); the LP is solved by
SciPy's HiGHS (``linprog``): OSQP, an ADMM solver, does not converge on this LP in
200 000 iterations (measured), HiGHS solves it exactly at a vertex.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from planner.catch.grasp import Contact, build_grasp_problem
from planner.errors import InfeasibleError
from planner.hand.model import HandModel
from planner.hand.spec import INCH_M, PALM_FRAME
from planner.hand.tendon import actuator_capacity

CYLINDER_DIAMETER_M = 2.5 * INCH_M  # seed 000, line 128: the 2.5 in ball grip
CURL_SAMPLES = 100  # fractions s in [0, 1] tried before the bisection
TOUCH_TOL_M = 1e-9  # bisection stops within this of the surface
BINDING = 1e-3  # a motor within 0.1 % of its capacity is counted as limiting
PLACE_STEP_M = 0.005  # the cylinder's places along the palm, this far apart


@dataclass(frozen=True)
class Closure:
    """Where one finger closes on the cylinder: ``curl`` (the fraction s), its joints
    ``q`` (the whole hand's vector, others as given), the pad point and the contact
    normal (into the cylinder, perpendicular to its axis). ``reached`` False: no
    posture of the curl touches it (``why`` says what is in the way)."""

    finger: str
    reached: bool
    curl: float
    q: np.ndarray
    point_m: np.ndarray
    normal: np.ndarray
    why: str = ""


@dataclass(frozen=True)
class Grip:
    """The grip on the cylinder: ``force_n`` (the palm's normal force), the fingers
    that touch, the motors at their capacity and what limits each."""

    diameter_m: float
    offset_m: float  # where the cylinder lies: this far from the palm centre to the knuckles
    force_n: float
    fingers: tuple[str, ...]
    closures: tuple[Closure, ...]
    limiting: tuple[str, ...]  # e.g. "tendon force (motor.index_mcp)"
    finger_forces_n: tuple[float, ...]  # normal force of each touching finger
    q: np.ndarray | None = None  # the closed hand
    contacts: tuple[Contact, ...] = ()  # the palm's, then the pads'
    forces_n: np.ndarray | None = None  # (len(contacts), 3): each contact's force on the cylinder

    @property
    def force_kgf(self) -> float:
        return self.force_n / 9.81


def cylinder_frame(hand: HandModel, q: np.ndarray, radius: float,
                   offset_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The cylinder's centre (on its axis, ``offset_m`` from the palm centre towards the
    knuckles: the palm_center frame's -y) and its unit axis (world)."""
    P = hand.frame_pose(q, PALM_FRAME)
    return P[:3, 3] + radius * P[:3, 2] - offset_m * P[:3, 1], P[:3, 0].copy()


def _axis_distance(p: np.ndarray, centre: np.ndarray, axis: np.ndarray) -> float:
    d = p - centre
    return float(np.linalg.norm(d - (d @ axis) * axis))


def _finger_points(hand: HandModel, q: np.ndarray, finger: str) -> tuple[np.ndarray, np.ndarray]:
    """The pad point and the finger's joint origins (world) at ``q`` (one FK pass)."""
    m, d = hand.pin_model, hand.pin_data
    qp = np.zeros(m.nq)
    qp[[m.idx_qs[m.getJointId(n)] for n in hand.joint_names]] = q
    pin.forwardKinematics(m, d, qp)
    R, t = hand.T_world_root[:3, :3], hand.T_world_root[:3, 3]
    pad = pin.updateFramePlacement(m, d, m.getFrameId(hand.tip_frames[hand.fingers.index(finger)]))
    joints = [R @ d.oMi[m.getJointId(j)].translation + t for j in hand.spec.joints_of(finger)]
    return R @ pad.translation + t, np.array(joints)


def flexion_joints(hand: HandModel, finger: str) -> list[int]:
    """The finger's independent joints a tendon motor or a finger's geared motor drives (its
    flexion joints; not the abduction servos). The AGH's paired base joint is the
    flexion joint of its shaft's source finger only: the other finger's follows it."""
    own = set(hand.spec.joints_of(finger))
    return [hand.index[a.drives] for a in hand.actuators
            if (a.tendon_force_n is not None or a.kind == "gear") and a.drives in own]


def curled(hand: HandModel, q0: np.ndarray, finger: str, s: float) -> np.ndarray:
    """``q0`` with ``finger`` curled: its flexion joints at ``s`` x their upper limit
    (clipped into the range), its other joints at 0 (clipped), couplings applied."""
    q = q0.copy()
    for j in hand.joint_slice(finger):
        q[j] = np.clip(0.0, hand.lower[j], hand.upper[j])
    for j in flexion_joints(hand, finger):
        q[j] = np.clip(s * hand.upper[j], hand.lower[j], hand.upper[j])
    return hand.apply_couplings(q)


def close_on(hand: HandModel, q0: np.ndarray, finger: str, centre: np.ndarray,
             axis: np.ndarray, radius: float) -> Closure:
    """Curl ``finger`` until its pad first touches the cylinder (see the module)."""
    def gap(s: float) -> float:
        pad, _ = _finger_points(hand, curled(hand, q0, finger, s), finger)
        return _axis_distance(pad, centre, axis) - radius

    grid = np.linspace(0.0, 1.0, CURL_SAMPLES + 1)
    gaps = [gap(s) for s in grid]
    hit = next((k for k, g in enumerate(gaps) if g <= 0.0), None)
    if hit is None or hit == 0:
        q = curled(hand, q0, finger, 1.0 if hit is None else 0.0)
        why = (f"closed, its pad stays {1000 * min(gaps):.1f} mm off the cylinder"
               if hit is None else "its pad is inside the cylinder when straight")
        return Closure(finger, False, 1.0, q, np.zeros(3), np.zeros(3), why)
    lo, hi = grid[hit - 1], grid[hit]
    while hi - lo > TOUCH_TOL_M:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gap(mid) > 0.0 else (lo, mid)
    q = curled(hand, q0, finger, hi)
    pad, joints = _finger_points(hand, q, finger)
    inside = [j for j, p in zip(hand.spec.joints_of(finger), joints)
              if _axis_distance(p, centre, axis) < radius - 1e-6]
    d = centre - pad
    n = d - (d @ axis) * axis
    n /= np.linalg.norm(n)
    if inside:
        return Closure(finger, False, hi, q, pad, n, f"{', '.join(inside)} inside the cylinder "
                       "before the pad touches")
    return Closure(finger, True, hi, q, pad, n)


def grip(hand: HandModel, diameter_m: float = CYLINDER_DIAMETER_M) -> Grip:
    """The largest grip on the cylinder over its places along the palm (see the module)."""
    half_palm = next(lk.size_m[1] for lk in hand.spec.links if lk.name == "palm") / 2
    best = None
    for k in range(int(half_palm / PLACE_STEP_M + 1e-9) + 1):
        g = grip_at(hand, k * PLACE_STEP_M, diameter_m)
        if best is None or g.force_n > best.force_n + 1e-9 or (
                g.force_n > best.force_n - 1e-9 and len(g.fingers) > len(best.fingers)):
            best = g
    return best


def grip_at(hand: HandModel, offset_m: float, diameter_m: float = CYLINDER_DIAMETER_M) -> Grip:
    """Close every finger on the cylinder lying ``offset_m`` from the palm centre towards
    the knuckles, and find the largest grip there (see the module)."""
    radius = 0.5 * diameter_m
    q = hand.q_neutral.copy()
    centre, axis = cylinder_frame(hand, q, radius, offset_m)
    closures = tuple(close_on(hand, q, f, centre, axis, radius) for f in hand.fingers)
    for c in closures:
        if c.reached:
            for j in hand.joint_slice(c.finger):
                q[j] = c.q[j]
    q = hand.apply_couplings(q)
    touching = [c for c in closures if c.reached]
    if not touching:
        return Grip(diameter_m, offset_m, 0.0, (), closures, ("no finger reaches the cylinder",),
                    ())
    jac = hand.tip_jacobians(q)
    normal = hand.frame_pose(q, PALM_FRAME)[:3, 2]
    line = centre - radius * normal  # where the cylinder's side touches the palm
    palm = [Contact(f"palm@{c.finger}", p, normal.copy(), palm_point_jacobian(hand, q, p))
            for c in touching for p in [line + ((c.point_m - line) @ axis) * axis]]
    tips = [Contact(c.finger, c.point_m, c.normal, jac[hand.fingers.index(c.finger)])
            for c in touching]
    f, prob = _max_squeeze(hand, q, palm + tips, centre)
    tau = prob.tau_map @ f.ravel()
    ratio = np.abs(tau) / prob.capacity
    cap = actuator_capacity(hand)
    binding = [m for m in np.argsort(-ratio) if ratio[m] >= 1.0 - BINDING]
    k = len(palm)
    force = float(sum(fc @ ct.normal for fc, ct in zip(f[:k], palm)))
    limiting = tuple(cap.part(int(m)) for m in binding)
    if not binding:
        against = max(-float(ct.normal @ normal) for ct in tips)
        why = (f"no motor: the pads meet the cylinder's side (at best {against:+.2f} of a "
               "pad's push is against the palm), a push along the palm nothing balances")
        limiting = (why,)
    return Grip(diameter_m, offset_m, force, tuple(c.finger for c in touching), closures,
                limiting,
                tuple(float(fc @ ct.normal) for fc, ct in zip(f[k:], tips)), q,
                tuple(palm + tips), f)


def _max_squeeze(hand: HandModel, q: np.ndarray, contacts: list[Contact], centre: np.ndarray):
    """The LP: the grasp QP's rows (balance, friction pyramids, motor rows within
    +-capacity, gravity left out), maximising the palm contacts' normal forces."""
    from scipy.optimize import linprog

    prob = build_grasp_problem(hand, q, contacts, np.zeros(3), centre, case="grip")
    n_motor = len(prob.capacity)
    lower, upper = prob.lower.copy(), prob.upper.copy()
    lower[-n_motor:], upper[-n_motor:] = -prob.capacity, prob.capacity
    c = np.zeros(prob.A.shape[1])
    for k, ct in enumerate(contacts):
        if ct.name.startswith("palm"):
            c[3 * k:3 * k + 3] = -ct.normal
    eq = lower == upper
    hi, lo = ~eq & np.isfinite(upper), ~eq & np.isfinite(lower)
    res = linprog(c, A_ub=np.vstack([prob.A[hi], -prob.A[lo]]),
                  b_ub=np.concatenate([upper[hi], -lower[lo]]), A_eq=prob.A[eq], b_eq=lower[eq],
                  bounds=[(None, None)] * len(c), method="highs")
    if res.status != 0:
        raise InfeasibleError(f"grip LP on the cylinder: {res.message}")
    return res.x.reshape(-1, 3), prob


def palm_point_jacobian(hand: HandModel, q: np.ndarray, point_m: np.ndarray) -> np.ndarray:
    """World position Jacobian (3, n) of a point fixed to the palm, at ``point_m`` (world)."""
    model, data = hand.pin_model, hand.pin_data
    qp = np.zeros(model.nq)
    idx = np.array([model.idx_qs[model.getJointId(n)] for n in hand.joint_names])
    qp[idx] = q
    pin.computeJointJacobians(model, data, qp)
    pin.updateFramePlacements(model, data)
    fid = model.getFrameId(PALM_FRAME)
    J = pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:, idx]
    R, t = hand.T_world_root[:3, :3], hand.T_world_root[:3, 3]
    r = point_m - (R @ data.oMf[fid].translation + t)
    Jv, Jw = R @ J[:3], R @ J[3:]
    return Jv - np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]]) @ Jw

"""Catch: throw -> intercept -> open pre-catch pose -> closing -> trajectory file.

World = the catch frame (spec section 5): origin at the launch point, +x towards
the hand, z up; the nominal catch point C = (dist, 0, height) is where the throw
passes in a vacuum.

Mount. The rail base (URDF root) sits at ``C + offset_m`` with orientation
``rpy_deg`` (catch-frame axes), from the hand file's optional ``[catch]``
section or, without one, from ``default_mount``: the wrist flexion axis
horizontal and across the throw (so flexion turns the palm normal inside the
x-z plane of the ball's path), the palm normal at zero flexion pointing back
along a ball that descends at ``DESIGN_DESCENT_DEG`` (32 deg), the fingers up,
and the wrist axis placed so that the nominal path passes the wrist at the
palm's own distance (``|palm_center - wrist|`` measured along the palm). With
that placement the wrist's two joints (flexion: direction of the normal;
deviation: how far along the palm the ball lands, cos(dev)) let the palm face
the ball exactly for arrival angles within about +-30 deg of the design angle;
the rail, which runs across the throw, takes up the sideways shift that
deviation causes. Outside that range the palm meets the ball at an angle (the
misalignment is reported and the stopping QP's friction cone decides whether
the palm can still stop it).

Everything per throw is computed in the *reference frame*: the catch frame
shifted so that C is the origin. The hand mounted there (``CatchPlanner.hand``)
and its IK solver are built once; a throw only shifts the ball by -C, and the
file's ``T_world_root`` is the reference mount shifted by +C
(``hand.mounted(T_world_root)`` is the same hand in the catch frame).

Per throw (``CatchPlanner.plan``):

1. Intercept (``_intercept``): on the ball's path near C, the time t at which
   the palm can hold ``palm_center + radius * n = ball(t)`` with n (the palm's
   +z) against the ball's velocity: flexion from the velocity's direction,
   then t from the ball's height above the palm plane (a root in t), then
   deviation and rail in closed form. When no pose faces the ball exactly
   (deviation or flexion out of range), the palm's position alone is solved
   (deviation clamped) and the misalignment reported; when even that fails the
   throw is out of reach. The pose is then confirmed with placo
   (``HandIK.solve_palm``, warm-started: usually zero or one iteration) and the
   intercept time refined on the confirmed pose.
2. Closing (``_closing``, once per ball radius, cached): a closed hand whose
   fingertips sit ``TIP_GAP_M`` outside the ball's surface, each at 40 deg
   above the ball's equator on its own finger's side (IK, wrist and rail
   locked; fingers that cannot reach are pulled to the nearest point of the
   sphere). The grasp condition of the independent check (thumb plus two more
   fingertips within radius + 10 mm of the ball centre, here planned with 2 mm
   to spare) is evaluated along the min-jerk closing move in the palm frame;
   the fraction of the move after which it holds for good is ``u_grasp``.
   Open = the closed pose's abduction joints with every flexion joint at 0
   (extended), so the closing move is pure flexion.
3. Timing: the hand starts from ``rest`` at t = 0 and begins to move after
   ``SIGNAL_S`` (25 ms, seed) + ``PLAN_BUDGET_S`` (5 ms, the planning latency
   budget) -- later with observations: after the last observation. The move to
   the open pose lasts ``phase_duration`` (min-jerk within speed and
   acceleration limits). The closing move (also ``phase_duration``; seed: 150-
   300 ms) is placed so that the grasp condition is met when the ball has
   stopped in the palm (``stop_time`` after the intercept), then delayed if a
   fingertip would come within ``TOUCH_CLEAR_M`` of the still-arriving ball;
   it must complete the grasp within ``GRASP_WINDOW_S`` (150 ms) of the
   intercept. Rows at ``rate_hz`` until ``intercept_t + HOLD_AFTER_S``.
4. Forces (``planner.catch.grasp``): stopping the ball on the palm (2 cm give)
   and holding it in the closed hand, each a QP with friction cones and every
   motor within its capacity (its peak torque, or its tendon's design force at the
   spool: ``planner.hand.tendon``); headroom and the limiting motor are reported.
5. Self-check on the rows (same criteria as the independent check): the ball
   within ``INTERCEPT_TOL_M`` of ``palm_center + radius * n`` at intercept_t
   (joints interpolated), no fingertip inside the ball before it, the grasp
   within the window and held to the end.

Infeasible throws (out of reach, too fast, fingers in the way, grasp, torque)
are planned as far as they go; ``CatchPlan.reasons`` says why.

Known limits of the shipped hands (reported, not hidden): the default hand's
thumb cannot come within radius + 10 mm of a ball held on the palm (its CMC
sits 3 cm proud of the palm; with CMC flexion at 90 deg and IP at 80 deg, both
at their limits, the tip stays ~17 mm outside a tennis ball), so every catch
with it fails the grasp criterion; a CMC flexion range of 110 deg (or the CMC
1 cm closer to the palm) would reach. The mk5 hand's true-size fingers do not
reach a ball on its 1.5x palm at all. Stopping a ball that arrives faster than
~5.3 m/s over the palm's 2 cm give needs more than the wrist flexion motor's
2 N m peak.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import cached_property
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import tomllib

from planner.catch import grasp as gq
from planner.catch.flight import (
    Ball,
    FitResult,
    Flight,
    check_throw,
    fit_observations,
    get_ball,
    load_observations_csv,
    predict_intercept,
    predict_throw,
)
from planner.catch.flight import _finite as flight_finite
from planner.check.criteria import (
    GRASP_MIN_TIPS,
    GRASP_TOL_M,
    GRASP_WINDOW_S,
    INTERCEPT_TOL_M,
)
from planner.errors import InfeasibleError, InputError, PlannerError
from planner.hand.model import HandModel, load_hand
from planner.hand.spec import PALM_FRAME, hands_dir, rpy_matrix
from planner.ik import HandIK, PressTarget
from planner.trajectory import Phase, min_jerk, phase_duration, sample
from planner.trajfile import TrajectoryWriter

SIGNAL_S = 0.025  # seed (Markus): 25 ms of signal processing
PLAN_BUDGET_S = 0.005  # planning latency budget (bench target p99)
ACTUATION_SEED_S = (0.150, 0.300)  # seed: open-to-closed actuation time
# (GRASP_WINDOW_S, GRASP_TOL_M, GRASP_MIN_TIPS, INTERCEPT_TOL_M: the check's criteria,
# one definition, imported above; the planner aims inside them)
GRASP_MARGIN_M = 0.002  # planned with this much to spare
INTERCEPT_PLAN_TOL_M = 0.001  # what the planner aims for
TOUCH_CLEAR_M = 0.002  # before intercept_t fingertips stay this far outside the ball
TIP_GAP_M = 0.003  # closed fingertips: this far outside the ball's surface
TIP_ELEVATION_DEG = 40.0  # closed fingertips: above the ball's equator (palm = south pole)
HOLD_AFTER_S = 0.5  # rows until intercept_t + this
DESIGN_DESCENT_DEG = 36.0  # default mount: the palm faces a ball descending at this angle
DESIGN_DEV_DEG = 10.0  # ... with the wrist deviated this much (room for the path's curvature)
REST_CURL = 0.3  # rest pose: flexion joints at this fraction of their upper limit
MAX_MISALIGN_DEG = 80.0  # beyond this the ball grazes the palm: out of reach
_N_SEARCH = 46  # samples of the ball's path in the intercept search
_N_CLOSE = 201  # samples of the closing move (palm frame table)
_N_CAND = 25  # candidate starts of the closing move
_WRIST = ("wrist_flex", "wrist_dev")


# ====================================================================== mount


@dataclass(frozen=True)
class CatchMount:
    """Pose of the rail base (URDF root) relative to the nominal catch point.

    ``offset_m``: root origin minus the catch point, catch-frame axes (m);
    ``rpy_deg``: URDF roll-pitch-yaw of the root in the catch frame (deg)."""

    offset_m: tuple[float, float, float]
    rpy_deg: tuple[float, float, float]
    source: str

    @property
    def rotation(self) -> np.ndarray:
        return rpy_matrix(tuple(math.radians(a) for a in self.rpy_deg))

    def T_ref(self) -> np.ndarray:
        """Root pose in the reference frame (catch point at the origin)."""
        T = np.eye(4)
        T[:3, :3] = self.rotation
        T[:3, 3] = self.offset_m
        return T

    def T_world_root(self, catch_point: np.ndarray) -> np.ndarray:
        T = self.T_ref()
        T[:3, 3] += np.asarray(catch_point, dtype=float)
        return T


def _hand_file(name_or_path: str) -> Path | None:
    p = Path(name_or_path)
    if p.suffix == ".toml":
        return p if p.is_file() else None
    f = hands_dir() / f"{name_or_path}.toml"
    return f if f.is_file() else None


def _vec3(d: dict[str, Any], key: str, where: str) -> tuple[float, float, float]:
    v = d.get(key)
    if (not isinstance(v, list) or len(v) != 3 or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
            for x in v)):
        raise InputError(f"{where}: [catch] {key} must be a list of 3 finite numbers")
    return (float(v[0]), float(v[1]), float(v[2]))


def mount_from_file(path: Path) -> CatchMount | None:
    """The ``[catch]`` section of a hand file (``offset_m``, ``rpy_deg``), or None."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise InputError(f"cannot read hand file {path}: {e}") from None
    sec = data.get("catch")
    if sec is None:
        return None
    if not isinstance(sec, dict):
        raise InputError(f"{path.name}: [catch] must be a table")
    return CatchMount(_vec3(sec, "offset_m", path.name), _vec3(sec, "rpy_deg", path.name),
                      f"{path.name} [catch]")


def default_mount(hand: HandModel, descent_deg: float = DESIGN_DESCENT_DEG,
                  dev_deg: float = DESIGN_DEV_DEG) -> CatchMount:
    """The mount described in the module docstring, computed from the hand's geometry.

    Orientation: root x across the throw (+y of the catch frame), the palm normal at
    zero flexion = (-cos a, 0, sin a), a = ``descent_deg``: rpy = (90 + a, 0, 90).
    Position: the catch point C lies in the plane through the wrist axis that is
    parallel to the palm, at cos(``dev_deg``) times the palm centre's distance from
    the axis: a ball descending at ``descent_deg`` then lands on the palm centre with
    the wrist deviated by ``dev_deg``, which leaves deviation to spare both ways
    (towards 0 for the path's curvature, towards the limit for other angles)."""
    rpy = (90.0 + descent_deg, 0.0, 90.0)
    R = rpy_matrix(tuple(math.radians(a) for a in rpy))
    h = hand.mounted(np.eye(4))
    q0 = _zero_pose(h)
    P = h.palm_pose(q0)
    pc, n = P[:3, 3], P[:3, 2]
    W = h.frame_pose(q0, "wrist_flex")[:3, 3]
    g = pc - W
    g_p = g - float(g @ n) * n
    c_root = W + math.cos(math.radians(dev_deg)) * g_p
    off = -R @ c_root
    return CatchMount((float(off[0]), float(off[1]), float(off[2])), rpy,
                      f"default (palm faces a {descent_deg:g} deg descent)")


def catch_mount(hand: HandModel, source: str | None = None) -> CatchMount:
    """The ``[catch]`` mount of the hand file ``source`` (a name or a .toml path;
    default: the shipped file named like the hand), else ``default_mount``."""
    f = _hand_file(source if source is not None else hand.name)
    m = mount_from_file(f) if f is not None else None
    return m if m is not None else default_mount(hand)


def _zero_pose(hand: HandModel) -> np.ndarray:
    return hand.apply_couplings(np.clip(np.zeros(hand.n), hand.lower, hand.upper))


# ====================================================================== results


@dataclass(frozen=True)
class Closing:
    """The closing move for one ball radius (palm-frame data, throw-independent)."""

    radius: float
    q_closed: np.ndarray  # full configuration at the reference wrist pose
    duration_s: float
    u_grasp: float | None  # fraction of the move after which the grasp holds (None: never)
    tip_dist_m: np.ndarray  # (5,) closed fingertip distance from the ball centre
    grasp_fingers: tuple[str, ...]
    u: np.ndarray  # (K,) move fractions of the table
    tips_pc: np.ndarray  # (K, 5, 3) fingertips in the palm_center frame
    reason: str | None
    reach_m: float  # farthest fingertip from the ball centre during the move
    min_gap_m: np.ndarray  # (5,) closest each fingertip comes to the ball's surface


@dataclass
class CatchPlan:
    """A planned catch (no file written yet)."""

    feasible: bool
    reasons: list[str]
    flight: Flight
    catch_point: np.ndarray
    T_world_root: np.ndarray
    base_hand: HandModel
    rate_hz: float
    throw: dict[str, Any]
    launch_speed: float
    flight_time_s: float | None  # time at x = dist
    intercept_t: float
    intercept_point: np.ndarray  # ball centre at intercept_t (catch frame)
    arrival_velocity: np.ndarray
    intercept_error_m: float  # on the rows, as the independent check computes it
    misalignment_deg: float
    q_rest: np.ndarray
    q_open: np.ndarray
    q_closed: np.ndarray
    move_start_s: float
    move_s: float
    close_start_s: float
    close_s: float
    grasp_t: float | None  # first row time with the grasp
    grasp_fingers: tuple[str, ...]
    min_clearance_before_m: float  # min fingertip distance to the ball surface before intercept
    stop: gq.GraspResult | None
    hold: gq.GraspResult | None
    t: np.ndarray
    q: np.ndarray
    q_motor: np.ndarray
    ik_iterations: int
    t_info_s: float
    uncertainty: dict[str, float] | None = None
    planning_s: float = 0.0
    notes: list[str] = field(default_factory=list)

    @cached_property
    def hand(self) -> HandModel:
        """The hand mounted in the catch frame (``T_world_root``)."""
        return self.base_hand.mounted(self.T_world_root)

    @property
    def ready_s(self) -> float:
        return self.move_start_s + self.move_s

    def margins(self) -> dict[str, float]:
        out = {
            "reaction_s": self.move_start_s,
            "move_s": self.move_s,
            "ready_s": self.ready_s,
            "wait_open_s": self.close_start_s - self.ready_s,
            "close_s": self.close_s,
            "close_lead_s": self.intercept_t - self.close_start_s,
        }
        if self.grasp_t is not None:
            out["grasp_after_s"] = self.grasp_t - self.intercept_t
            out["grasp_slack_s"] = self.intercept_t + GRASP_WINDOW_S - self.grasp_t
        return out

    def metadata(self) -> dict[str, Any]:
        hand = self.base_hand
        return {
            "task": "catch", "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
            "T_world_root": self.T_world_root.tolist(), "rate_hz": self.rate_hz,
            "ball": self.flight.to_metadata(), "intercept_t": float(self.intercept_t),
            "catch": {
                "throw": self.throw,
                "catch_point": [float(x) for x in self.catch_point],
                "close_start": float(self.close_start_s),
                "grasp_t": None if self.grasp_t is None else float(self.grasp_t),
                "feasible": bool(self.feasible),
                "reasons": list(self.reasons),
            },
        }


@dataclass
class CatchResult:
    """What ``plan_catch`` returns: the plan and where it was written."""

    plan: CatchPlan
    out_path: str
    rows: int
    planning_s: float  # per throw: flight, intercept, timing, rows, forces, self-check
    writing_s: float
    setup_s: float = 0.0  # one-time: hand, IK, closing table (cached across calls)

    @property
    def feasible(self) -> bool:
        return self.plan.feasible

    @property
    def reasons(self) -> list[str]:
        return self.plan.reasons

    def __getattr__(self, name: str) -> Any:  # convenience: result.intercept_t etc.
        if name == "plan":
            raise AttributeError(name)
        return getattr(self.plan, name)


# ====================================================================== geometry helpers


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of (..., 3) arrays (np.cross is slow for small arrays)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _rot(axis: np.ndarray, ang: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v`` (N, 3) by angles ``ang`` (N,) about unit ``axis`` (Rodrigues)."""
    c = np.cos(ang)[:, None]
    s = np.sin(ang)[:, None]
    kv = _cross(np.broadcast_to(axis, v.shape), v)
    return v * c + kv * s + np.outer(v @ axis, axis) * (1.0 - c)


def _interp_row(t: np.ndarray, Q: np.ndarray, ti: float) -> np.ndarray:
    """Rows ``Q`` at times ``t`` interpolated linearly at ``ti`` (clamped to the ends)."""
    k = int(np.searchsorted(t, ti, side="right")) - 1
    if k < 0:
        return Q[0].copy()
    if k >= len(t) - 1:
        return Q[-1].copy()
    w = (ti - t[k]) / (t[k + 1] - t[k])
    return (1.0 - w) * Q[k] + w * Q[k + 1]


def _rot1(axis: np.ndarray, ang: float, v: np.ndarray) -> np.ndarray:
    return _rot(axis, np.array([ang]), v[None])[0]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@dataclass(frozen=True)
class _Intercept:
    t: float
    theta: float
    dev: float
    rail: float
    misalign: float  # rad
    aligned: bool
    reason: str | None


# ====================================================================== the planner


class CatchPlanner:
    """Everything built once per hand and mount: reference-mounted hand, IK, poses,
    wrist geometry, closing tables (per ball radius, on first use)."""

    def __init__(self, hand: HandModel, mount: CatchMount) -> None:
        self.base_hand = hand
        self.mount = mount
        self.T_ref = mount.T_ref()
        self.hand = hand.mounted(self.T_ref)
        h = self.hand
        self.ik = HandIK(h)
        idx = h.index
        for n in _WRIST:
            if n not in idx:
                raise PlannerError(f"hand {h.name!r} has no joint {n!r}: the catch planner "
                                   "needs the 2-DOF wrist")
        self.i_flex, self.i_dev = idx["wrist_flex"], idx["wrist_dev"]
        self.i_rail = idx.get("rail")
        self.arm = [i for i in (self.i_rail, self.i_flex, self.i_dev) if i is not None]
        self.finger_idx = np.array(sorted(set(range(h.n)) - set(self.arm)))
        abd = [i for i in self.finger_idx if "abd" in h.joint_names[i]]
        self.abd_idx = np.array(abd, dtype=int)
        self.flexion_idx = np.array([i for i in self.finger_idx if i not in set(abd)], dtype=int)
        self._locked = tuple(h.joint_names[i] for i in self.arm)
        self._pin_idx = np.array([h.pin_model.idx_qs[h.pin_model.getJointId(n)]
                                  for n in h.joint_names])
        self._tip_ids = [h.pin_model.getFrameId(f"{f}_tip") for f in h.fingers]
        self._palm_id = h.pin_model.getFrameId(PALM_FRAME)
        self._pin_data = h.pin_model.createData()
        self.q_zero = _zero_pose(h)
        self._geometry()
        self.q_rest = self._rest_pose()
        self.near_m = self._tip_reach()
        self._closings: dict[float, Closing] = {}

    # ------------------------------------------------------------ setup
    def _geometry(self) -> None:
        """Wrist geometry in the reference frame at zero flexion/deviation/rail, checked
        against the structure the closed-form intercept assumes."""
        h, q0 = self.hand, self.q_zero
        spec = h.spec

        def axis(name: str) -> np.ndarray:
            T = h.frame_pose(q0, name)
            return _unit(T[:3, :3] @ np.array(spec.joint(name).axis, dtype=float))

        self.e_f = axis("wrist_flex")
        self.u_d = axis("wrist_dev")
        self.e_r = axis("rail") if self.i_rail is not None else self.e_f.copy()
        self.W = h.frame_pose(q0, "wrist_flex")[:3, 3].copy()
        D = h.frame_pose(q0, "wrist_dev")[:3, 3]
        P = h.palm_pose(q0)
        self.pc0, self.n0 = P[:3, 3].copy(), P[:3, 2].copy()
        self.g0 = self.pc0 - self.W
        ok = (np.linalg.norm(D - self.W) < 1e-9 and abs(abs(self.u_d @ self.n0) - 1.0) < 1e-9
              and abs(self.e_f @ self.n0) < 1e-9 and abs(abs(self.e_r @ self.e_f) - 1.0) < 1e-9)
        if not ok:
            raise PlannerError("catch planner: the wrist must be flexion (across the rail) then "
                               "deviation about the palm normal, through one point")
        self.b0 = _unit(np.cross(self.n0, self.e_r))
        self._e_t = tuple(float(x) for x in self.e_f)
        self._n0_t = tuple(float(x) for x in self.n0)
        self._W_t = tuple(float(x) for x in self.W)
        g0p = self.g0 - (self.g0 @ self.n0) * self.n0
        self._dev_A = float(g0p @ self.b0)
        self._dev_B = float(np.cross(self.u_d, g0p) @ self.b0)
        self._g0n = float(self.g0 @ self.n0)
        lo, hi = self.hand.lower, self.hand.upper
        self.flex_lim = (float(lo[self.i_flex]), float(hi[self.i_flex]))
        self.dev_lim = (float(lo[self.i_dev]), float(hi[self.i_dev]))
        self.rail_lim = ((float(lo[self.i_rail]), float(hi[self.i_rail]))
                         if self.i_rail is not None else (0.0, 0.0))

    def _tip_reach(self) -> float:
        """Bound on any fingertip's distance from palm_center over the joint box (m):
        the sum of each finger's segment lengths from the palm centre (triangle
        inequality), plus 1 cm."""
        h, q0 = self.hand, self.q_zero
        pc = h.palm_pose(q0)[:3, 3]
        tips = h.tip_positions(q0)
        best = 0.0
        for k, f in enumerate(h.fingers):
            pts = [pc] + [h.frame_pose(q0, j)[:3, 3] for j in h.spec.joints_of(f)] + [tips[k]]
            best = max(best, sum(float(np.linalg.norm(b - a)) for a, b in pairwise(pts)))
        return best + 0.01

    def _rest_pose(self) -> np.ndarray:
        h = self.hand
        q = self.q_zero.copy()
        for i in self.flexion_idx:
            q[i] = REST_CURL * h.upper[i] if h.upper[i] > 0 else 0.0
        return h.apply_couplings(np.clip(q, h.lower, h.upper))

    def closing(self, radius: float) -> Closing:
        """The closing move for a ball of ``radius`` (cached)."""
        key = round(float(radius), 9)
        c = self._closings.get(key)
        if c is None:
            c = self._closings[key] = self._make_closing(float(radius))
        return c

    def _make_closing(self, r: float) -> Closing:
        h, ik = self.hand, self.ik
        q0 = self.q_zero
        centre = self.pc0 + r * self.n0
        T_pc = h.palm_pose(q0)
        el = math.radians(TIP_ELEVATION_DEG)
        # targets: each fingertip at TIP_ELEVATION above the ball's equator, on the side
        # of its finger's base
        targets = []
        for f in h.fingers:
            base = h.frame_pose(q0, h.spec.joints_of(f)[0])[:3, 3]
            d = base - centre
            d = d - (d @ self.n0) * self.n0
            d = _unit(d) if np.linalg.norm(d) > 1e-9 else self.b0
            p = centre + (r + TIP_GAP_M) * (math.cos(el) * d + math.sin(el) * self.n0)
            targets.append(p)
        q_init = q0.copy()
        for i in self.flexion_idx:
            q_init[i] = 0.5 * (h.lower[i] + h.upper[i])
        q_init = h.apply_couplings(np.clip(q_init, h.lower, h.upper))
        for n in self._locked:
            ik.solver.mask_dof(n)
        try:
            res = ik.solve([PressTarget(f, 0, tuple(p), (p[1], p[1]))
                            for f, p in zip(h.fingers, targets)], q_init, q_init, hover=(),
                           max_iter=150)
            q = res.q
            # fingertips that cannot reach their target: the nearest point of the sphere
            for _ in range(2):
                tips = h.tip_positions(q)
                tg = [centre + (r + TIP_GAP_M) * _unit(tp - centre) for tp in tips]
                res = ik.solve([PressTarget(f, 0, tuple(p), (p[1], p[1]))
                                for f, p in zip(h.fingers, tg)], q, q, hover=(), max_iter=80)
                q = res.q
        finally:
            for n in self._locked:
                ik.solver.unmask_dof(n)
        q_closed = q.copy()
        q_closed[self.arm] = q0[self.arm]
        q_open = self._open_from(q0, q_closed)
        dist = np.linalg.norm(h.tip_positions(q_closed) - centre, axis=1)
        # table of the closing move in the palm frame
        u = np.linspace(0.0, 1.0, _N_CLOSE)
        s = min_jerk(u)[:, None]
        Q = h.apply_couplings(q_open + (q_closed - q_open) * s)
        Tinv = np.linalg.inv(T_pc)
        tips_pc = np.empty((len(u), len(h.fingers), 3))
        for k in range(len(u)):
            tw = h.tip_positions(Q[k])
            tips_pc[k] = tw @ Tinv[:3, :3].T + Tinv[:3, 3]
        c_pc = np.array([0.0, 0.0, r])
        d_tab = np.linalg.norm(tips_pc - c_pc, axis=-1)
        within = d_tab <= r + GRASP_TOL_M - GRASP_MARGIN_M
        thumb = h.fingers.index("thumb")
        ok = within[:, thumb] & (within.sum(axis=1) >= GRASP_MIN_TIPS)
        u_g = None
        reason = None
        if ok[-1]:
            bad = np.flatnonzero(~ok)
            u_g = float(u[bad[-1] + 1]) if bad.size else 0.0
        else:
            near = [f"{f} {1000 * (d - r):+.1f} mm" for f, d in zip(h.fingers, dist)]
            why = ("the thumb" if not within[-1, thumb] else
                   f"{GRASP_MIN_TIPS} fingertips")
            reason = (f"grasp: {why} cannot reach within radius + "
                      f"{1000 * (GRASP_TOL_M - GRASP_MARGIN_M):.0f} mm of the ball centre "
                      f"on the palm (closest fingertip-to-surface: {', '.join(near)})")
        fingers = tuple(f for k, f in enumerate(h.fingers) if within[-1, k])
        T_c = phase_duration(q_closed - q_open, h.velocity, h.acceleration)
        return Closing(r, q_closed, T_c, u_g, dist, fingers, u, tips_pc, reason,
                       float(d_tab.max()), (d_tab - r).min(axis=0))

    def _open_from(self, q_arm: np.ndarray, q_closed: np.ndarray) -> np.ndarray:
        """Open hand: the arm joints of ``q_arm``, abduction as in ``q_closed``, flexion 0."""
        q = self.q_zero.copy()
        q[self.arm] = q_arm[self.arm]
        q[self.abd_idx] = q_closed[self.abd_idx]
        return self.hand.apply_couplings(np.clip(q, self.hand.lower, self.hand.upper))

    # ------------------------------------------------------------ intercept
    def _aligned(self, b: np.ndarray, v: np.ndarray, r: float):
        """For path samples (positions b, velocities v, reference frame): flexion that
        turns the normal against v, and h = height of the ball above the palm plane minus r."""
        e, n0 = self.e_f, self.n0
        m = -v - np.outer(-v @ e, e)
        m = _unit(m)
        theta = np.arctan2(_cross(np.broadcast_to(n0, m.shape), m) @ e, m @ n0)
        s = _rot(e, -theta, b - self.W)
        return theta, s, s @ n0 - (self._g0n + r)

    def _aligned1(self, flight: Flight, C: np.ndarray, t: float, r: float
                  ) -> tuple[float, np.ndarray, float]:
        """``_aligned`` for one time (plain float arithmetic: no numpy call overhead)."""
        bx, by, bz = (float(x) for x in flight.position(t) - C)
        vx, vy, vz = (float(x) for x in flight.velocity(t))
        ex, ey, ez = self._e_t
        nx, ny, nz = self._n0_t
        wx, wy, wz = self._W_t
        d = -(vx * ex + vy * ey + vz * ez)
        mx, my, mz = -vx - d * ex, -vy - d * ey, -vz - d * ez
        mn = math.sqrt(mx * mx + my * my + mz * mz)
        mx, my, mz = mx / mn, my / mn, mz / mn
        cx, cy, cz = ny * mz - nz * my, nz * mx - nx * mz, nx * my - ny * mx
        th = math.atan2(cx * ex + cy * ey + cz * ez, mx * nx + my * ny + mz * nz)
        # s = Rot(e, -th) (b - W)
        px, py, pz = bx - wx, by - wy, bz - wz
        c, sn = math.cos(-th), math.sin(-th)
        kx, ky, kz = ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px
        kp = (px * ex + py * ey + pz * ez) * (1.0 - c)
        s = np.array([px * c + kx * sn + kp * ex, py * c + ky * sn + kp * ey,
                      pz * c + kz * sn + kp * ez])
        h = float(s[0] * nx + s[1] * ny + s[2] * nz) - (self._g0n + r)
        return th, s, h

    def _dev_rail(self, s: np.ndarray, r: float) -> tuple[float, float] | None:
        """Deviation and rail that put palm_center + r n0 at ``s`` (zero-flexion frame)."""
        rho = math.hypot(self._dev_A, self._dev_B)
        phi = math.atan2(self._dev_B, self._dev_A)
        x = float(s @ self.b0) / rho
        if abs(x) > 1.0:
            return None
        best = None
        lo, hi = self.dev_lim
        for dev in (phi + math.acos(x), phi - math.acos(x)):
            dev = math.atan2(math.sin(dev), math.cos(dev))
            margin = min(dev - lo, hi - dev)
            if margin < 0:
                continue
            rail = self._rail_for(s, dev, r)
            if not (self.rail_lim[0] <= rail <= self.rail_lim[1]):
                continue
            if best is None or margin > best[0]:
                best = (margin, dev, rail)
        return None if best is None else (best[1], best[2])

    def _rail_for(self, s: np.ndarray, dev: float, r: float) -> float:
        if self.i_rail is None:
            return 0.0
        a = _rot1(self.u_d, dev, self.g0) + r * self.n0
        return float((s - a) @ self.e_r)

    def _intercept(self, flight: Flight, C: np.ndarray, r: float, t_c: float) -> _Intercept:
        t = np.linspace(max(0.0, t_c - 0.30), t_c + 0.15, _N_SEARCH)
        b = flight.position(t) - C
        v = flight.velocity(t)
        _, _, hgt = self._aligned(b, v, r)
        # first crossing of the palm plane (+ before, - after)
        cross = np.flatnonzero((hgt[:-1] > 0) & (hgt[1:] <= 0))
        if cross.size:
            k = int(cross[0])
            ta, tb, fa, fb = float(t[k]), float(t[k + 1]), float(hgt[k]), float(hgt[k + 1])
            # h is smooth (~ the ball's height above the palm plane): a bracketed
            # secant converges in 2-4 steps to 1e-8 m
            ti, (th, s_vec, _) = _bracketed_secant(
                lambda tm: self._aligned1(flight, C, tm, r), ta, tb, fa, fb)
            sol = self._dev_rail(s_vec, r)
            if sol is not None and self.flex_lim[0] <= th <= self.flex_lim[1]:
                return _Intercept(ti, th, sol[0], sol[1], 0.0, True, None)
        return self._intercept_position_only(flight, C, r, t)

    def _crossing(self, flight: Flight, C: np.ndarray, rho: float, ta: float, tb: float,
                  fa: float, fb: float) -> float:
        """Time in [ta, tb] at which the ball is ``rho`` from the flexion axis (secant)."""
        e = self.e_f

        def f(t: float) -> tuple[float]:
            w = flight.position(t) - C - self.W
            return (float(np.linalg.norm(w - (w @ e) * e)) - rho,)

        return _bracketed_secant(f, ta, tb, fa, fb)[0]

    def _intercept_position_only(self, flight: Flight, C: np.ndarray, r: float,
                                 t: np.ndarray) -> _Intercept:
        """No pose faces the ball exactly: put the palm point on the path with the
        deviation at each candidate value and pick the least misaligned reachable one."""
        b = flight.position(t) - C
        e = self.e_f
        w = b - self.W
        w_p = w - np.outer(w @ e, e)
        dist = np.linalg.norm(w_p, axis=1)
        lo, hi = self.dev_lim
        best: _Intercept | None = None
        closest = (np.inf, None)
        for dev in (lo, 0.5 * lo, 0.0, 0.5 * hi, hi):
            a = _rot1(self.u_d, dev, self.g0) + r * self.n0
            a_p = a - (a @ e) * e
            rho = float(np.linalg.norm(a_p))
            f = dist - rho
            cross = np.flatnonzero((f[:-1] > 0) & (f[1:] <= 0))
            k_near = int(np.argmin(np.abs(f)))
            if abs(f[k_near]) < closest[0]:
                closest = (float(abs(f[k_near])), float(t[k_near]))
            if not cross.size:
                continue
            k = int(cross[0])
            tk = self._crossing(flight, C, rho, float(t[k]), float(t[k + 1]), float(f[k]),
                                float(f[k + 1]))
            bk = flight.position(tk) - C
            vk = flight.velocity(tk)
            wk = bk - self.W
            wk_p = wk - (wk @ e) * e
            th = float(math.atan2(np.cross(a_p, wk_p) @ e, a_p @ wk_p))
            if not self.flex_lim[0] <= th <= self.flex_lim[1]:
                continue
            n = _rot1(e, th, self.n0)
            mis = float(math.acos(np.clip(-(vk @ n) / np.linalg.norm(vk), -1.0, 1.0)))
            rail = float((wk - _rot1(e, th, a)) @ self.e_r) if self.i_rail is not None else 0.0
            if not (self.rail_lim[0] <= rail <= self.rail_lim[1]):
                continue
            if mis > math.radians(MAX_MISALIGN_DEG):
                continue
            if best is None or mis < best.misalign:
                best = _Intercept(tk, th, dev, rail, mis, False, None)
        if best is not None:
            return best
        # out of reach: keep the open hand at its reference pose, meet the ball where
        # it passes closest
        tk = closest[1] if closest[1] is not None else float(t[len(t) // 2])
        return _Intercept(tk, 0.0, 0.0, 0.0, 0.0, False,
                          f"out of reach: no wrist/rail pose puts the palm on the ball's path "
                          f"facing it (closest {1000 * closest[0]:.0f} mm off the palm's circle)")

    # ------------------------------------------------------------ FK helpers
    def _frames(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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

    # ------------------------------------------------------------ plan
    def plan(self, flight: Flight, catch_point: np.ndarray, rate_hz: float = 100.0,
             t_info: float = 0.0, throw: dict[str, Any] | None = None,
             flight_time_s: float | None = None, fit: FitResult | None = None) -> CatchPlan:
        """Plan the catch of ``flight`` with the hand mounted at ``catch_point`` (catch
        frame). ``t_info``: when the flight is known (last observation); the hand moves
        from ``t_info + SIGNAL_S + PLAN_BUDGET_S``. No file is written."""
        t0 = time.perf_counter()
        h = self.hand
        C = np.asarray(catch_point, dtype=float)
        r = float(flight.ball.radius_m)
        mass = float(flight.ball.mass_kg)
        reasons: list[str] = []
        notes: list[str] = []
        closing = self.closing(r)
        if closing.reason:
            reasons.append(closing.reason)
        for f, gap in zip(h.fingers, closing.min_gap_m):
            if gap < 0:
                reasons.append(f"fingers in the way: the {f} tip passes {1000 * -gap:.1f} mm "
                               "inside the ball while the hand closes")

        # 1. intercept
        if flight_time_s is None:
            try:
                flight_time_s = float(flight.time_at_x(float(C[0])))
            except InfeasibleError:
                flight_time_s = None
        t_c = flight_time_s if flight_time_s is not None else self._closest_time(flight, C)
        ic = self._intercept(flight, C, r, t_c)
        if ic.reason:
            reasons.append(ic.reason)
        q_arm = self.q_zero.copy()
        q_arm[self.i_flex], q_arm[self.i_dev] = ic.theta, ic.dev
        if self.i_rail is not None:
            q_arm[self.i_rail] = ic.rail
        q_open = self._open_from(q_arm, closing.q_closed)
        ik_iter = 0
        if ic.reason is None:
            b_i = flight.position(ic.t) - C
            n_des = _rot1(self.e_f, ic.theta, self.n0)
            # the fingers are not masked (their hard coupling tasks would lose rank); the
            # palm does not depend on them and the posture/stay tasks hold them
            res = self.ik.solve_palm(b_i, n_des, q_open, q_open, offset_m=r, max_iter=5,
                                     tol_m=INTERCEPT_PLAN_TOL_M, tol_rad=0.02)
            ik_iter = res.iterations
            if res.iterations:
                q_open = self._open_from(res.q, closing.q_closed)
        # intercept time on the confirmed pose: closest approach to palm_center + r n
        P = self._palm_target(q_open, r)
        t_i = self._refine_time(flight, C, P, ic.t)
        q_closed = q_open.copy()
        q_closed[self.finger_idx] = closing.q_closed[self.finger_idx]
        v_i = flight.velocity(t_i)
        n_i = h.palm_pose(q_open)[:3, 2]
        misalign = math.degrees(math.acos(np.clip(-(v_i @ n_i) / np.linalg.norm(v_i), -1, 1)))

        # 2. timing
        t_react = max(0.0, t_info) + SIGNAL_S + PLAN_BUDGET_S
        T_m = phase_duration(q_open - self.q_rest, h.velocity, h.acceleration)
        ready = t_react + T_m
        T_c = closing.duration_s
        dt = 1.0 / rate_hz
        stop_t = gq.stop_time(v_i)
        if ready > t_i:
            reasons.append(f"too fast: the open pre-catch pose is reached at {ready:.3f} s, "
                           f"{1000 * (ready - t_i):.0f} ms after the ball (t = {t_i:.3f} s)")
        s_c = self._close_start(flight, C, q_open, closing, t_i, ready, stop_t, r)
        phases = [Phase(delta=q_open - self.q_rest, duration_s=T_m),
                  Phase(delta=q_closed - q_open, duration_s=T_c)]
        starts = np.array([t_react, s_c])

        # 3. rows
        n_rows = math.floor((t_i + HOLD_AFTER_S) * rate_hz + 1e-9) + 1
        t = np.arange(n_rows) * dt
        Q = h.apply_couplings(sample(phases, starts, t, self.q_rest))
        QM = h.motor_angles(Q)

        # 4. self-check on the rows
        self._rate = rate_hz
        err, clear, g_t, g_f, check_reasons = self._check_rows(flight, C, r, t, Q, t_i, s_c + T_c,
                                                               closing.reason is not None)
        reasons += check_reasons

        # 5. forces
        stop = hold = None
        q_i = _interp_row(t, Q, t_i)
        centre_i = self._palm_target(q_i, r)
        try:
            stop = gq.grasp_forces(h, q_i, centre_i, r, gq.stop_force(mass, v_i), case="stop",
                                   tip_tol_m=0.001, moment_balance=False)
        except InfeasibleError as e:
            reasons.append(f"{_kind(e)} (stopping the ball over {100 * gq.STOP_DISTANCE_M:g} "
                           f"cm): {e}")
        centre_c = self._palm_target(q_closed, r)
        try:
            hold = gq.grasp_forces(h, q_closed, centre_c, r, gq.hold_force(mass), case="hold",
                                   tip_tol_m=GRASP_TOL_M, moment_balance=True)
        except InfeasibleError as e:
            reasons.append(f"{_kind(e)} (holding the ball): {e}")

        T_world = self.mount.T_world_root(C)
        unc = None
        if fit is not None:
            unc = _uncertainty(fit, float(C[0] + centre_i[0]))
        plan = CatchPlan(
            feasible=not reasons, reasons=reasons, flight=flight, catch_point=C,
            T_world_root=T_world, base_hand=self.base_hand, rate_hz=float(rate_hz),
            throw=dict(throw or {}), launch_speed=flight.speed, flight_time_s=flight_time_s,
            intercept_t=float(t_i), intercept_point=flight.position(t_i),
            arrival_velocity=v_i, intercept_error_m=err, misalignment_deg=misalign,
            q_rest=self.q_rest, q_open=q_open, q_closed=q_closed, move_start_s=t_react,
            move_s=T_m, close_start_s=float(s_c), close_s=T_c, grasp_t=g_t, grasp_fingers=g_f,
            min_clearance_before_m=clear, stop=stop, hold=hold, t=t, q=Q, q_motor=QM,
            ik_iterations=ik_iter, t_info_s=float(t_info), uncertainty=unc, notes=notes)
        plan.planning_s = time.perf_counter() - t0
        return plan

    def _closest_time(self, flight: Flight, C: np.ndarray) -> float:
        t = np.linspace(0.0, 3.0, 601)
        d = np.linalg.norm(flight.position(t) - C, axis=1)
        return float(t[int(np.argmin(d))])

    def _palm_target(self, q: np.ndarray, r: float) -> np.ndarray:
        """palm_center + r n (reference frame)."""
        P = self.hand.palm_pose(q)
        return P[:3, 3] + r * P[:3, 2]

    def _refine_time(self, flight: Flight, C: np.ndarray, P: np.ndarray, t: float) -> float:
        for _ in range(3):
            b = flight.position(t) - C
            v = flight.velocity(t)
            step = float((P - b) @ v / (v @ v))
            t += step
            if abs(step) < 1e-9:
                break
        return float(t)

    def _close_start(self, flight: Flight, C: np.ndarray, q_open: np.ndarray,
                     closing: Closing, t_i: float, ready: float, stop_t: float,
                     r: float) -> float:
        """Start of the closing move: grasp when the ball has stopped in the palm, not
        before the open pose is reached, later if a fingertip would touch the ball
        before intercept_t."""
        if closing.u_grasp is None:
            return max(ready, t_i)
        T_c = closing.duration_s
        want = max(ready, t_i + stop_t - closing.u_grasp * T_c)
        if want >= t_i:
            return want
        # the ball can only meet a fingertip in the last stretch before the palm
        speed = float(np.linalg.norm(flight.velocity(t_i)))
        tt = np.arange(max(want, t_i - (closing.reach_m + r) / speed), t_i, 0.001)
        if tt.size == 0:
            return want
        Tinv = np.linalg.inv(self.hand.palm_pose(q_open))
        b_pc = (flight.position(tt) - C) @ Tinv[:3, :3].T + Tinv[:3, 3]
        # candidate starts, earliest first; fingertips from the closing table (the more
        # closed of the two neighbouring samples)
        cands = np.linspace(want, t_i, _N_CAND)
        n_tab = len(closing.u)
        U = np.clip((tt[None, :] - cands[:, None]) / closing.duration_s, 0.0, 1.0)
        k = np.minimum(np.ceil(U * (n_tab - 1)).astype(int), n_tab - 1)
        d = np.linalg.norm(closing.tips_pc[k] - b_pc[None, :, None, :], axis=-1)
        ok = ~np.any(d < r + TOUCH_CLEAR_M, axis=(1, 2))
        good = np.flatnonzero(ok)
        return float(cands[good[0]]) if good.size else float(t_i)

    def _check_rows(self, flight: Flight, C: np.ndarray, r: float, t: np.ndarray,
                    Q: np.ndarray, t_i: float, t_static: float,
                    grasp_known_bad: bool = False):
        """The independent check's catch criteria on the planned rows."""
        reasons = []
        h = self.hand
        qi = _interp_row(t, Q, t_i)
        P = self._palm_target(qi, r)
        err = float(np.linalg.norm(flight.position(t_i) - C - P))
        if err > INTERCEPT_TOL_M:
            reasons.append(f"the palm misses the ball by {1000 * err:.0f} mm at t = {t_i:.3f} s")
        # rows that matter: before the intercept those in which the ball is within
        # ``near_m`` of the palm target (no fingertip reaches farther); after it, rows until
        # the hand stops moving (``t_static``; later rows repeat the last), and the last row
        b_all = flight.position(t) - C
        pre = (t < t_i) & (np.linalg.norm(b_all - P, axis=1) < self.near_m + 2.0 * r)
        post = (t >= t_i) & (t <= t_static + 1.5 / self._rate)  # static afterwards
        post[-1] = t[-1] >= t_i
        idx = np.flatnonzero(pre | post)
        tips, palm = self._frames(Q[idx])
        tt = t[idx]
        before = tt < t_i
        clear = np.inf
        if before.any():
            b = b_all[idx][before]
            d = np.linalg.norm(tips[before] - b[:, None, :], axis=-1) - r
            clear = float(d.min())
            if clear < 0:
                k, f = np.unravel_index(int(np.argmin(d)), d.shape)
                reasons.append(f"fingers in the way: {h.fingers[f]} tip inside the ball at "
                               f"t = {tt[before][k]:.3f} s, before the intercept")
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
                reasons.append(f"grasp lost at t = {ta[lost]:.3f} s")
        elif not grasp_known_bad:
            k = int(np.argmax(ok)) if ok.any() else None
            when = (f"only at t = {ta[k]:.3f} s ({1000 * (ta[k] - t_i):.0f} ms after the "
                    "intercept)" if k is not None else "never")
            reasons.append(f"too slow to close: the grasp (thumb + {GRASP_MIN_TIPS - 1} "
                           f"fingertips within radius + {1000 * GRASP_TOL_M:g} mm) holds {when}"
                           f", limit {1000 * GRASP_WINDOW_S:g} ms")
        return err, clear, g_t, g_f, reasons


def _kind(e: InfeasibleError) -> str:
    """'torque' when a motor's capacity is what fails, else 'friction' (no force split lies
    inside the contacts' friction cones)."""
    return "torque" if "needs motor." in str(e) else "friction"


def _uncertainty(fit: FitResult, x_plane: float) -> dict[str, float] | None:
    try:
        t, _, cov, sig_t = predict_intercept(fit, x_plane)
    except PlannerError:
        return None
    return {"x_plane_m": x_plane, "t_s": t, "sigma_t_s": sig_t,
            "sigma_y_m": float(math.sqrt(max(cov[1, 1], 0.0))),
            "sigma_z_m": float(math.sqrt(max(cov[2, 2], 0.0)))}


# ====================================================================== API

_PLANNERS: dict[tuple, CatchPlanner] = {}


def get_planner(hand: HandModel | str = "default", mount: CatchMount | None = None) -> CatchPlanner:
    """The planner for ``hand`` (a HandModel, name or .toml path) and mount, built once."""
    source = hand if isinstance(hand, str) else None
    model = load_hand(hand) if isinstance(hand, str) else hand
    if not isinstance(model, HandModel):
        raise InputError(f"hand must be a hand name, a .toml path or a HandModel, got {hand!r}")
    if mount is None:
        mount = catch_mount(model, source)
    key = (model.urdf_sha256, model.name, mount.offset_m, mount.rpy_deg)
    pl = _PLANNERS.get(key)
    if pl is None:
        pl = _PLANNERS[key] = CatchPlanner(model, mount)
    return pl


def _finite(name: str, x: Any) -> float:
    """A finite float, or InputError naming ``name`` (shared with the flight module)."""
    return flight_finite(name, x)


MIN_DIST_M = 0.1  # launch point at least this far from the hand's nominal catch point
MAX_DIST_M = 100.0


def _bracketed_secant(f, ta: float, tb: float, fa: float, fb: float, iters: int = 12):
    """Root of a smooth function on the bracket [ta, tb] (fa > 0 >= fb): secant steps kept
    inside the shrinking bracket, bisection when a step leaves it. ``f(t)`` returns a
    tuple whose last item is the value; returns (t, f(t)) of the last iterate."""
    t0, f0, t1, f1 = ta, fa, tb, fb
    tm, out = 0.5 * (ta + tb), None
    for _ in range(iters):
        tm = t1 - f1 * (t1 - t0) / (f1 - f0) if f1 != f0 else 0.5 * (ta + tb)
        if not ta < tm < tb:
            tm = 0.5 * (ta + tb)
        out = f(tm)
        fm = out[-1]
        if fm > 0:
            ta = tm
        else:
            tb = tm
        t0, f0, t1, f1 = t1, f1, tm, fm
        if abs(fm) < 1e-8 or tb - ta < 1e-9:
            break
    return tm, out


def validate_throw(angle_deg: Any, dist_m: Any, height_m: Any, rate_hz: Any
                   ) -> tuple[float, float, float, float]:
    """InputError unless 0 < angle < 90, MIN_DIST_M <= dist <= MAX_DIST_M,
    |height| < 10 m, all finite,
    1 <= rate <= 10000 Hz. (A throw from closer than the hand's own size is no throw: a
    tiny distance would ask for flights of microseconds.)"""
    a, d, hgt = check_throw(angle_deg, dist_m, height_m, prefix="--")
    if not MIN_DIST_M <= d <= MAX_DIST_M:
        raise InputError(f"--dist must be between {MIN_DIST_M:g} and {MAX_DIST_M:g} m, got {d:g}")
    rate = _finite("--rate", rate_hz)
    if not 1.0 <= rate <= 10000.0:
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate:g}")
    return a, d, hgt, rate


def plan_throw(angle_deg: float, dist_m: float, height_m: float = 0.0,
               hand: HandModel | str = "default", ball: Ball | str = "tennis",
               drag: bool = False, observations: Any = None, rate_hz: float = 100.0,
               planner: CatchPlanner | None = None) -> CatchPlan:
    """Validate, predict (or fit) the flight and plan; no file is written.

    ``observations``: None, a CSV path (``t,x,y,z``) or a pair (ts, ps)."""
    a, d, hgt, rate = validate_throw(angle_deg, dist_m, height_m, rate_hz)
    b = get_ball(ball)
    pl = planner or get_planner(hand)
    return _plan_validated(pl, a, d, hgt, b, bool(drag), _load_obs(observations, drag), rate)


def _load_obs(observations: Any, drag: bool):
    if observations is None:
        return None
    if isinstance(observations, (str, Path)):
        return load_observations_csv(observations, min_rows=6 if drag else 3)
    try:
        ts, ps = observations
    except (TypeError, ValueError):
        raise InputError("observations must be a CSV path or a pair (ts, ps)") from None
    return np.asarray(ts, dtype=float), np.asarray(ps, dtype=float)


def _plan_validated(pl: CatchPlanner, a: float, d: float, hgt: float, b: Ball, drag: bool,
                    obs, rate: float) -> CatchPlan:
    t_start = time.perf_counter()
    C = np.array([d, 0.0, hgt])
    nominal = predict_throw(a, d, hgt, b, drag)  # also validates the throw itself
    fit = None
    t_info = 0.0
    flight = nominal
    if obs is not None:
        ts, ps = obs
        fit = fit_observations(ts, ps, b, b.drag_per_m if drag else 0.0)
        flight = fit.flight
        t_info = float(ts[-1])
    try:
        t_f = float(flight.time_at_x(d))
    except InfeasibleError:
        t_f = None
    throw = {"angle_deg": a, "dist_m": d, "height_m": hgt, "ball": b.name, "drag": drag,
             "observations": None if fit is None else fit.n_observations}
    plan = pl.plan(flight, C, rate, t_info=t_info, throw=throw, flight_time_s=t_f, fit=fit)
    if fit is not None:
        plan.notes.append(f"fitted to {fit.n_observations} observations "
                          f"(rms residual {1000 * fit.residual_rms:.1f} mm)")
    plan.planning_s = time.perf_counter() - t_start
    return plan


def write_plan(plan: CatchPlan, out_path: str) -> int:
    """Write the plan's rows (hand-trajectory v1); returns the number of rows."""
    hand = plan.base_hand
    writer = TrajectoryWriter(out_path, plan.metadata(), hand.joint_names, hand.motor_names)
    try:
        writer.write_rows(plan.t, plan.q, plan.q_motor)
    except BaseException as e:
        writer.abort(discard=isinstance(e, InputError))
        raise
    writer.close()
    return writer.rows


def plan_catch(angle_deg: float, dist_m: float, height_m: float, hand: HandModel | str,
               out_path: str, ball: Ball | str = "tennis", drag: bool = False,
               observations: Any = None, rate_hz: float = 100.0,
               strict: bool = False) -> CatchResult:
    """Plan the catch of a throw at ``angle_deg`` through (dist, 0, height) and write it.

    Every argument is checked before any file is created (InputError). The plan is
    written even when the catch is infeasible (``result.reasons`` says why); with
    ``strict`` an infeasible plan then raises InfeasibleError (the file stays)."""
    a, d, hgt, rate = validate_throw(angle_deg, dist_m, height_m, rate_hz)
    b = get_ball(ball)
    if not isinstance(out_path, str) or not out_path:
        raise InputError("an output path (or '-') is needed")
    if out_path != "-":
        parent = Path(out_path).parent
        if not parent.is_dir():
            raise InputError(f"cannot write {out_path}: no such directory {parent}")
    obs = _load_obs(observations, drag)
    t0 = time.perf_counter()
    pl = get_planner(hand)
    pl.closing(b.radius_m)
    setup = time.perf_counter() - t0
    plan = _plan_validated(pl, a, d, hgt, b, bool(drag), obs, rate)
    t1 = time.perf_counter()
    rows = write_plan(plan, out_path)
    res = CatchResult(plan, out_path, rows, plan.planning_s, time.perf_counter() - t1, setup)
    if strict and not plan.feasible:
        raise InfeasibleError("; ".join(plan.reasons), problem=res)
    return res

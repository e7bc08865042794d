"""Catch: throw -> intercept -> open pre-catch pose -> closing -> trajectory file.

The package, stage by stage: ``flight`` (the ball), ``mount`` (where the hand sits),
``arm`` (the joints a catch moves, and its fixed poses), ``intercept`` (where the palm
meets the ball), ``closing`` (how the fingers close on it), ``grasp`` (the contact
forces that stop and hold it), ``rowcheck`` (the self-check on the rows),
``planner`` (``CatchPlanner``: one throw, those stages in order), ``results`` (what a
plan is) and this module, the API (``plan_catch``, ``plan_throw``, ``get_planner``).

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

1. Intercept (``intercept.find_intercept``): on the ball's path near C, the time t at which
   the palm can hold ``palm_center + radius * n = ball(t)`` with n (the palm's
   +z) against the ball's velocity: flexion from the velocity's direction,
   then t from the ball's height above the palm plane (a root in t), then
   deviation and rail in closed form. When no pose faces the ball exactly
   (deviation or flexion out of range), the palm's position alone is solved
   (deviation clamped) and the misalignment reported; when even that fails the
   throw is out of reach. The pose is then confirmed with placo
   (``HandIK.solve_palm``, warm-started: usually zero or one iteration) and the
   intercept time refined on the confirmed pose.
2. Closing (``closing.make_closing``, once per ball radius, cached): a closed hand whose
   fingertips sit ``TIP_GAP_M`` outside the ball's surface, each at 40 deg
   above the ball's equator on its own finger's side (IK, wrist and rail
   locked; fingers that cannot reach are pulled to the nearest point of the
   sphere), every finger's body (the replay's capsules and pad spheres)
   ``BODY_CLEAR_M`` outside it (aimed higher, up to 70 deg, then opened; the
   fingertips' closing is the fallback when that grasps too late). The grasp condition of the independent check (thumb plus two more
   fingertips within radius + 10 mm of the ball centre, here planned with 2 mm
   to spare) is evaluated along the min-jerk closing move in the palm frame;
   the fraction of the move after which it holds for good is ``u_grasp``.
   Open = the closed pose's abduction joints with every flexion joint at 0
   (extended), so the closing move is pure flexion.
3. Timing and the soft catch (``stopping.plan_stop``): the hand starts from ``rest`` at
   t = 0 and begins to move after ``SIGNAL_S`` (25 ms, seed) + ``PLAN_BUDGET_S`` (5 ms,
   the planning latency budget) -- later with observations: after the last observation
   -- to the pre-catch pose (min-jerk within speed and acceleration limits). From there
   the arm draws back along the ball's path so that the palm meets it moving (the arm's
   speeds by a QP, the recoil under the ball's push, the palm's tilt) and brings it to
   rest within every motor's capacity (``planner.catch.plan.stopping``). The closing move
   (seed: 150-300 ms) is placed so that the grasp condition is met when the pad has
   stopped the ball on the palm, then delayed if a fingertip would come within
   ``TOUCH_CLEAR_M`` of the still-arriving ball; it must complete the grasp within
   ``GRASP_WINDOW_S`` (150 ms) of the intercept. Once the grasp is made the wrist turns the
   closed hand palm up, its downhill 5 deg into the fingers (``holdturn.hold_turn``: a ball
   rolling on the palm rolls into the fingers, not off the open wrist side) -- or, where
   the ball would roll off the wrist side before that turn has levelled the palm
   (``roll``), the turn is already under way when the ball lands (``turnahead``). Rows at
   ``rate_hz`` until ``intercept_t + HOLD_AFTER_S`` (and the arm at rest).
4. Forces: stopping the ball judged on the rows by the check's own rule
   (``planner.check.ball.ball_loads``: the pad, the ball riding the palm, the arm's
   inertia, the friction cone, every motor's headroom), holding it in the closed hand by
   the grasp QP (friction cones, every motor within its capacity: its peak torque, or its
   tendon's design force at the spool: ``planner.hand.tendon``).
5. Self-check on the rows (same criteria as the independent check): the ball
   within ``INTERCEPT_TOL_M`` of ``palm_center + radius * n`` at intercept_t
   (joints interpolated), no fingertip inside the ball before it, the grasp
   within the window and held to the end.

Infeasible throws (out of reach, too soon, too fast to stop, fingers in the way, grasp,
friction, torque) are planned as far as they go; ``CatchPlan.reasons`` says why, each with
its ``CatchReason`` kind.

Known limits of the shipped hands (reported, not hidden): the default hand's
thumb cannot come within radius + 10 mm of a ball held on the palm (its CMC
sits 3 cm proud of the palm; with CMC flexion at 90 deg and IP at 80 deg, both
at their limits, the tip stays ~17 mm outside a tennis ball), so every catch
with it fails the grasp criterion; a CMC flexion range of 110 deg (or the CMC
1 cm closer to the palm) would reach. The mk5 hand's true-size fingers do not
reach a ball on its 1.5x palm at all. The soft catch stops balls of up to ~6-7 m/s at
the palm within the wrist flexion motor's 2 N m peak (``docs/history/soft-catch.md``).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from planner.catch.flight.observe import fit_observations, load_observations_csv
from planner.catch.flight.path import (
    MAX_HEIGHT_M,
    Ball,
    check_throw,
    get_ball,
    predict_throw,
)
from planner.catch.flight.path import finite_float as flight_finite
from planner.catch.plan.arm import REST_CURL
from planner.catch.plan.closing import GRASP_MARGIN_M, TIP_ELEVATION_DEG, TIP_GAP_M, TOUCH_CLEAR_M
from planner.catch.plan.intercept import MAX_MISALIGN_DEG
from planner.catch.plan.mount import (
    DESIGN_DESCENT_DEG,
    DESIGN_DEV_DEG,
    CatchMount,
    catch_mount,
    default_mount,
    mount_from_file,
)
from planner.catch.plan.planner import HOLD_AFTER_S, PLAN_BUDGET_S, SIGNAL_S, CatchPlanner
from planner.catch.plan.reasons import reasons_text
from planner.catch.plan.results import CatchPlan, CatchResult, Closing, ThrowInfo
from planner.check.criteria import (
    GRASP_MIN_TIPS,
    GRASP_TOL_M,
    GRASP_WINDOW_S,
    INTERCEPT_TOL_M,
)
from planner.errors import InfeasibleError, InputError
from planner.hand.model import HandModel, load_hand
from planner.trajfile import TrajectoryWriter

ACTUATION_SEED_S = (0.150, 0.300)  # seed: open-to-closed actuation time
# (GRASP_WINDOW_S, GRASP_TOL_M, GRASP_MIN_TIPS, INTERCEPT_TOL_M: the check's criteria,
# one definition, imported above; the planner aims inside them)

__all__ = [
    "ACTUATION_SEED_S", "DESIGN_DESCENT_DEG", "DESIGN_DEV_DEG", "GRASP_MARGIN_M",
    "GRASP_MIN_TIPS", "GRASP_TOL_M", "GRASP_WINDOW_S", "HOLD_AFTER_S", "INTERCEPT_TOL_M",
    "MAX_MISALIGN_DEG", "PLAN_BUDGET_S", "REST_CURL", "SIGNAL_S", "TIP_ELEVATION_DEG",
    "TIP_GAP_M", "TOUCH_CLEAR_M", "CatchMount", "CatchPlan", "CatchPlanner", "CatchResult",
    "Closing", "catch_mount", "default_mount", "get_planner", "mount_from_file", "plan_catch",
    "plan_throw", "validate_live", "validate_throw", "write_plan",
]

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


def finite_float(name: str, x: Any) -> float:
    """A finite float, or InputError naming ``name`` (shared with the flight module)."""
    return flight_finite(name, x)


MIN_DIST_M = 0.1  # launch point at least this far from the hand's nominal catch point
MAX_DIST_M = 100.0



def validate_throw(angle_deg: Any, dist_m: Any, height_m: Any, rate_hz: Any
                   ) -> tuple[float, float, float, float]:
    """InputError unless 0 < angle < 90, MIN_DIST_M <= dist <= MAX_DIST_M,
    |height| < 10 m, all finite,
    1 <= rate <= 10000 Hz. (A throw from closer than the hand's own size is no throw: a
    tiny distance would ask for flights of microseconds.)"""
    a, d, hgt = check_throw(angle_deg, dist_m, height_m, prefix="--")
    if not MIN_DIST_M <= d <= MAX_DIST_M:
        raise InputError(f"--dist must be between {MIN_DIST_M:g} and {MAX_DIST_M:g} m, got {d:g}")
    rate = finite_float("--rate", rate_hz)
    if not 1.0 <= rate <= 10000.0:
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate:g}")
    return a, d, hgt, rate


def validate_live(dist_m: Any, height_m: Any, rate_hz: Any) -> tuple[float, float, float]:
    """``validate_throw``'s rules for a live catch, whose throw comes from the observations:
    where the hand is (dist, height) and the rate."""
    d = finite_float("--dist", dist_m)
    if not MIN_DIST_M <= d <= MAX_DIST_M:
        raise InputError(f"--dist must be between {MIN_DIST_M:g} and {MAX_DIST_M:g} m, got {d:g}")
    hgt = finite_float("--height", height_m)
    if not abs(hgt) < MAX_HEIGHT_M:
        raise InputError(f"--height must be between -{MAX_HEIGHT_M:g} and {MAX_HEIGHT_M:g} m "
                         f"(exclusive), got {hgt:g}")
    rate = finite_float("--rate", rate_hz)
    if not 1.0 <= rate <= 10000.0:
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate:g}")
    return d, hgt, rate


def plan_throw(angle_deg: float, dist_m: float, height_m: float = 0.0,
               hand: HandModel | str = "default", ball: Ball | str = "tennis",
               drag: bool = False, observations: Any = None, rate_hz: float = 100.0,
               planner: CatchPlanner | None = None, soft: bool = True) -> CatchPlan:
    """Validate, predict (or fit) the flight and plan; no file is written.

    ``observations``: None, a CSV path (``t,x,y,z``) or a pair (ts, ps); ``soft`` False:
    the palm waits for the ball at rest (the catch before issue 15, for comparison).
    ``angle_deg`` None with observations: the throw is the observations' alone."""
    a, d, hgt, rate = _validate(angle_deg, dist_m, height_m, rate_hz, observations)
    b = get_ball(ball)
    pl = planner or get_planner(hand)
    return _plan_validated(pl, a, d, hgt, b, bool(drag), _load_obs(observations, drag), rate,
                           soft)


def _validate(angle_deg: Any, dist_m: Any, height_m: Any, rate_hz: Any, observations: Any
              ) -> tuple[float | None, float, float, float]:
    """``validate_throw``; without an angle (None) when the observations give the throw."""
    if angle_deg is None:
        if observations is None:
            raise InputError("a catch needs --angle or --observations (the throw)")
        d, hgt, rate = validate_live(dist_m, height_m, rate_hz)
        return None, d, hgt, rate
    return validate_throw(angle_deg, dist_m, height_m, rate_hz)


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


def _plan_validated(pl: CatchPlanner, a: float | None, d: float, hgt: float, b: Ball,
                    drag: bool, obs, rate: float, soft: bool = True) -> CatchPlan:
    """The plan of a validated throw: predicted from ``a``, or fitted to ``obs`` (the
    throw's angle then the fit's; ``a`` only said, not planned with)."""
    t_start = time.perf_counter()
    C = np.array([d, 0.0, hgt])
    if a is not None:
        flight = predict_throw(a, d, hgt, b, drag)  # also validates the throw itself
    fit = None
    t_info = 0.0
    asked = a
    if obs is not None:
        ts, ps = obs
        fit = fit_observations(ts, ps, b, b.drag_per_m if drag else 0.0)
        flight = fit.flight
        t_info = float(ts[-1])
        v = flight.v0
        a = math.degrees(math.atan2(float(v[2]), math.hypot(float(v[0]), float(v[1]))))
    try:
        t_f = float(flight.time_at_x(d))
    except InfeasibleError:
        t_f = None
    throw = ThrowInfo(a if asked is None else asked, d, hgt, b.name, drag,
                      None if fit is None else fit.n_observations)
    plan = pl.plan(flight, C, rate, t_info=t_info, throw=throw, flight_time_s=t_f, fit=fit,
                   soft=soft)
    notes = plan.notes
    if fit is not None:
        notes += ((f"fitted to {fit.n_observations} observations "
                   f"(rms residual {1000 * fit.residual_rms:.1f} mm)"),)
        if asked is None or abs(a - asked) > 0.05:
            notes += ((f"the throw from the observations: {a:.1f} deg"
                       + ("" if asked is None else f" (--angle {asked:g} said, not used)")),)
    return replace(plan, notes=notes, planning_s=time.perf_counter() - t_start)


def write_plan(plan: CatchPlan, out_path: str) -> int:
    """Write the plan's rows (hand-trajectory version 2: the end marker says ``"catch":
    "held"`` or ``"infeasible"`` with its reason); returns the number of rows."""
    return _written(plan, out_path).rows


def _written(plan: CatchPlan, out_path: str | None) -> TrajectoryWriter:
    """The closed writer of the plan's file (``out_path`` None: its text in memory)."""
    hand = plan.base_hand
    writer = TrajectoryWriter(out_path, plan.metadata(), hand)
    try:
        writer.write_rows(plan.rows.t, plan.rows.q, plan.rows.q_motor)
    except BaseException as e:
        writer.abort(discard=isinstance(e, InputError))
        raise
    writer.close(plan.end_claims())
    return writer


def plan_catch(angle_deg: float, dist_m: float, height_m: float, hand: HandModel | str,
               out_path: str | None = None, ball: Ball | str = "tennis", drag: bool = False,
               observations: Any = None, rate_hz: float = 100.0,
               strict: bool = False) -> CatchResult:
    """Plan the catch of a throw at ``angle_deg`` through (dist, 0, height) and write it
    to ``out_path`` ('-': stdout; None: kept in memory, ``CatchResult.text``, as
    ``plan_song`` does).

    Every argument is checked before any file is created (InputError). The plan is
    written even when the catch is infeasible (``result.reasons`` says why); with
    ``strict`` an infeasible plan then raises InfeasibleError (the file stays)."""
    a, d, hgt, rate = _validate(angle_deg, dist_m, height_m, rate_hz, observations)
    b = get_ball(ball)
    if out_path is not None and (not isinstance(out_path, str) or not out_path):
        raise InputError("an output path (or '-', or None: in memory) is needed")
    if out_path is not None and out_path != "-":
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
    writer = _written(plan, out_path)
    res = CatchResult(plan, out_path, writer.rows, plan.planning_s, time.perf_counter() - t1,
                      setup, writer.text)
    if strict and not plan.feasible:
        raise InfeasibleError(reasons_text(plan.reasons), problem=res)
    return res

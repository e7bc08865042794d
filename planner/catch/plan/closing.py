"""How the hand closes on a ball: the closing move per ball size (fingertip targets on the
ball, IK with the arm locked, the grasp condition along the move) and when it starts
for a throw (grasp once the ball has stopped, no fingertip touching it before)."""

from __future__ import annotations

import math

import numpy as np

from planner.catch.flight.path import Flight
from planner.catch.plan.arm import CatchJoints, open_from, zero_pose
from planner.catch.plan.geometry import unit
from planner.catch.plan.intercept import Wrist
from planner.catch.plan.results import Closing
from planner.check.criteria import GRASP_MIN_TIPS, GRASP_TOL_M
from planner.hand.model import HandModel
from planner.ik import HandIK, PressTarget
from planner.play.fingerbody import FingerBodies
from planner.trajectory import Phase, min_jerk, phase_duration, sample

GRASP_MARGIN_M = 0.002  # planned with this much to spare
PALM_KNOT_S = 0.010  # the moving palm's pose computed this often before the intercept and
# interpolated between (10 us a pose): measured against every instant's own pose, the ball
# in the palm's frame within 0.41 mm (median 0.28 mm) over the 68 closing starts of
# bench_live's 20 throws at 100 Hz / 5 mm, within TOUCH_CLEAR_M
TOUCH_CLEAR_M = 0.002  # before intercept_t fingertips stay this far outside the ball
TIP_GAP_M = 0.003  # closed fingertips (pad points): this far outside the ball's surface
BODY_CLEAR_M = 0.0015  # closed fingers' bodies (the physics replay's capsules and pad spheres,
# ``planner.play.fingerbody``): at least this far outside it -- the ball lies 1-2 mm off its
# plan when the fingers close (replay, 40 deg / 2.0 m); a body inside it is a servo pressing
# a rigid ball (the middle and ring pads were 3.4-3.6 mm inside: ring MCP 0.49 of 0.40 N m)
TIP_ELEVATION_DEG = 40.0  # closed fingertips: above the ball's equator (palm = south pole)
TIP_ELEVATION_MAX_DEG = 70.0  # ... raised up to this for a finger whose body is in the ball
ELEVATION_STEP_DEG = 10.0  # ... in these steps
_ELEVATION_TRIES = 4  # 40, 50, 60, 70 deg
_N_CLOSE = 201  # samples of the closing move (palm frame table)
N_CAND = 25  # candidate starts of the closing move
_CAND_CHUNK = 4  # ... judged this many at a time, earliest first (the first clear one is
# among the first four in 93 % of a live catch's re-plans: bench_live throws, 100 Hz)
_CAND_STEPS = np.arange(N_CAND, dtype=float)  # the candidates' steps from the earliest


def make_closing(hand: HandModel, ik: HandIK, joints: CatchJoints, wrist: Wrist,
                 r: float, bodies: bool = True) -> Closing:
    """The closing move for a ball of radius ``r`` on the palm (``planner.catch.plan.api``,
    step 2): the closed pose (``closed_pose``) and the move to it (``closing_from``)."""
    return closing_from(hand, joints, wrist, r, closed_pose(hand, ik, joints, wrist, r, bodies))


def closed_pose(hand: HandModel, ik: HandIK, joints: CatchJoints, wrist: Wrist,
                r: float, bodies: bool = True) -> np.ndarray:
    """The closed hand on a ball of radius ``r`` on the palm: fingertips ``TIP_GAP_M``
    outside the ball, each ``TIP_ELEVATION_DEG`` above its equator on its finger's side (IK,
    the arm locked), the arm's joints at the zero pose. ``bodies``: the fingers' bodies,
    too, kept ``BODY_CLEAR_M`` outside the ball (False: the fingertips alone, the closing
    before the bodies were judged; the planner's fallback when the later grasp is too
    late). (``planner.catch.plan.closingtable`` ships it per hand and ball.)"""
    h = hand
    q0 = zero_pose(h)
    centre = wrist.pc0 + r * wrist.n0
    # each fingertip TIP_ELEVATION_DEG above the ball's equator; a finger whose body is
    # then inside the ball (its pad sphere curled into it) higher, in steps, up to
    # TIP_ELEVATION_MAX_DEG, before its flexion is opened (``_bodies_clear``)
    el_deg = np.full(len(h.fingers), TIP_ELEVATION_DEG)
    fb = FingerBodies(h)
    for _ in range(_ELEVATION_TRIES if bodies else 1):
        q = _tips_on_ball(h, ik, joints, q0, centre, r, wrist, el_deg)
        low = (body_gaps_m(h, q, centre, r + BODY_CLEAR_M, fb) < 0.0) & \
            (el_deg < TIP_ELEVATION_MAX_DEG - 1e-9)
        if not bodies or not low.any():
            break
        el_deg[low] += ELEVATION_STEP_DEG
    q = _close_one_dof(h, q, centre, r + TIP_GAP_M)
    if bodies:
        q = _bodies_clear(h, set(joints.flexion_idx), q0, q, centre, r + BODY_CLEAR_M)
    q_closed = q.copy()
    q_closed[list(joints.arm)] = q0[list(joints.arm)]
    return q_closed


def closing_from(hand: HandModel, joints: CatchJoints, wrist: Wrist, r: float,
                 q_closed: np.ndarray) -> Closing:
    """The closing move to the closed pose ``q_closed`` (``closed_pose``) for a ball of
    radius ``r``: the grasp condition along the min-jerk move in the palm frame, the
    fingers' bodies along it."""
    h = hand
    q0 = zero_pose(h)
    centre = wrist.pc0 + r * wrist.n0
    T_pc = h.palm_pose(q0)
    fb = FingerBodies(h)
    q_open = open_from(h, joints, q0, q_closed)
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
    bodies = _body_table(h, fb, Q, Tinv)
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
    T_c = phase_duration(q_closed - q_open, h.velocity, h.acceleration, j_max=h.jerk)
    return Closing(r, q_closed, T_c, u_g, dist, fingers, u, tips_pc, reason,
                   float(d_tab.max()), (d_tab - r).min(axis=0), *bodies)


def _body_table(h: HandModel, fb: FingerBodies, Q: np.ndarray, Tinv: np.ndarray):
    """The fingers' bodies along the closing move ``Q`` in the palm frame (``Tinv``: world
    -> palm), shape by shape (a pad sphere, a segment's capsule): points (K, G, P, 3), a
    shape with fewer repeating its first, their radii (G, P), each shape's bounding sphere
    (centres (K, G, 3), radii (K, G)). Every configuration at once
    (``FingerBodies.points_many``)."""
    shapes = [(f, a, n) for f in h.fingers
              for a, n in zip(np.cumsum((0,) + fb.shapes[f].n_points[:-1]),
                              fb.shapes[f].n_points)]
    G, P = len(shapes), max(n for _, _, n in shapes)
    pts = np.empty((len(Q), G, P, 3))
    rad = np.empty((G, P))
    world = {f: fb.points_many(Q, f) for f in h.fingers}
    radii = {f: np.repeat(fb.shapes[f].radius_m, fb.shapes[f].n_points) for f in h.fingers}
    for g, (f, a, n) in enumerate(shapes):
        p = world[f][:, a:a + n].reshape(-1, 3) @ Tinv[:3, :3].T + Tinv[:3, 3]
        pts[:, g, :n] = p.reshape(len(Q), n, 3)
        pts[:, g, n:] = pts[:, g, :1]
        rad[g, :n], rad[g, n:] = radii[f][a:a + n], radii[f][a]
    centre = pts.mean(axis=2)
    bound = (np.linalg.norm(pts - centre[:, :, None, :], axis=-1) + rad[None]).max(axis=2)
    return pts, rad, centre, bound


def _tips_on_ball(h: HandModel, ik: HandIK, joints: CatchJoints, q0: np.ndarray,
                  centre: np.ndarray, r: float, wrist: Wrist, el_deg: np.ndarray) -> np.ndarray:
    """The IK (the arm locked) of the fingertips ``TIP_GAP_M`` outside the ball, each
    ``el_deg`` above its equator on the side of its finger's base; a fingertip that cannot
    reach its target: the nearest point of that sphere."""
    targets = []
    for f, el in zip(h.fingers, np.radians(el_deg)):
        base = h.frame_pose(q0, h.spec.joints_of(f)[0])[:3, 3]
        d = base - centre
        d = d - (d @ wrist.n0) * wrist.n0
        d = unit(d) if np.linalg.norm(d) > 1e-9 else wrist.b0
        targets.append(centre + (r + TIP_GAP_M) * (math.cos(el) * d + math.sin(el) * wrist.n0))
    q_init = q0.copy()
    for i in joints.flexion_idx:
        q_init[i] = 0.5 * (h.lower[i] + h.upper[i])
    q_init = h.apply_couplings(np.clip(q_init, h.lower, h.upper))
    for n in joints.locked:
        ik.solver.mask_dof(n)
    try:
        res = ik.solve([PressTarget(f, 0, tuple(p), (p[1], p[1]))
                        for f, p in zip(h.fingers, targets)], q_init, q_init, hover=(),
                       max_iter=150)
        q = res.q
        for _ in range(2):
            tips = h.tip_positions(q)
            tg = [centre + (r + TIP_GAP_M) * unit(tp - centre) for tp in tips]
            res = ik.solve([PressTarget(f, 0, tuple(p), (p[1], p[1]))
                            for f, p in zip(h.fingers, tg)], q, q, hover=(), max_iter=80)
            q = res.q
    finally:
        for n in joints.locked:
            ik.solver.unmask_dof(n)
    return q


def _close_one_dof(hand: HandModel, q: np.ndarray, centre: np.ndarray, reach_m: float
                   ) -> np.ndarray:
    """A finger of one degree of freedom closes along its one arc, which the IK's point
    targets can only approach: its joint is set where its tip, flexing from open, first
    comes within ``reach_m`` of the ball's centre, or where it comes nearest."""
    q = q.copy()
    for k, f in enumerate(hand.fingers):
        own = hand.own_independent(f)
        if len(own) != 1:
            continue
        j = own[0]
        s = np.linspace(hand.lower[j], hand.upper[j], _N_CLOSE)
        Q = np.repeat(q[None, :], len(s), axis=0)
        Q[:, j] = s
        Q = hand.apply_couplings(Q)
        d = np.array([np.linalg.norm(hand.tip_position(qs, k) - centre) for qs in Q])
        hit = np.flatnonzero(d <= reach_m)
        q[j] = s[hit[0]] if hit.size else s[int(np.argmin(d))]
    return hand.apply_couplings(q)


def body_gaps_m(hand: HandModel, q: np.ndarray, centre: np.ndarray, r: float,
                bodies: FingerBodies | None = None) -> np.ndarray:
    """Each finger's body (segments' capsules, pad sphere) at ``q``: its smallest distance
    to the surface of the ball of radius ``r`` at ``centre`` (m, (fingers,); < 0 inside)."""
    fb = bodies if bodies is not None else FingerBodies(hand)
    out = np.empty(len(hand.fingers))
    for k, f in enumerate(hand.fingers):
        p, rad = fb.points(q, f, update=k == 0)
        out[k] = float((np.linalg.norm(p - centre, axis=1) - rad).min()) - r
    return out


_CLEAR_BISECT = 20  # bisection steps of a finger's opening (2^-20 of its travel)


def closed_pose_constants() -> tuple[float, ...]:
    """The constants ``closed_pose`` reads (the shipped poses' parameters,
    ``closingtable.params``)."""
    return (TIP_GAP_M, BODY_CLEAR_M, TIP_ELEVATION_DEG, TIP_ELEVATION_MAX_DEG,
            ELEVATION_STEP_DEG, _ELEVATION_TRIES, _N_CLOSE, _CLEAR_BISECT)


def _bodies_clear(hand: HandModel, flexion: set[int], q_from: np.ndarray, q: np.ndarray,
                  centre: np.ndarray, reach_m: float) -> np.ndarray:
    """The closed pose with every finger's body at least ``reach_m`` from the ball's
    centre: the IK's targets are the pad points, and a curled distal segment's pad sphere
    (or a segment) can reach into the ball where its pad point is outside it (default hand:
    the middle and ring pads 3.4-3.6 mm inside a tennis ball, the servos pressing a rigid
    ball); such a finger's own joints are opened towards ``q_from`` (straight, clear) by
    bisection to the most closed pose that is clear."""
    fb = FingerBodies(hand)
    q = q.copy()
    gaps = body_gaps_m(hand, q, centre, reach_m, fb)
    for k, f in enumerate(hand.fingers):
        if gaps[k] >= 0.0:
            continue
        idx = [j for j in hand.own_independent(f) if j in flexion]
        if not idx:
            continue
        lo_s, hi_s = 0.0, 1.0  # share of the closing from q_from kept: lo clear, hi not
        for _ in range(_CLEAR_BISECT):
            mid = 0.5 * (lo_s + hi_s)
            qm = q.copy()
            qm[idx] = q_from[idx] + mid * (q[idx] - q_from[idx])
            qm = hand.apply_couplings(qm)
            if body_gaps_m(hand, qm, centre, reach_m, fb)[k] >= 0.0:
                lo_s = mid
            else:
                hi_s = mid
        q[idx] = q_from[idx] + lo_s * (q[idx] - q_from[idx])
        q = hand.apply_couplings(q)
    return q


def earliest_close_start(closing: Closing, t_i: float, ready: float, stop_t: float) -> float:
    """The earliest start ``close_start`` can return (its first candidate): the grasp when
    the ball has stopped, not before ``ready`` (and not before ``t_i`` for a closing that
    never grasps). Cheap: no geometry."""
    if closing.u_grasp is None:
        return max(ready, t_i)
    return max(ready, t_i + stop_t - closing.u_grasp * closing.duration_s)


def closing_offsets(closing: Closing, finger_idx: np.ndarray, q_open: np.ndarray,
                    t_s: np.ndarray, t_i: float, stop_t: float) -> np.ndarray:
    """The fingers' offsets from ``q_open`` at times ``t_s`` (rows, one per time) of the
    closing started at ``earliest_close_start`` (the hand ready before it: the rows' own
    start when no fingertip would touch the ball first; a later one leaves them more open)
    for a ball meeting the palm at ``t_i`` and stopped by its pad in ``stop_t``."""
    delta = np.zeros(len(q_open))
    delta[finger_idx] = closing.q_closed[finger_idx] - q_open[finger_idx]
    s_c = earliest_close_start(closing, t_i, -math.inf, stop_t)
    return sample([Phase(delta, closing.duration_s)], np.array([s_c]), t_s,
                  np.zeros(len(q_open)))


def close_start(hand: HandModel, flight: Flight, C: np.ndarray, q_open: np.ndarray,
                closing: Closing, t_i: float, ready: float, stop_t: float, r: float,
                stop=None) -> float:
    """Start of the closing move: grasp when the ball has stopped in the palm, not
    before the open pose is reached, later if a fingertip would touch the ball
    before intercept_t. ``stop``: the arm's stopping motion (``stopping.SoftStop``) the
    palm makes while the ball comes (None or still: the palm at rest at ``q_open``): the
    ball is judged in the frame of the moving palm, which recedes along the flight and
    keeps the ball among the fingers longer than a palm at rest (the live catch, whose
    rows cannot be re-made once written: at rest, the closing started early and the
    thumb's body met the true flight 0.2-1.4 mm deep 15-20 ms before the palm on 5 of 20
    throws at 100 Hz / 5 mm, each dropped in the replay)."""
    want = earliest_close_start(closing, t_i, ready, stop_t)
    if closing.u_grasp is None or want >= t_i:
        return want
    # the ball can only meet a fingertip in the last stretch before the palm
    speed = math.hypot(*flight.velocity1(t_i))
    tt = np.arange(max(want, t_i - (closing.reach_m + r) / speed), t_i, 0.001)
    if tt.size == 0:
        return want
    b_pc = ball_in_palm(hand, flight, C, q_open, tt, t_i, stop)
    # candidate starts, earliest first (np.linspace's numbers, written out); the fingers'
    # bodies from the closing table (the more closed of the two neighbouring samples): no
    # point within its radius + TOUCH_CLEAR_M of the ball's surface. The pad point is on
    # its pad sphere, so a start whose fingertips touch the ball has a body touching it:
    # the tips are judged first (cheap), the bodies only for the starts whose tips are
    # clear.
    cands = _CAND_STEPS * ((t_i - want) / (N_CAND - 1)) + want
    cands[-1] = t_i
    n_tab = len(closing.u)
    for lo in range(0, N_CAND, _CAND_CHUNK):  # the first clear one is nearly always early
        c = cands[lo:lo + _CAND_CHUNK]
        U = np.clip((tt[None, :] - c[:, None]) / closing.duration_s, 0.0, 1.0)
        k = np.minimum(np.ceil(U * (n_tab - 1)).astype(int), n_tab - 1)
        dd = closing.tips_pc[k] - b_pc[None, :, None, :]
        dd *= dd  # (the norm over the last axis, written out: np.linalg.norm is slow there)
        d = np.sqrt(dd[..., 0] + dd[..., 1] + dd[..., 2])
        g = np.flatnonzero(~np.any(d < r + TOUCH_CLEAR_M, axis=(1, 2)))
        # the bodies of the earliest whose tips are clear first (usually clear), then
        # of the rest of the chunk's
        for part in (g[:1], g[1:]):
            if part.size:
                part = part[~_bodies_touch(closing, k[part], b_pc, r + TOUCH_CLEAR_M)]
                if part.size:
                    return float(c[part[0]])
    return float(t_i)


def ball_in_palm(hand: HandModel, flight: Flight, C: np.ndarray, q_open: np.ndarray,
                 tt: np.ndarray, t_i: float, stop) -> np.ndarray:
    """The ball's centre at times ``tt`` (before the intercept ``t_i``) in the palm's
    frame (the palm at ``q_open``, or on its stopping motion ``stop``: at ``q_open`` at
    the intercept, the motion's travel from there)."""
    if stop is None or not np.any(stop.qd):
        T = hand.palm_pose(q_open)  # a rigid pose: its inverse maps x to R^T (x - p)
        return (flight.position(tt) - (C + T[:3, 3])) @ T[:3, :3]
    n = len(q_open)
    knots = np.linspace(tt[0], tt[-1], max(2, math.ceil((tt[-1] - tt[0]) / PALM_KNOT_S) + 1))
    off = stop.offset(np.append(knots, t_i), n)  # (the knots' and the intercept's)
    F = hand.palm_poses(q_open + off[:-1] - off[-1])[:, :3, :].reshape(len(knots), 12)
    # the palm's pose between the knots, element by element (a smooth motion: see
    # ``PALM_KNOT_S``): ``np.interp``'s arithmetic, the 12 elements at once
    inner = tt < knots[-1]  # (the last sample: the last knot's pose)
    x = tt[inner]
    j = np.searchsorted(knots, x, side="right") - 1
    T = np.empty((len(tt), 12))
    T[inner] = (F[j + 1] - F[j]) / (knots[j + 1] - knots[j])[:, None] * (x - knots[j])[:, None] \
        + F[j]
    T[~inner] = F[-1]
    T = T.reshape(len(tt), 3, 4)
    rel = flight.position(tt) - (C + T[:, :, 3])
    return np.einsum("ti,tij->tj", rel, T[:, :, :3])


def _bodies_touch(closing: Closing, k: np.ndarray, b_pc: np.ndarray, reach_m: float
                  ) -> np.ndarray:
    """(candidates,) whether any finger's body, at the table samples ``k`` (candidates,
    times), comes within ``reach_m`` (+ its points' radii) of the ball centres ``b_pc``
    (times, 3): the bounding spheres first, the points only where one is near."""
    dd = closing.bound_pc[k] - b_pc[None, :, None, :]
    dd *= dd  # (the norm over the last axis, written out: np.linalg.norm is slow there)
    near = np.sqrt(dd[..., 0] + dd[..., 1] + dd[..., 2]) < closing.bound_r_m[k] + reach_m
    out = np.zeros(k.shape[0], dtype=bool)
    if not near.any():
        return out
    ic, it, jf = np.nonzero(near)
    p = closing.bodies_pc[k[ic, it], jf] - b_pc[it][:, None, :]  # (m, P, 3)
    p *= p
    hit = np.any(np.sqrt(p[..., 0] + p[..., 1] + p[..., 2]) <
                 closing.bodies_r_m[jf] + reach_m, axis=1)
    out[ic[hit]] = True
    return out

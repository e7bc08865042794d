"""Run a trajectory in the scene: the servos track its rows, the physics does the rest.

The replay starts at rest in the first row's pose (keys up, the ball at its launch
state), then steps ``scene.TIMESTEP_S`` at a time. Between two rows the servos' position
reference moves linearly (what a controller interpolating 100 Hz setpoints does); the
speed and inverse-dynamics feedforward move likewise (``actuators.Reference``).
At every row's time the state is sampled: the hand's joints, every key's travel and
the finger touching it, the servos' forces and what they asked for (before the clamp
to their motor's torque), the pad points, the ball and its contacts (``sampling``: a
row copies MuJoCo's state, the rest is computed after the run). A ball with drag gets
``-m k |v| v`` as an applied force at every step (spec section 4). On a keyboard only
the keys the hand can reach within a row collide in it (``nearkeys``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.hand.model import GRAVITY_WORLD, HandModel
from planner.simulate import actuators as act
from planner.simulate import sampling as sm
from planner.simulate.scene import TIMESTEP_S, Ball, Scene, inverse_dynamics, servo_kv


@dataclass(frozen=True)
class SimRecord:
    """The sampled replay, one entry per trajectory row (arrays, SI units)."""

    t_s: np.ndarray  # (T,)
    q_ref: np.ndarray  # (T, n) the rows
    q_sim: np.ndarray  # (T, n) the simulated joints
    key_dip_m: np.ndarray  # (T, 88) each key's travel down (zeros without a keyboard)
    key_finger: np.ndarray  # (T, 88) int8: the finger touching a key (the hand's index), -1
    servo_force: np.ndarray  # (T, n_motor) joint-side force the servo applied
    servo_demand: np.ndarray  # (T, n_motor) what the control law asked for (unclamped)
    force_limit: np.ndarray  # (T, n_motor) the servo's joint-side limit at that row
    tips_m: np.ndarray  # (T, fingers, 3) pad points, world
    palm_m: np.ndarray  # (T, 3) palm_center, world
    ball_m: np.ndarray  # (T, 3) ball centre (NaN without a ball)
    ball_speed_m_s: np.ndarray  # (T,)
    ball_contacts: np.ndarray  # (T,) int: hand geoms touching the ball
    ball_force_n: np.ndarray  # (T,) sum of normal forces on the ball, the peak since the last row
    ball_fingers: np.ndarray  # (T, fingers) bool: the finger touches the ball (any of its geoms)
    substeps: int
    wall_s: float
    unstable_at_s: float | None = None  # MuJoCo reset a diverging state here (first time)
    reach_overruns: int = 0  # rows over which the hand moved past half nearkeys' margin
    hand_contacts: tuple[tuple[int, int, int], ...] = ()  # two hands: (row, geom of the
    # left, geom of the right) of every contact between them at a row


def _ctrl_rows(scene: Scene, ref: act.Reference) -> tuple[np.ndarray, np.ndarray]:
    """Per row: the servo control at the row and its change to the next row."""
    kp = scene.servos.kp
    base = ref.q_rad + (servo_kv(scene) / kp) * ref.qd_rad_s + ref.feedforward_nm / kp
    slope = np.zeros_like(base)
    slope[:-1] = np.diff(base, axis=0)
    return base, slope


def _ball_contacts(scene: Scene, data, mujoco):
    """The ball's contacts with the hand and their summed normal force (N)."""
    geoms = np.asarray(data.contact.geom[:data.ncon])
    if len(geoms) == 0:
        return 0, 0.0
    on_ball = np.flatnonzero((geoms[:, 0] == scene.ball_geom) | (geoms[:, 1] == scene.ball_geom))
    force = 0.0
    wrench = np.zeros(6)
    for i in on_ball:
        mujoco.mj_contactForce(scene.model, data, int(i), wrench)
        force += abs(float(wrench[0]))
    return len(on_ball), force


def _rest_keys_on_fingers(scene: Scene, data, mujoco) -> None:
    """Start every key a pad point is pressing in the first row as far down as the pad
    holds it (at most to its bed): the replay starts at rest with the plan's first pose."""
    from planner.check.criteria import key_contacts
    from planner.simulate.keyboard import planned_key_travel

    tips = np.array(data.site_xpos[scene.tip_sites])[None]
    travel = planned_key_travel(key_contacts(tips))[0]
    data.qpos[scene.key_qpos] = np.maximum(data.qpos[scene.key_qpos], travel)
    mujoco.mj_forward(scene.model, data)


def launch_velocity(ball: Ball, dt_s: float) -> np.ndarray:
    """The ball's first velocity in MuJoCo: its launch velocity less half a step of its
    acceleration (gravity and drag at launch), the leapfrog start. MuJoCo integrates
    semi-implicitly (the velocity first, the position with the new velocity): started at
    ``v0`` the ball flies 0.5 g dt t below its flight (3.5 mm at 0.7 s with 1 ms steps:
    measured, live catches where the true flight grazes the thumb 0.2-1.4 mm deep were
    held in the replay, the ball passing under the thumb; started half a step back it
    follows the flight within 0.01 mm at 0.7 s with gravity alone, and the thumb deflects
    it as ``check`` says)."""
    v0 = np.asarray(ball.v0_m_s, dtype=float)
    a0 = GRAVITY_WORLD - ball.drag_per_m * float(np.linalg.norm(v0)) * v0
    return v0 - 0.5 * dt_s * a0


def _start(scene: Scene, q: np.ndarray, ball: Ball | None, mujoco):
    """The simulation's first state: the hand at the first row, the ball (if any) at its
    launch with its initial velocity, the keys resting on the fingers that start on them;
    and the ball's first velocity index (None without a ball)."""
    model = scene.model
    data = mujoco.MjData(model)
    data.qpos[scene.hand_qpos] = q[0]
    vadr = None
    if scene.ball_body >= 0:
        adr = model.jnt_qposadr[model.body_jntadr[scene.ball_body]]
        vadr = model.jnt_dofadr[model.body_jntadr[scene.ball_body]]
        data.qpos[adr:adr + 3] = model.body_pos[scene.ball_body]
        data.qpos[adr + 3:adr + 7] = (1.0, 0.0, 0.0, 0.0)
        if ball is not None:
            data.qvel[vadr:vadr + 3] = launch_velocity(ball, TIMESTEP_S)
    mujoco.mj_forward(model, data)
    if len(scene.key_qpos):
        _rest_keys_on_fingers(scene, data, mujoco)
    return data, vadr


def _step_row(scene: Scene, data, mujoco, ctrls: np.ndarray, ctrl_view: np.ndarray,
              ball: Ball | None, vadr: int | None) -> float:
    """Step from one row to the next, step ``j`` at control ``ctrls[j]`` (the control
    moving linearly), the ball's drag applied every step; returns the ball's peak contact
    force over the steps (N)."""
    model = scene.model
    step = mujoco.mj_step
    if scene.ball_body < 0:  # (the keyboard: nothing but the control per step)
        for c in ctrls:
            ctrl_view[:] = c
            step(model, data)
        return 0.0
    drag = ball.drag_per_m if ball is not None else 0.0
    mass = float(model.body_mass[scene.ball_body])
    peak_f = 0.0
    for c in ctrls:
        ctrl_view[:] = c
        if drag > 0.0:
            v = data.qvel[vadr:vadr + 3]
            data.xfrc_applied[scene.ball_body, :3] = -mass * drag * np.linalg.norm(v) * v
        step(model, data)
        peak_f = max(peak_f, _ball_contacts(scene, data, mujoco)[1])
    return peak_f


def _near(scene: Scene, data):
    """The row-by-row collision selection of a keyboard scene (None: no keyboard)."""
    if not len(scene.key_qpos):
        return None
    from planner.simulate import nearkeys
    from planner.simulate.hand_mjcf import HAND_CONAFFINITY, HAND_CONTYPE

    m = scene.model
    hand = np.flatnonzero((m.geom_contype & HAND_CONTYPE).astype(bool)
                          & (m.geom_conaffinity & HAND_CONAFFINITY).astype(bool))
    return nearkeys.near_keys(m, data, scene.key_geom_key, hand)


def _run(scene: Scene, data, mujoco, base, slope, lims, n_sub: int, ball, vadr, t_s,
         on_progress) -> tuple[sm.Rows, float | None, int]:
    """The rows' loop: (the samples, the time MuJoCo first reset a diverging state,
    the rows whose hand moved past half the collision selection's margin)."""
    from planner.simulate import nearkeys

    model = scene.model
    T = len(t_s)
    a = sm.addr(scene)
    rows = sm.Rows(T, len(scene.hand_qpos), len(a.sites))
    bad_qacc = int(mujoco.mjtWarning.mjWARN_BADQACC)
    unstable, peak_f, overruns, span, sel = None, 0.0, 0, None, None
    forcerange, ctrl_view = model.actuator_forcerange, data.ctrl
    frac = (np.arange(n_sub) / n_sub)[:, None]
    nk = _near(scene, data)
    try:
        for k in range(T):
            forcerange[:, 0] = -lims[k]
            forcerange[:, 1] = lims[k]
            rows.take(k, data, a)
            if a.ball_body >= 0:
                nb, fb = _ball_contacts(scene, data, mujoco)
                # the force: the largest since the previous row (an impact lasts a few steps)
                rows.take_ball(k, data, a, nb, max(fb, peak_f))
            if nk is not None:
                now = nearkeys.hand_span_m(nk, data)
                if span is not None and nearkeys.moved_m(span, now) > 0.5 * nk.margin_m:
                    overruns += 1
                span, was = now, sel
                sel = nearkeys.reachable(nk, span)
                nearkeys.apply(nk, model, sel, was)
            if k == T - 1:
                break
            # (every substep's control at once: the same elementwise arithmetic)
            peak_f = _step_row(scene, data, mujoco, base[k] + slope[k] * frac, ctrl_view,
                               ball, vadr)
            if unstable is None and data.warning[bad_qacc].number > 0:
                unstable = float(t_s[k])
            if on_progress is not None and k % 100 == 0:
                on_progress(k, T)
    finally:
        if nk is not None:  # (the scene's model as it was built)
            nearkeys.apply(nk, model, None, sel)
    return rows, unstable, overruns


def _reference(scene: Scene, hand: HandModel | tuple[HandModel, ...], q: np.ndarray,
               t_s: np.ndarray) -> act.Reference:
    """The servos' reference: one hand's, or each hand's of its own columns, joined."""
    if isinstance(hand, HandModel):
        return act.reference(hand, q, t_s, inverse_dynamics(scene))
    cut = np.cumsum([0, *(h.n for h in hand)])
    refs = [act.reference(h, q[:, a:b], t_s, inverse_dynamics(scene, i))
            for i, (h, a, b) in enumerate(zip(hand, cut[:-1], cut[1:]))]
    return act.Reference(*(np.concatenate([getattr(r, f) for r in refs], axis=1)
                           for f in ("q_rad", "qd_rad_s", "feedforward_nm", "ratio")))


def hand_contacts(rows: sm.Rows, geom_hand: np.ndarray | None) -> tuple[tuple[int, int, int], ...]:
    """Every contact between two hands' geoms at a row: (row, the first hand's geom, the
    second's); none for one hand."""
    if geom_hand is None or geom_hand.max(initial=-1) < 1 or not rows.contact_rows:
        return ()
    out = []
    for k, geoms in zip(rows.contact_rows, rows.contact_geoms):
        h1, h2 = geom_hand[geoms[:, 0]], geom_hand[geoms[:, 1]]
        for (g1, g2), a, b in zip(geoms.tolist(), h1.tolist(), h2.tolist()):
            if a >= 0 and b >= 0 and a != b:
                out.append((int(k), g1, g2) if a < b else (int(k), g2, g1))
    return tuple(out)


def simulate(scene: Scene, hand: HandModel | tuple[HandModel, ...], t_s: np.ndarray,
             q: np.ndarray, *, ball: Ball | None = None,
             on_progress: Callable[[int, int], None] | None = None) -> SimRecord:
    """Replay rows ``q`` (T, n) at times ``t_s`` in ``scene`` (built for ``hand``
    mounted where the rows were planned; two hands: a tuple, ``q`` their columns)."""
    import time

    import mujoco

    wall0 = time.perf_counter()
    # MuJoCo's warnings would print on stdout (--json owns it): counted in data.warning
    mujoco.set_mju_user_warning(lambda _msg: None)
    data, vadr = _start(scene, q, ball, mujoco)
    T = len(t_s)
    dt_row = float(np.median(np.diff(t_s))) if T > 1 else 0.01
    n_sub = max(1, round(dt_row / TIMESTEP_S))
    ref = _reference(scene, hand, q, t_s)
    base, slope = _ctrl_rows(scene, ref)
    lims = scene.servos.force_limit(ref.ratio)  # (T, n_motor): elementwise, row by row alike
    rows, unstable, overruns = _run(scene, data, mujoco, base, slope, lims, n_sub, ball, vadr,
                                    t_s, on_progress)
    demand, force = sm.servo_rows(rows, scene.servos.drive, base, scene.servos.kp,
                                  servo_kv(scene), lims)
    n_tips = len(scene.tip_sites)
    key_finger, ball_fingers = sm.touches(rows, scene.key_geom_key, scene.geom_finger,
                                          scene.ball_geom, n_tips)
    return SimRecord(t_s=np.asarray(t_s, dtype=float), q_ref=q, q_sim=rows.q,
                     key_dip_m=rows.key, key_finger=key_finger,
                     servo_force=force, servo_demand=demand,
                     force_limit=np.array(lims), tips_m=rows.sites[:, :n_tips],
                     palm_m=rows.sites[:, n_tips],
                     ball_m=rows.ball, ball_speed_m_s=rows.ball_v,
                     ball_contacts=rows.ball_n.astype(int), ball_force_n=rows.ball_f,
                     ball_fingers=ball_fingers,
                     substeps=n_sub, wall_s=time.perf_counter() - wall0,
                     unstable_at_s=unstable, reach_overruns=overruns,
                     hand_contacts=hand_contacts(rows, scene.geom_hand))

"""Run a trajectory in the scene: the servos track its rows, the physics does the rest.

The replay starts at rest in the first row's pose (keys up, the ball at its launch
state), then steps ``scene.TIMESTEP_S`` at a time. Between two rows the servos' position
reference moves linearly (what a controller interpolating 100 Hz setpoints does); the
speed and inverse-dynamics feedforward move likewise (``actuators.Reference``).
At every row's time the state is sampled: the hand's joints, every key's travel and
the finger touching it, the servos' forces and what they asked for (before the clamp
to their motor's torque), the pad points, the ball and its contacts. A ball with drag
gets ``-m k |v| v`` as an applied force at every step (spec section 4).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.hand.model import HandModel
from planner.simulate import actuators as act
from planner.simulate.scene import TIMESTEP_S, Ball, Scene, inverse_dynamics, servo_kv

N_KEYS = 88


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


def _ctrl_rows(scene: Scene, ref: act.Reference) -> tuple[np.ndarray, np.ndarray]:
    """Per row: the servo control at the row and its change to the next row."""
    kp = scene.servos.kp
    base = ref.q_rad + (servo_kv(scene) / kp) * ref.qd_rad_s + ref.feedforward_nm / kp
    slope = np.zeros_like(base)
    slope[:-1] = np.diff(base, axis=0)
    return base, slope


def _contacts(scene: Scene, data, mujoco, out_finger: np.ndarray, ball_geom: int,
              out_ball: np.ndarray):
    """Fill ``out_finger`` (88,) with the finger touching each key and ``out_ball``
    (fingers,) with the fingers touching the ball; return the ball's hand contacts and
    their summed normal force (N)."""
    out_finger.fill(-1)
    out_ball[:] = False
    n = data.ncon
    if n == 0:
        return 0, 0.0
    geoms = np.asarray(data.contact.geom[:n])
    g1, g2 = geoms[:, 0], geoms[:, 1]
    k1, k2 = scene.key_geom_key[g1], scene.key_geom_key[g2]
    f1, f2 = scene.geom_finger[g1], scene.geom_finger[g2]
    key = np.where(k1 >= 0, k1, k2)
    fin = np.where(k1 >= 0, f2, f1)
    sel = (key >= 0) & (fin >= 0)
    out_finger[key[sel]] = fin[sel]
    if ball_geom < 0:
        return 0, 0.0
    on = (g1 == ball_geom) | (g2 == ball_geom)
    fb = np.where(g1 == ball_geom, f2, f1)[on]
    out_ball[fb[fb >= 0]] = True
    return _ball_contacts(scene, data, mujoco, geoms)


def _ball_contacts(scene: Scene, data, mujoco, geoms: np.ndarray | None = None):
    """The ball's contacts with the hand and their summed normal force (N)."""
    if geoms is None:
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
            data.qvel[vadr:vadr + 3] = ball.v0_m_s
    mujoco.mj_forward(model, data)
    if len(scene.key_qpos):
        _rest_keys_on_fingers(scene, data, mujoco)
    return data, vadr


def _arrays(T: int, n: int, nm: int, n_tips: int) -> dict[str, np.ndarray]:
    """The record's arrays, one entry per row (``n_tips``: the hand's fingers)."""
    rec = {k: np.empty(s) for k, s in (
        ("q_sim", (T, n)), ("key", (T, N_KEYS)), ("force", (T, nm)), ("demand", (T, nm)),
        ("limit", (T, nm)), ("tips", (T, n_tips, 3)), ("palm", (T, 3)), ("ball", (T, 3)),
        ("ball_v", (T,)), ("ball_n", (T,)), ("ball_f", (T,)))}
    rec["key_finger"] = np.full((T, N_KEYS), -1, dtype=np.int8)
    rec["ball_fingers"] = np.zeros((T, n_tips), dtype=bool)
    return rec


@dataclass(frozen=True)
class _Addr:
    """The scene's addresses and gains the replay reads at every row (looked up once)."""

    drive_qpos: np.ndarray
    drive_dof: np.ndarray
    kp: np.ndarray
    kv: np.ndarray


def _addr(scene: Scene) -> _Addr:
    d = scene.servos.drive
    return _Addr(scene.hand_qpos[d], scene.hand_dof[d], scene.servos.kp, servo_kv(scene))


def _sample(rec: dict, k: int, scene: Scene, data, mujoco, ctrl: np.ndarray,
            lim: np.ndarray, peak_f: float, a: _Addr) -> None:
    """Row ``k``'s sample: the state the row's setpoint meets."""
    drive_qpos, drive_dof = a.drive_qpos, a.drive_dof
    rec["q_sim"][k] = data.qpos[scene.hand_qpos]
    rec["key"][k] = data.qpos[scene.key_qpos] if len(scene.key_qpos) else 0.0
    # (from the state itself: data.actuator_length and _velocity are those of the last
    # step's start, 1 ms old -- at 250 rad/s^2 a 0.3 N m error of the demand)
    demand = a.kp * (ctrl - data.qpos[drive_qpos]) - a.kv * data.qvel[drive_dof]
    rec["demand"][k] = demand
    rec["force"][k] = np.clip(demand, -lim, lim)
    rec["limit"][k] = lim
    rec["tips"][k] = data.site_xpos[scene.tip_sites]
    rec["palm"][k] = data.site_xpos[scene.palm_site]
    finger_now = np.full(N_KEYS, -1, dtype=np.int64)
    nb, fb = _contacts(scene, data, mujoco, finger_now, scene.ball_geom, rec["ball_fingers"][k])
    rec["key_finger"][k] = finger_now
    if scene.ball_body >= 0:
        rec["ball"][k] = data.xpos[scene.ball_body]
        rec["ball_v"][k] = float(np.linalg.norm(data.cvel[scene.ball_body][3:]))
    # the force: the largest since the previous row (an impact lasts a few steps)
    rec["ball_n"][k], rec["ball_f"][k] = nb, max(fb, peak_f)


def _step_row(scene: Scene, data, mujoco, ctrl: np.ndarray, slope: np.ndarray, n_sub: int,
              ball: Ball | None, vadr: int | None) -> float:
    """Step from one row to the next (the control moving linearly, the ball's drag
    applied every step); returns the ball's peak contact force over the steps (N)."""
    model = scene.model
    drag = ball.drag_per_m if ball is not None else 0.0
    mass = float(model.body_mass[scene.ball_body]) if scene.ball_body >= 0 else 0.0
    peak_f = 0.0
    ball_on = scene.ball_body >= 0
    # (every substep's control at once: the same elementwise arithmetic, in one call)
    ctrls = ctrl + slope * (np.arange(n_sub) / n_sub)[:, None]
    for j in range(n_sub):
        data.ctrl[:] = ctrls[j]
        if drag > 0.0:
            v = data.qvel[vadr:vadr + 3]
            data.xfrc_applied[scene.ball_body, :3] = -mass * drag * np.linalg.norm(v) * v
        mujoco.mj_step(model, data)
        if ball_on:
            peak_f = max(peak_f, _ball_contacts(scene, data, mujoco)[1])
    return peak_f


def simulate(scene: Scene, hand: HandModel, t_s: np.ndarray, q: np.ndarray, *,
             ball: Ball | None = None,
             on_progress: Callable[[int, int], None] | None = None) -> SimRecord:
    """Replay rows ``q`` (T, n) at times ``t_s`` in ``scene`` (built for ``hand``
    mounted where the rows were planned)."""
    import time

    import mujoco

    wall0 = time.perf_counter()
    # MuJoCo's warnings would print on stdout (--json owns it): counted in data.warning
    mujoco.set_mju_user_warning(lambda _msg: None)
    model = scene.model
    data, vadr = _start(scene, q, ball, mujoco)
    T = len(t_s)
    dt_row = float(np.median(np.diff(t_s))) if T > 1 else 0.01
    n_sub = max(1, round(dt_row / TIMESTEP_S))
    ref = act.reference(hand, q, t_s, inverse_dynamics(scene))
    base, slope = _ctrl_rows(scene, ref)
    rec = _arrays(T, q.shape[1], len(scene.servos.kp), len(scene.tip_sites))
    bad_qacc = int(mujoco.mjtWarning.mjWARN_BADQACC)
    unstable = None
    peak_f = 0.0
    addr = _addr(scene)
    lims = scene.servos.force_limit(ref.ratio)  # (T, n_motor): elementwise, row by row alike
    forcerange = model.actuator_forcerange
    for k in range(T):
        lim = lims[k]
        forcerange[:, 0] = -lim
        forcerange[:, 1] = lim
        _sample(rec, k, scene, data, mujoco, base[k], lim, peak_f, addr)
        if k == T - 1:
            break
        peak_f = _step_row(scene, data, mujoco, base[k], slope[k], n_sub, ball, vadr)
        if unstable is None and data.warning[bad_qacc].number > 0:
            unstable = float(t_s[k])
        if on_progress is not None and k % 100 == 0:
            on_progress(k, T)
    if scene.ball_body < 0:
        rec["ball"][:] = np.nan
        rec["ball_v"][:] = np.nan
    return SimRecord(t_s=np.asarray(t_s, dtype=float), q_ref=q, q_sim=rec["q_sim"],
                     key_dip_m=rec["key"], key_finger=rec["key_finger"],
                     servo_force=rec["force"], servo_demand=rec["demand"],
                     force_limit=rec["limit"], tips_m=rec["tips"], palm_m=rec["palm"],
                     ball_m=rec["ball"], ball_speed_m_s=rec["ball_v"],
                     ball_contacts=rec["ball_n"].astype(int), ball_force_n=rec["ball_f"],
                     ball_fingers=rec["ball_fingers"],
                     substeps=n_sub, wall_s=time.perf_counter() - wall0,
                     unstable_at_s=unstable)

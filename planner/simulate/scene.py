"""The MuJoCo scene of a replay, built as MJCF text by our code (nothing downloaded):
the hand from its URDF placed at the file's ``T_world_root``, its servos, its couplings
as equality constraints, and the task's world -- the keyboard (play) or the ball (catch).

``build_scene`` returns the compiled model and the indices the replay reads. Solver
settings: 1 ms steps (10 per row at 100 Hz; the stiffest servo, a PIP with its DIP,
has a natural period of about 10 ms), the implicit-in-velocity integrator
(``implicitfast``: the servos' damping is integrated implicitly), an elliptic friction
cone (a grasp's friction as a cone, not a pyramid).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from planner.errors import InputError
from planner.hand.bodies import collision_bodies
from planner.hand.model import GRAVITY_WORLD, HandModel
from planner.hand.pair import prefixed_spec
from planner.hand.urdf import urdf_text
from planner.simulate import actuators as act
from planner.simulate.hand_mjcf import (
    HAND_CONAFFINITY,
    HAND_CONTYPE,
    PAD_FRICTION,
    hand_bodies,
    matrix_quat,
    mjcf_vec,
)
from planner.simulate.keyboard import KEY_STIFFNESS_N_M, key_bodies

TIMESTEP_S = 0.001
CONTACT_MODELS = ("full", "pads")
WORLD_CONTYPE, WORLD_CONAFFINITY = 2, 1  # keys and ball touch the hand, not each other
COUPLING_POLY_DEGREE = 4  # MuJoCo's joint equality: a quartic (a nonlinear law is fitted)
# Contacts, key stops and couplings as near-rigid constraints: MuJoCo's default (a 20 ms
# time constant, impedance 0.95) lets a 40 g key pass its bed by 0.09 rad under a 4 N m
# push; impedance 0.999 at the smallest stable time constant (2 steps) leaves 2e-5 rad.
HARD_SOLREF = (2 * TIMESTEP_S, 1.0)
HARD_SOLIMP = (0.99, 0.999, 0.001)
# the palm pad's pair with the ball: the friction the automatic contact had (MuJoCo takes
# the larger of two geoms': the palm box's rubber and the ball's, both 0.8), in a pair's
# five numbers (sliding twice, torsional, rolling twice)
PAD_PAIR_FRICTION = f"{PAD_FRICTION:g} {PAD_FRICTION:g} 0.005 0.0001 0.0001"
KEY_FRICTION = 0.5  # pad on a key top (the pad's 0.8 applies: MuJoCo takes the larger)
# Keys at rest sleep (MuJoCo's sleeping islands, 3.4+: a tree slower than the tolerance
# for 10 steps leaves the pipeline -- its limit row, its dynamics -- until a hand geom
# touches it; docs: Computation, "Sleeping islands"). 88 keys resting on their stops were
# 88 of the ~100 constraint rows of every step. The tolerance: a key slower than 10 um/s
# (0.1 um per 10 ms row, 1/50000 of its 5 mm key-down travel) is at rest. MuJoCo's
# default, 1 mm/s, froze keys still settling and moved the sample songs' physics F1 by up
# to 0.03 (twinkle 0.354 -> 0.334, fast 0.354 -> 0.319); at 1e-5 (and 1e-7) every key's
# travel stays within 0.1 um of the awake replay's (bench/bench_simulate.py --speed).
KEY_SLEEP_TOLERANCE_M_S = 1e-5


@dataclass(frozen=True)
class Ball:
    """The catch's ball: initial state (catch frame), radius, mass, drag k (1/m) and its
    moment of inertia over m R^2 (the planner's ``Ball.inertia_ratio``: a catch file's by
    ``planner.balls.file_inertia_ratio``; 0.4 is MuJoCo's solid sphere)."""

    p0_m: tuple[float, float, float]
    v0_m_s: tuple[float, float, float]
    radius_m: float
    mass_kg: float
    drag_per_m: float
    inertia_ratio: float


@dataclass(frozen=True)
class Scene:
    """A compiled scene and where its parts are in MuJoCo's arrays."""

    model: object  # mujoco.MjModel
    xml: str
    hand_qpos: np.ndarray  # (n,) qpos address of each hand joint, the hand's order
    hand_dof: np.ndarray  # (n,) dof address of each hand joint
    key_qpos: np.ndarray  # (88,) qpos address of each key hinge (empty without keys)
    key_geom_key: np.ndarray  # (ngeom,) key index of a geom, -1 for none
    geom_finger: np.ndarray  # (ngeom,) finger index (the hand's fingers; two hands: the
    # left's, then the right's) of a hand geom, -1 none
    tip_sites: np.ndarray  # site ids of the pad points, the hand's fingers' order (each hand's)
    palm_site: int  # (two hands: the left's; a play reads none)
    ball_body: int  # -1 without a ball
    ball_geom: int
    servos: act.ServoSet
    geom_hand: np.ndarray | None = None  # (ngeom,) the part (hand) of a hand geom, -1 none
    hand_dofs: tuple[np.ndarray, ...] = ()  # each hand's dof addresses (its part of hand_dof)
    hand_qposes: tuple[np.ndarray, ...] = ()  # each hand's qpos addresses


def _f(x) -> str:
    return f"{float(x):.12g}"


def require_mujoco():
    """The ``mujoco`` module, or the InputError saying how to get it (exit 2)."""
    try:
        import mujoco
    except ImportError:
        raise InputError("simulate needs MuJoCo: pip install -e \".[physics]\"") from None
    except (AttributeError, OSError, RuntimeError) as e:  # MUJOCO_GL names a missing library
        import os

        raise InputError(f"MuJoCo does not load with MUJOCO_GL={os.environ.get('MUJOCO_GL')}"
                         f" ({type(e).__name__}: {e}): set it to egl, osmesa or glfw, or "
                         "unset it") from None
    return mujoco


def _keyboard(world: ET.Element) -> None:
    for k in key_bodies():
        # (a key may sleep at rest: KEY_SLEEP_TOLERANCE_M_S)
        body = ET.SubElement(world, "body", name=k.name, pos="0 0 0", sleep="allowed")
        # straight down (qpos = the key's travel, m), from its rest stop to its bed
        ET.SubElement(body, "joint", name=f"{k.name}_slide", type="slide", axis="0 0 -1",
                      limited="true", range=mjcf_vec((0.0, k.dip_m)),
                      stiffness=_f(KEY_STIFFNESS_N_M), springref=_f(k.springref_m),
                      damping=_f(k.damping_ns_m))
        box = np.array([2 * h for h in k.boxes[0].half_m])  # (its inertia does not act)
        ET.SubElement(body, "inertial", pos=mjcf_vec(k.com_m), mass=_f(k.mass_kg),
                      diaginertia=mjcf_vec([k.mass_kg * float(box @ box) / 12.0] * 3))
        for i, b in enumerate(k.boxes):
            ET.SubElement(body, "geom", name=f"{k.name}_{i}", type="box", pos=mjcf_vec(b.center_m),
                          size=mjcf_vec(b.half_m), mass="0",
                          contype=str(WORLD_CONTYPE), conaffinity=str(WORLD_CONAFFINITY),
                          friction=f"{KEY_FRICTION} 0.005 0.0001",
                          rgba="0.1 0.1 0.1 1" if k.black else "0.95 0.95 0.92 1")


def _ball(world: ET.Element, ball: Ball) -> None:
    body = ET.SubElement(world, "body", name="ball", pos=mjcf_vec(ball.p0_m))
    ET.SubElement(body, "freejoint", name="ball_free")
    inertia = ball.inertia_ratio * ball.mass_kg * ball.radius_m ** 2  # about its centre
    ET.SubElement(body, "inertial", pos="0 0 0", mass=_f(ball.mass_kg),
                  diaginertia=mjcf_vec([inertia] * 3))  # (the geom's own would be a solid ball's)
    ET.SubElement(body, "geom", name="ball", type="sphere", size=_f(ball.radius_m),
                  contype=str(WORLD_CONTYPE),
                  conaffinity=str(WORLD_CONAFFINITY), friction="0.8 0.005 0.0001",
                  rgba="0.8 0.9 0.2 1")


def _palm_pads(root: ET.Element, parts: tuple[ScenePart, ...]) -> None:
    """The ball on a hand's padded palm (the hand file's ``[palm] pad_give_m``,
    ``planner.hand.pad``): the palm box's contact with the ball alone as an explicit pair
    whose time constant gives the pad's give at its rated speed, critically damped (the
    automatic palm-ball contact excluded). A hand without a pad keeps the hard contact; no
    other contact changes (a play's scene has no ball)."""
    pads = [p for p in parts if p.hand.palm_pad is not None]
    if not pads:
        return
    el = ET.SubElement(root, "contact")
    for part in pads:
        pre = part.prefix
        ET.SubElement(el, "exclude", body1=f"{pre}palm", body2="ball")
        ET.SubElement(el, "pair", name=f"{pre}palm_pad", geom1=f"{pre}palm_box", geom2="ball",
                      condim="3", friction=PAD_PAIR_FRICTION,
                      solref=mjcf_vec((part.hand.palm_pad.contact_time_s(), 1.0)),
                      solimp=mjcf_vec(HARD_SOLIMP))


def _couplings(eq: ET.Element, hand: HandModel, joints, pre: str = "") -> None:
    """Each coupling as ``dep = poly(src)``: the URDF's mimic (linear) as it is; a
    nonlinear law (Mk5) fitted by a quartic over the source joint's range. ``pre``: the
    hand's prefix in a two-hand scene."""
    mimic = {j.name: j.mimic for j in joints if j.mimic is not None}
    for c in hand.couplings:
        dep, src = pre + hand.joint_names[c.dep], pre + hand.joint_names[c.src]
        if dep in mimic and mimic[dep][0] == src:
            coef = [mimic[dep][2], mimic[dep][1], 0.0, 0.0, 0.0]
        else:
            x = np.linspace(hand.lower[c.src], hand.upper[c.src], 200)
            coef = list(np.polyfit(x, c.value(x), COUPLING_POLY_DEGREE)[::-1])
        ET.SubElement(eq, "joint", name=f"couple_{dep}", joint1=dep, joint2=src,
                      polycoef=" ".join(f"{v:.12g}" for v in coef))


@dataclass(frozen=True)
class ScenePart:
    """One hand of a scene: its model, where its root is (``T_world_root``), its servos,
    the prefix of its names ("" alone; ``left.``/``right.`` in a two-hand scene) and its
    geoms' (contype, conaffinity)."""

    hand: HandModel
    T_world_root: np.ndarray
    servos: act.ServoSet
    prefix: str = ""
    collide_bits: tuple[int, int] = (HAND_CONTYPE, HAND_CONAFFINITY)


PAIR_BIT = 4  # two hands: the left's geoms carry it in contype, the right's in conaffinity


def pair_bits(i: int) -> tuple[int, int]:
    """Hand ``i`` of two: its geoms' (contype, conaffinity), so that each hand's geoms
    touch the keys, the ball and the other hand's geoms, never its own (MuJoCo collides
    two geoms when contype of one and conaffinity of the other share a bit)."""
    return ((HAND_CONTYPE | PAIR_BIT, HAND_CONAFFINITY) if i == 0
            else (HAND_CONTYPE, HAND_CONAFFINITY | PAIR_BIT))


def _hand_part(world: ET.Element, part: ScenePart, contact: str) -> list:
    """A hand's bodies under a mount body at its root's pose, its palm site; its joints."""
    hand, pre, T = part.hand, part.prefix, np.asarray(part.T_world_root, dtype=float)
    mount = ET.SubElement(world, "body", name=f"{pre}mount", pos=" ".join(f"{float(v):.12g}" for v in T[:3, 3]),
                          quat=mjcf_vec(matrix_quat(T[:3, :3])))
    armature = {pre + hand.joint_names[int(d)]: float(a)
                for d, a in zip(part.servos.drive, part.servos.armature)}
    spec = hand.spec if not pre else prefixed_spec(hand.spec, pre)
    joints = hand_bodies(hand.urdf if not pre else urdf_text(spec), mount,
                         tuple(pre + t for t in hand.tip_frames), armature,
                         collision_bodies(spec), pads_only=contact == "pads",
                         collide_bits=part.collide_bits)
    palm = _find_body(mount, pre + "palm_center")  # (an empty Element is falsy: no `or`)
    ET.SubElement(mount if palm is None else palm, "site", name=f"{pre}palm_center_site",
                  size="0.002")
    return joints


def _actuators(acts: ET.Element, part: ScenePart) -> None:
    servos, pre = part.servos, part.prefix
    for m, name in enumerate(servos.names):
        kp = servos.kp[m]
        lim = servos.force_limit(servos.ratio)[m]
        ET.SubElement(acts, "general", name=f"motor.{pre}{name}",
                      joint=pre + part.hand.joint_names[int(servos.drive[m])], gaintype="fixed",
                      gainprm=_f(float(kp)), biastype="affine", biasprm=mjcf_vec((0.0, -kp, 0.0)),
                      forcelimited="true", forcerange=mjcf_vec((-lim, lim)))


def scene_xml(hand: HandModel, T_world_root: np.ndarray, keyboard: bool,
              ball: Ball | None, servos: act.ServoSet,
              contact: str = "full") -> tuple[str, list]:
    """The scene of one hand (``parts_xml`` of one part)."""
    return parts_xml(hand.name, (ScenePart(hand, T_world_root, servos),), keyboard, ball,
                     contact)


def parts_xml(name: str, parts: tuple[ScenePart, ...], keyboard: bool, ball: Ball | None,
              contact: str = "full") -> tuple[str, list]:
    """The MJCF text of a scene of one hand or two (``parts``), and the first hand's
    joints."""
    root = ET.Element("mujoco", model=f"replay_{name}")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true", boundmass="1e-6",
                  boundinertia="1e-12")
    option = ET.SubElement(root, "option", timestep=_f(TIMESTEP_S), integrator="implicitfast",
                           cone="elliptic",
                           gravity=" ".join(f"{float(g):g}" for g in GRAVITY_WORLD))
    if keyboard:  # (the catch's ball and hand never rest: nothing to gain)
        option.set("sleep_tolerance", _f(KEY_SLEEP_TOLERANCE_M_S))
        ET.SubElement(option, "flag", sleep="enable")
    ET.SubElement(root, "size", memory="64M")
    default = ET.SubElement(root, "default")
    ET.SubElement(default, "geom", solref=mjcf_vec(HARD_SOLREF), solimp=mjcf_vec(HARD_SOLIMP))
    ET.SubElement(default, "joint", solreflimit=mjcf_vec(HARD_SOLREF), solimplimit=mjcf_vec(HARD_SOLIMP))
    ET.SubElement(default, "equality", solref=mjcf_vec(HARD_SOLREF), solimp=mjcf_vec(HARD_SOLIMP))
    world = ET.SubElement(root, "worldbody")
    joints = [_hand_part(world, part, contact) for part in parts]
    if keyboard:
        _keyboard(world)
    if ball is not None:
        _ball(world, ball)
        if contact == "full":
            _palm_pads(root, parts)
    eq = ET.SubElement(root, "equality")
    for part, js in zip(parts, joints):
        _couplings(eq, part.hand, js, part.prefix)
    acts = ET.SubElement(root, "actuator")
    for part in parts:
        _actuators(acts, part)
    return ET.tostring(root, encoding="unicode"), joints[0]


def _find_body(el: ET.Element, name: str) -> ET.Element | None:
    for b in el.iter("body"):
        if b.get("name") == name:
            return b
    return None


def build_scene(hand: HandModel, T_world_root: np.ndarray, *, keyboard: bool = False,
                ball: Ball | None = None, contact: str = "full") -> Scene:
    """Compile the scene; the servos' damping is set from the compiled mass matrix.

    ``contact``: "full" (every finger segment, the palm, the pads: the URDF's shapes) or
    "pads" (only the pad points, as the kinematic check: the dynamics without the
    geometry of the fingers' bodies)."""
    return build_parts(hand.name, (ScenePart(hand, T_world_root, act.servo_set(hand)),),
                       keyboard=keyboard, ball=ball, contact=contact)


def pair_parts(hands: tuple[HandModel, ...], poses: tuple[np.ndarray, ...],
               prefixes: tuple[str, ...]) -> tuple[ScenePart, ...]:
    """The parts of a two-hand scene: each hand at its pose, its names prefixed, its
    geoms touching the other hand's (``pair_bits``)."""
    return tuple(ScenePart(h, T, act.servo_set(h), p, pair_bits(i))
                 for i, (h, T, p) in enumerate(zip(hands, poses, prefixes)))


def build_parts(name: str, parts: tuple[ScenePart, ...], *, keyboard: bool = False,
                ball: Ball | None = None, contact: str = "full") -> Scene:
    """``build_scene`` of one hand or two (``parts``): the hands' joints, dofs, servos
    and fingers in the parts' order, each servo's damping from its own hand."""
    if contact not in CONTACT_MODELS:
        raise InputError(f"contact model must be one of {', '.join(CONTACT_MODELS)}: {contact!r}")
    mujoco = require_mujoco()
    xml, _ = parts_xml(name, parts, keyboard, ball, contact)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    qpos, dofs = [], []
    for part in parts:
        names = [part.prefix + n for n in part.hand.joint_names]
        qpos.append(np.array([model.jnt_qposadr[model.joint(n).id] for n in names]))
        dofs.append(np.array([model.jnt_dofadr[model.joint(n).id] for n in names]))
        data.qpos[qpos[-1]] = part.hand.q_neutral
    mujoco.mj_forward(model, data)
    kvs = [_servo_damping(model, data, part, dof, mujoco) for part, dof in zip(parts, dofs)]
    model.actuator_biasprm[:, 2] = -np.concatenate(kvs)
    key_qpos = np.array([model.jnt_qposadr[model.joint(f"{k.name}_slide").id]
                         for k in key_bodies()] if keyboard else [], dtype=int)
    key_geom = np.full(model.ngeom, -1, dtype=int)
    geom_finger = np.full(model.ngeom, -1, dtype=int)
    geom_hand = np.full(model.ngeom, -1, dtype=int)
    fingers = [(i, part.prefix + f) for i, part in enumerate(parts) for f in part.hand.fingers]
    for g in range(model.ngeom):
        name = model.geom(g).name
        body = model.body(model.geom_bodyid[g]).name
        if name.startswith("key_"):
            key_geom[g] = int(name.split("_")[1]) - 21
        elif (model.geom_contype[g] & HAND_CONTYPE) and \
                (model.geom_conaffinity[g] & HAND_CONAFFINITY):
            geom_finger[g] = next((k for k, (_, f) in enumerate(fingers)
                                   if body.startswith(f)), -1)
            geom_hand[g] = next(i for i, part in enumerate(parts)
                                if body.startswith(part.prefix))
    ball_body = model.body("ball").id if ball is not None else -1
    first = parts[0]
    return Scene(model=model, xml=xml, hand_qpos=np.concatenate(qpos),
                 hand_dof=np.concatenate(dofs), key_qpos=key_qpos, key_geom_key=key_geom,
                 geom_finger=geom_finger,
                 tip_sites=np.array([model.site(p.prefix + f).id for p in parts
                                     for f in p.hand.tip_frames]),
                 palm_site=model.site(f"{first.prefix}palm_center_site").id,
                 ball_body=ball_body,
                 ball_geom=model.geom("ball").id if ball is not None else -1,
                 servos=act.joined_servos([p.servos for p in parts],
                                          [p.prefix for p in parts],
                                          [p.hand.n for p in parts]),
                 geom_hand=geom_hand, hand_dofs=tuple(dofs), hand_qposes=tuple(qpos))


def _servo_damping(model, data, part: ScenePart, hand_dof: np.ndarray, mujoco) -> np.ndarray:
    """A hand's servos' damping: critical for a driven joint's inertia with its coupled
    joints moving along (v^T M v, v = S's column)."""
    hand, servos = part.hand, part.servos
    S = hand.dq_dindependent(hand.q_neutral)
    col = {int(j): k for k, j in enumerate(hand.independent)}
    inertia = np.empty(len(servos.drive))
    Mv = np.zeros(model.nv)
    for m, d in enumerate(servos.drive):
        v = np.zeros(model.nv)
        v[hand_dof] = S[:, col[int(d)]]
        mujoco.mj_mulM(model, data, Mv, v)
        inertia[m] = float(v @ Mv)
    return act.critical_damping(servos.kp, inertia)


def servo_kv(scene: Scene) -> np.ndarray:
    return -np.asarray(scene.model.actuator_biasprm[:, 2])


def inverse_dynamics(scene: Scene, part: int | None = None):
    """``f(q, qd, qdd) -> tau`` (n,): the generalised forces on the hand's joints that
    give it acceleration ``qdd`` at ``q, qd`` in this scene's model without contacts
    (``M(q) qdd + c(q, qd)``: links, rotor inertia as armature, Coriolis, gravity). The
    couplings' constraint forces are left out: a servo's feedforward sums its coupled
    joints' forces (``actuators.reference``). ``part``: hand ``part`` of a two-hand scene
    alone (its joints; the hands are separate trees, so neither moves the other's)."""
    mujoco = require_mujoco()
    model = scene.model
    data = mujoco.MjData(model)
    acc = np.zeros(model.nv)
    out = np.zeros(model.nv)
    qpos = scene.hand_qpos if part is None else scene.hand_qposes[part]
    dof = scene.hand_dof if part is None else scene.hand_dofs[part]

    def f(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        data.qpos[qpos] = q
        data.qvel[:] = 0.0
        data.qvel[dof] = qd
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_makeM(model, data)  # (the armature included)
        mujoco.mj_comVel(model, data)
        mujoco.mj_rne(model, data, 0, out)  # c(q, qd): Coriolis, centrifugal, gravity
        bias = out[dof].copy()
        acc[:] = 0.0
        acc[dof] = qdd
        mujoco.mj_mulM(model, data, out, acc)
        return out[dof] + bias

    return f

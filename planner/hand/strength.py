"""The hand's strength from its own model (``hand --strength``), beside seed 000's
requirements.

Per finger (thumb included):

* **Fingertip force, straight and flexed**: the largest force the pad pushes with
  along its own normal (the distal segment's palmar side, the pad frame's -z), the
  palm held fixed (only the finger's own motors count), the hand's weight left out.
  Joint torques ``tau = J^T f u`` (Pinocchio's Jacobian of the pad point), motor
  torques through the couplings and the efficiency (``HandModel.motor_torques``), each
  within its capacity (``planner.hand.tendon``: peak torque, or tendon force x spool
  radius): ``f = min_m cap_m / |tau_m(u)|``, the argmin naming the limiting part.
  Straight: every joint of the finger at 0. Flexed: every tendon-driven flexion joint
  at ``FLEXED_RAD`` (45 deg, the issue's estimate), clipped to its range; abduction 0.
* **Key press at the weakest posture**: the smallest of the atlas's ``max_force_n``
  over every press pose the finger has (``planner.play.atlas``: the poses ``play``
  presses with, gravity at the keyboard mount included; 0 where the motors cannot drive
  the key down its travel, ``DESCENT_PART``); beside it the motor torque
  a 1 N key press needs there, against the seed's 0.144 N m (line 82).
* **Actuation time, open to closed**: each tendon-driven flexion joint from its lower
  to its upper limit, rest to rest at its speed and acceleration limits
  (``d >= v^2/a``: ``d/v + v/a``, else ``2 sqrt(d/a)``), the slowest joint of the
  finger; its speed limit named: the motor's speed through the transmission, or the
  joint's mechanical cap (or its acceleration limit, when the move never reaches that
  speed).

For the hand: the **grip force** on a 2.5 in cylinder (``planner.hand.grip``).

Requirements (seed 000 = ``000_776cdc32671efdf6.txt``): grip 25-40 kg +-5 (Table 1,
line 38), actuation 150-300 ms +-50 (line 40), key press 0.144 N m of motor torque
for "about 1Nm of force" (line 82: a force in N m, read as 1 N; and a 20 mm pulley
there against the 5 mm spool radius of line 267).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from planner.hand.grip import Grip, flexion_joints, grip
from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity

FLEXED_RAD = math.radians(45.0)  # issue 17: "45 deg flexion, all fingers"
GRIP_REQUIRED_KG = (25.0, 40.0)  # seed 000 Table 1, line 38 (tolerance +-5 kg)
ACTUATION_REQUIRED_S = (0.150, 0.300)  # seed 000 Table 1, line 40
ACTUATION_TOL_S = 0.050  # seed 000 Table 1, line 40: the tolerance, +-50 ms
PRESS_REQUIRED_NM = 0.144  # seed 000, line 82: motor torque to press a key
PRESS_KEY_FORCE_N = 1.0  # seed 000, line 82: "about 1Nm of force to press a piano key"
# a press pose whose motors cannot drive the key down its travel (planner.play.force:
# its spring with the pad's friction) holds no note: its ``max_force_n`` is 0
DESCENT_PART = "the descent: the key's spring with the pad's friction (planner.play.force)"
KGF_N = 9.81  # one kilogram-force (the seed's g, line 177)


@dataclass(frozen=True)
class FingerStrength:
    """One finger's numbers (SI units; ``*_part`` name the limiting part)."""

    finger: str
    straight_force_n: float
    straight_part: str
    flexed_force_n: float
    flexed_part: str
    press_force_n: float | None  # None: the finger presses no key from the mount
    press_part: str
    press_torque_nm: float | None  # motor torque for a PRESS_KEY_FORCE_N press there
    close_time_s: float
    close_part: str


@dataclass(frozen=True)
class HandStrength:
    hand: str
    fingers: tuple[FingerStrength, ...]
    grip: Grip

    def to_dict(self) -> dict:
        """``hand --strength --json``: one JSON object (SI units, kgf where named)."""
        g = self.grip
        return {
            "command": "hand", "name": self.hand, "strength": {
                "fingers": [asdict(f) for f in self.fingers],
                "grip": {"cylinder_diameter_m": g.diameter_m, "offset_m": g.offset_m,
                         "force_n": g.force_n, "force_kgf": g.force_kgf,
                         "fingers": list(g.fingers), "finger_forces_n": list(g.finger_forces_n),
                         "limiting": list(g.limiting),
                         "not_touching": {c.finger: c.why for c in g.closures if not c.reached}},
                "requirements": {"grip_kg": list(GRIP_REQUIRED_KG),
                                 "actuation_s": list(ACTUATION_REQUIRED_S),
                                 "press_motor_torque_nm": PRESS_REQUIRED_NM,
                                 "press_key_force_n": PRESS_KEY_FORCE_N,
                                 "source": "seed 000_776cdc32671efdf6, Table 1 and line 82"}}}

    def summary(self) -> str:
        """The strength table, each number beside the seed's requirement."""
        lo, hi = ACTUATION_REQUIRED_S
        L = [(f"hand {self.hand}: strength from its model (motors, tendons at their design "
              "force, gears; the hand's weight left out but for key presses)"),
             "  fingertip force along the pad normal (N), straight | flexed 45 deg:"]
        for f in self.fingers:
            L.append(f"    {f.finger:7s} {f.straight_force_n:7.2f}  {f.straight_part:32s} | "
                     f"{f.flexed_force_n:7.2f}  {f.flexed_part}")
        L.append(f"  key press at the weakest press pose (N; motor torque for a "
                 f"{PRESS_KEY_FORCE_N:g} N key, seed {PRESS_REQUIRED_NM} N m):")
        for f in self.fingers:
            if f.press_force_n is None:
                L.append(f"    {f.finger:7s}    none  {f.press_part}")
            else:
                L.append(f"    {f.finger:7s} {f.press_force_n:7.2f}  {f.press_part:32s} "
                         f"{f.press_torque_nm:.4f} N m")
        L.append(f"  actuation open -> closed (ms; seed {lo * 1000:.0f}-{hi * 1000:.0f} +-50):")
        for f in self.fingers:
            t = f.close_time_s
            verdict = ("ok" if lo <= t <= hi else "within +-50" if lo - ACTUATION_TOL_S <= t
                       <= hi + ACTUATION_TOL_S else "outside")
            L.append(f"    {f.finger:7s} {t * 1000:7.0f}  {verdict:11s} {f.close_part}")
        g = self.grip
        glo, ghi = GRIP_REQUIRED_KG
        L.append(f"  grip on a {g.diameter_m * 1000:.1f} mm (2.5 in) cylinder, "
                 f"{g.offset_m * 1000:.0f} mm from the palm centre towards the knuckles: "
                 f"{g.force_n:.1f} N = {g.force_kgf:.2f} kgf (seed {glo:g}-{ghi:g} kg +-5)"
                 + (f" by {', '.join(g.fingers)}" if g.fingers else ""))
        L.append(f"    limited by: {', '.join(g.limiting) or '-'}")
        for c in g.closures:
            if not c.reached:
                L.append(f"    {c.finger} does not touch: {c.why}")
        return "\n".join(L)


def _finger_motors(hand: HandModel, finger: str) -> list[int]:
    """The motors that move the finger: those driving one of its joints, or the source of
    a coupling one of its joints follows (the AGH's shaft of a paired base joint)."""
    own = set(hand.spec.joints_of(finger))
    moved = own | {c.source for c in hand.spec.couplings if c.joint in own}
    return [m for m, a in enumerate(hand.actuators) if a.drives in moved]


def finger_posture(hand: HandModel, finger: str, flex_rad: float) -> np.ndarray:
    """The hand at rest with ``finger``'s joints at 0 and its tendon-driven flexion joints
    at ``flex_rad`` (each clipped into its range), couplings applied."""
    q = hand.q_neutral.copy()
    for j in hand.joint_slice(finger):
        q[j] = np.clip(0.0, hand.lower[j], hand.upper[j])
    for j in flexion_joints(hand, finger):
        q[j] = np.clip(flex_rad, hand.lower[j], hand.upper[j])
    return hand.apply_couplings(q)


def pad_normal(hand: HandModel, q: np.ndarray, finger: str) -> np.ndarray:
    """The pad's outward normal (world): the pad frame's -z, its palmar side."""
    return -hand.frame_pose(q, hand.tip_frames[hand.fingers.index(finger)])[:3, 2]


def tip_force(hand: HandModel, q: np.ndarray, finger: str) -> tuple[float, str]:
    """The largest pad force (N) along the pad normal at ``q`` and its limiting part."""
    u = pad_normal(hand, q, finger)
    J = hand.tip_jacobians(q)[hand.fingers.index(finger)]
    per_n = hand.motor_torques(q, J.T @ u)
    cap = actuator_capacity(hand)
    best, part = math.inf, "nothing (no motor is loaded)"
    for m in _finger_motors(hand, finger):
        if abs(per_n[m]) > 1e-12 and cap.torque_nm[m] / abs(per_n[m]) < best:
            best, part = cap.torque_nm[m] / abs(per_n[m]), cap.part(m)
    return float(best), part


def close_time(hand: HandModel, finger: str) -> tuple[float, str]:
    """Rest-to-rest time (s) of the finger's flexion joints over their whole range,
    the slowest one, and what sets its speed."""
    worst, part = 0.0, ""
    for j in flexion_joints(hand, finger):
        d, v, a = hand.upper[j] - hand.lower[j], hand.velocity[j], hand.acceleration[j]
        cruise = d >= v * v / a
        t = d / v + v / a if cruise else 2.0 * math.sqrt(d / a)
        if t > worst:
            worst, part = t, (_speed_source(hand, j) if cruise else
                              f"{hand.joint_names[j]} at its {a:g} rad/s^2 (it never "
                              f"reaches its {v:g} rad/s)")
    return worst, part


def _speed_source(hand: HandModel, j: int) -> str:
    """What limits joint ``j``'s speed: its motor's speed, or the joint's mechanical cap."""
    name = hand.joint_names[j]
    m = next(m for m, a in enumerate(hand.actuators) if a.drives == name)
    motor_limited = math.inf
    for x in np.linspace(hand.lower[j], hand.upper[j], 41):
        q = hand.q_neutral.copy()
        q[j] = x
        motor_limited = min(motor_limited, hand.motor_speed[m] / abs(hand.motor_ratio(
            hand.apply_couplings(q))[m]))
    v = hand.velocity[j]
    if v < motor_limited * (1 - 1e-6):
        return f"{name} at its {v:g} rad/s cap (the motor allows {motor_limited:.0f} rad/s)"
    return f"{name} at motor.{hand.motor_names[m]}'s speed ({v:.1f} rad/s at the joint)"


def press_strength(hand: HandModel) -> dict[str, tuple[float | None, str, float | None]]:
    """Per finger: the smallest ``max_force_n`` over its atlas press poses (every play
    posture's), the limiting part there and the motor torque a PRESS_KEY_FORCE_N press
    needs there."""
    from planner.play.atlas import SPAN_M, STEP_M, Atlas, posture_count

    atlases = [Atlas(hand, posture=i) for i in range(posture_count(hand))]
    cap = actuator_capacity(hand)
    n = round(SPAN_M / STEP_M)
    out: dict[str, tuple[float | None, str, float | None]] = {}
    for f in hand.fingers:
        entries = [(a, e) for a in atlases for pc in range(12) for k in range(-n, n + 1)
                   if (e := a.entry_at(f, pc, k)) is not None]
        if not entries:
            out[f] = (None, "no press pose: the finger reaches no key from the mount", None)
            continue
        atlas, weakest = min(entries, key=lambda ae: ae[1].max_force_n)
        q = atlas.full_q(weakest, "press", 0.0)
        F = weakest.max_force_n
        load = np.abs(hand.press_torques(q, {f: F})) / cap.torque_nm
        m = int(np.argmax(load))
        need = np.abs(hand.press_torques(q, {f: PRESS_KEY_FORCE_N}))[_finger_motors(hand, f)]
        part = DESCENT_PART if F == 0.0 else cap.part(m)
        out[f] = (float(F), part, float(need.max()))
    return out


def hand_strength(hand: HandModel) -> HandStrength:
    """Every number of the strength table (see the module)."""
    press = press_strength(hand)
    fingers = []
    for f in hand.fingers:
        s_f, s_p = tip_force(hand, finger_posture(hand, f, 0.0), f)
        x_f, x_p = tip_force(hand, finger_posture(hand, f, FLEXED_RAD), f)
        t, t_p = close_time(hand, f)
        fingers.append(FingerStrength(f, s_f, s_p, x_f, x_p, press[f][0], press[f][1],
                                      press[f][2], t, t_p))
    return HandStrength(hand.name, tuple(fingers), grip(hand))

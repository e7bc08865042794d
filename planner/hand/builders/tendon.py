"""The tendon hand (``kind = "tendon"``, the default): a thumb with a CMC abduction
servo and CMC flexion and IP on tendons; four long fingers, each an MCP abduction
servo, MCP flexion on one tendon, PIP and DIP on another (the DIP coupled to the PIP)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from planner.errors import InputError
from planner.hand.builders.common import (
    assemble_spec,
    long_fingers,
    seg_link,
    start_hand,
    tip,
)
from planner.hand.builders.values import (
    get_length,
    get_positive,
    get_range,
    get_value,
    get_vec,
    rotor_inertia,
)
from planner.hand.spec import (
    FINGERS,
    ROTOR_KEY,
    Actuator,
    HandSpec,
    Joint,
    LinearCoupling,
    Link,
)


@dataclass(frozen=True)
class _TendonDrive:
    """What every tendon finger of a hand file shares: the spool and its motor, the
    tendons' efficiency, the abduction servos, the fingers' speed and acceleration caps."""

    spool: float
    w_motor: float
    eff: float
    tau_peak: float
    servo: dict
    v_cap: float
    a_max: float
    rotor: float = 0.0  # the tendon motors' rotor inertia, kg m^2

    def speed(self, arm: float) -> float:
        """A joint's speed cap: the motor's speed through its moment arm, or the cap."""
        return min(self.v_cap, self.w_motor * self.spool / arm)


def build_tendon_hand(data: dict[str, Any]) -> HandSpec:
    hp = start_hand(data)
    palm = get_value(data, "palm", dict)
    p_len = get_length(palm, "length")
    tendon = get_value(data, "tendon", dict)
    spool = get_positive(tendon, "spool_radius_m")
    eff = get_value(tendon, "efficiency")
    if not 0 < eff <= 1:
        raise InputError("tendon efficiency must be in (0, 1]")
    fs = get_value(data, "finger_speed", dict)
    tp = _TendonDrive(spool, get_value(tendon, "motor_speed_rad_s"), eff,
                      get_value(tendon, "motor_peak_torque_nm"), get_value(data, "servo", dict),
                      get_value(fs, "velocity_cap_rad_s"), get_value(fs, "acceleration_rad_s2"),
                      rotor_inertia(tendon, "motor_" + ROTOR_KEY))
    fingers = long_fingers(data)
    _tendon_thumb(get_value(data, "thumb", dict), tp, hp.links, hp.joints, hp.actuators,
                  hp.finger_joints)
    for f in sorted(fingers, key=lambda f: FINGERS.index(f["name"])):
        _tendon_finger(f, tp, p_len, hp.links, hp.joints, hp.actuators, hp.couplings,
                       hp.finger_joints)
    return assemble_spec(data, hp)


def _tendon_thumb(th: dict, tp: _TendonDrive, links, joints, actuators, finger_joints) -> None:
    """The thumb: a CMC abduction servo, CMC flexion and IP on tendons."""
    tb, tt, tw = get_length(th, "base"), get_length(th, "top"), get_length(th, "width")
    tarm = get_value(th, "moment_arm_m", dict)
    for k in ("cmc_flex", "ip"):
        get_positive(tarm, k)
    tm = get_value(th, "masses_kg", dict)
    cmc_xyz = get_vec(th, "base_xyz_m")
    cmc_rpy = tuple(math.radians(a) for a in get_vec(th, "base_rpy_deg"))
    links += [Link("thumb_cmc", 0.01, (0.0, 0.0, 0.0), (0.02, 0.02, 0.02)),
              seg_link("thumb_base", tb, tw, get_value(tm, "base")),
              seg_link("thumb_top", tt, tw * 0.9, get_value(tm, "top"))]
    lo, hi = get_range(th, "cmc_abd")
    joints.append(Joint("thumb_cmc_abd", "revolute", "palm", "thumb_cmc", cmc_xyz, cmc_rpy,
                        (0.0, 0.0, 1.0), lo, hi, min(tp.v_cap, get_value(tp.servo, "speed_rad_s")), tp.a_max,
                        get_value(tp.servo, "peak_torque_nm")))
    lo, hi = get_range(th, "cmc_flex")
    joints.append(Joint("thumb_cmc_flex", "revolute", "thumb_cmc", "thumb_base", (0.0, 0.0, 0.0),
                        axis=(-1.0, 0.0, 0.0), lower=lo, upper=hi,
                        velocity=tp.speed(get_value(tarm, "cmc_flex")), acceleration=tp.a_max,
                        effort=tp.tau_peak * tp.eff / tp.spool * get_value(tarm, "cmc_flex")))
    lo, hi = get_range(th, "ip")
    joints.append(Joint("thumb_ip", "revolute", "thumb_base", "thumb_top", (0.0, tb, 0.0),
                        axis=(-1.0, 0.0, 0.0), lower=lo, upper=hi,
                        velocity=tp.speed(get_value(tarm, "ip")), acceleration=tp.a_max,
                        effort=tp.tau_peak * tp.eff / tp.spool * get_value(tarm, "ip")))
    tl, tj = tip("thumb", "thumb_top", tt, tw * 0.9)
    links.append(tl)
    joints.append(tj)
    actuators += [
        Actuator("thumb_cmc_abd", "servo", "thumb_cmc_abd",
                 (("thumb_cmc_abd", get_value(tp.servo, "gear_ratio")),), get_value(tp.servo, "speed_rad_s"),
                 get_value(tp.servo, "peak_torque_nm"), 1.0),
        Actuator("thumb_cmc_flex", "tendon", "thumb_cmc_flex",
                 (("thumb_cmc_flex", get_value(tarm, "cmc_flex") / tp.spool),), tp.w_motor, tp.tau_peak,
                 tp.eff, tp.spool, rotor_inertia_kg_m2=tp.rotor),
        Actuator("thumb_ip", "tendon", "thumb_ip", (("thumb_ip", get_value(tarm, "ip") / tp.spool),),
                 tp.w_motor, tp.tau_peak, tp.eff, tp.spool,
                 rotor_inertia_kg_m2=tp.rotor),
    ]
    finger_joints.append(("thumb", ("thumb_cmc_abd", "thumb_cmc_flex", "thumb_ip")))


def _tendon_finger(f: dict, tp: _TendonDrive, p_len: float, links, joints, actuators,
                   couplings, finger_joints) -> None:
    """A long finger: an MCP abduction servo, MCP flexion on one tendon, PIP and DIP on
    another (the DIP coupled to the PIP)."""
    n = f["name"]
    lb, lm, lt, w = get_length(f, "base"), get_length(f, "middle"), get_length(f, "top"), get_length(f, "width")
    arm = get_value(f, "moment_arm_m", dict)
    ms = get_value(f, "masses_kg", dict)
    ratio = get_value(f, "dip_ratio")
    if not 0.0 < ratio <= 1.5:
        raise InputError(f"{n}: dip_ratio must be in (0, 1.5] (the seed uses 0.667, 0.556, 0.333)")
    links += [Link(f"{n}_knuckle", 0.005, (0.0, 0.0, 0.0), (0.01, 0.01, 0.01)),
              seg_link(f"{n}_base", lb, w, get_value(ms, "base")),
              seg_link(f"{n}_middle", lm, w * 0.95, get_value(ms, "middle")),
              seg_link(f"{n}_top", lt, w * 0.9, get_value(ms, "top"))]
    lo_a, hi_a = get_range(f, "abd")
    joints.append(Joint(f"{n}_mcp_abd", "revolute", "palm", f"{n}_knuckle",
                        (get_value(f, "mcp_x_m"), p_len, float(f.get("mcp_z_m", 0.0))),
                        axis=(0.0, 0.0, 1.0), lower=lo_a,
                        upper=hi_a, velocity=min(tp.v_cap, get_value(tp.servo, "speed_rad_s")),
                        acceleration=tp.a_max, effort=get_value(tp.servo, "peak_torque_nm")))
    a_mcp, a_pip, a_dip = get_positive(arm, "mcp"), get_positive(arm, "pip"), get_positive(arm, "dip")
    # one tendon crosses the PIP and the DIP: its motor turns
    # (a_pip + ratio a_dip) / tp.spool per PIP radian
    a_pip_eff = a_pip + ratio * a_dip
    v_pip = tp.speed(a_pip_eff)
    for jn, parent, child, xyz, key, v, a in (
        ("mcp_flex", f"{n}_knuckle", f"{n}_base", (0.0, 0.0, 0.0), "mcp", tp.speed(a_mcp), a_mcp),
        ("pip", f"{n}_base", f"{n}_middle", (0.0, lb, 0.0), "pip", v_pip, a_pip),
        ("dip", f"{n}_middle", f"{n}_top", (0.0, lm, 0.0), "dip", ratio * v_pip, a_dip),
    ):
        lo, hi = get_range(f, key)
        joints.append(Joint(f"{n}_{jn}", "revolute", parent, child, xyz, axis=(-1.0, 0.0, 0.0),
                            lower=lo, upper=hi, velocity=v, acceleration=tp.a_max,
                            effort=tp.tau_peak * tp.eff / tp.spool * a))
    # the DIP follows the PIP: its range must hold ratio x the PIP's range
    pip, dip = joints[-2], joints[-1]
    if not (dip.lower <= ratio * pip.lower + 1e-12 and ratio * pip.upper <= dip.upper + 1e-12):
        raise InputError(f"{n}: dip range does not contain dip_ratio x pip range")
    couplings.append(LinearCoupling(f"{n}_dip", f"{n}_pip", ratio))
    tl, tj = tip(n, f"{n}_top", lt, w * 0.9)
    links.append(tl)
    joints.append(tj)
    actuators += [
        Actuator(f"{n}_abd", "servo", f"{n}_mcp_abd", ((f"{n}_mcp_abd", get_value(tp.servo, "gear_ratio")),),
                 get_value(tp.servo, "speed_rad_s"), get_value(tp.servo, "peak_torque_nm"), 1.0),
        Actuator(f"{n}_mcp", "tendon", f"{n}_mcp_flex", ((f"{n}_mcp_flex", a_mcp / tp.spool),),
                 tp.w_motor, tp.tau_peak, tp.eff, tp.spool,
                 rotor_inertia_kg_m2=tp.rotor),
        # one tendon crosses the PIP and the DIP
        Actuator(f"{n}_pip", "tendon", f"{n}_pip",
                 ((f"{n}_pip", a_pip / tp.spool), (f"{n}_dip", a_dip / tp.spool)),
                 tp.w_motor, tp.tau_peak, tp.eff, tp.spool,
                 rotor_inertia_kg_m2=tp.rotor),
    ]
    finger_joints.append((n, (f"{n}_mcp_abd", f"{n}_mcp_flex", f"{n}_pip", f"{n}_dip")))

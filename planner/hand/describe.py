"""A hand as its user reads it: ``cli.py hand``'s description (``format_hand``) and its
JSON object (``hand_dict``): joints with their limits, couplings, actuators."""

from __future__ import annotations

import numpy as np

from planner.hand.model import HandModel
from planner.hand.spec import LinearCoupling


def hand_dict(hand: HandModel) -> dict:
    """``hand --json``: what ``format_hand`` says, one JSON object (SI units: m and rad)."""
    def coupling(c) -> dict:
        if isinstance(c, LinearCoupling):
            return {"joint": c.joint, "source": c.source, "kind": "linear",
                    "ratio": c.ratio, "offset": c.offset}
        return {"joint": c.joint, "source": c.source, "kind": "mk5", "table": c.table,
                "finger": c.finger}

    return {
        "command": "hand", "name": hand.name, "description": hand.spec.description,
        "side": hand.side, "urdf_sha256": hand.urdf_sha256,
        "rail": bool(hand.spec.rail_enabled),
        "fingers": list(hand.fingers),
        "joints": [{"name": n, "lower": float(hand.lower[i]), "upper": float(hand.upper[i]),
                    "velocity": float(hand.velocity[i]),
                    "acceleration": float(hand.acceleration[i]),
                    "jerk": float(hand.jerk[i]), "stop_margin": float(hand.stop_margin[i]),
                    "unit": "m" if n in hand.rig_joints else "rad"}
                   for i, n in enumerate(hand.joint_names)],
        "couplings": [coupling(c) for c in hand.spec.couplings],
        "play": None if (p := hand.spec.play_posture) is None else {
            "reach_m": list(p.reach_m), "wrist_flex_rad": p.wrist_flex_rad,
            "wrist_dev_rad": p.wrist_dev_rad, "press_depth_m": p.press_depth_m},
        "actuators": [{"name": a.name, "kind": a.kind, "drives": a.drives,
                       "speed_rad_s": a.speed_rad_s, "peak_torque_nm": a.peak_torque_nm,
                       "efficiency": a.efficiency,
                       "rotor_inertia_kg_m2": a.rotor_inertia_kg_m2} for a in hand.actuators],
    }

def format_hand(hand: HandModel) -> str:
    """A readable description: DOF, joints with limits, couplings, actuators."""
    hand_dof = sum(1 for n in hand.joint_names if n not in hand.rig_joints)
    lines = [f"hand {hand.name}: {hand.spec.description}",
             f"  a {hand.side} hand, {hand_dof} hand joints "
             f"({hand_dof - len(hand.couplings)} independent)"
             + (f" + rig: {', '.join(hand.rig_joints)}" if hand.rig_joints else " (rail off)"),
             f"  urdf_sha256 {hand.urdf_sha256}",
             "  joints (lower..upper, max speed, max acceleration, max jerk):"]
    for i, n in enumerate(hand.joint_names):
        if n in hand.rig_joints:
            lines.append(f"    {n:16s} {hand.lower[i]:+.3f}..{hand.upper[i]:+.3f} m"
                         f"  {hand.velocity[i]:.2f} m/s  {hand.acceleration[i]:.1f} m/s^2"
                         f"  {hand.jerk[i]:.0f} m/s^3")
        else:
            lines.append(f"    {n:16s} {np.degrees(hand.lower[i]):+7.1f}..{np.degrees(hand.upper[i]):+7.1f} deg"
                         f"  {hand.velocity[i]:6.2f} rad/s  {hand.acceleration[i]:.0f} rad/s^2"
                         f"  {hand.jerk[i]:.3g} rad/s^3")
    p = hand.spec.play_posture
    if p is not None:
        lines.append(f"  play postures: reach {', '.join(f'{r:+.3f}' for r in p.reach_m)} m, wrist "
                     f"{np.degrees(p.wrist_flex_rad):+.1f} / {np.degrees(p.wrist_dev_rad):+.1f} deg, "
                     f"presses {1000 * p.press_depth_m:.1f} mm deep (bodies clear of the keys)")
    lines.append("  couplings:")
    for c in hand.spec.couplings:
        if isinstance(c, LinearCoupling):
            lines.append(f"    {c.joint} = {c.ratio:g} x {c.source}" + (f" + {c.offset:g}" if c.offset else ""))
        else:
            lines.append(f"    {c.joint} = q2({c.source}) - {c.source}  (Mk5 leverism, {c.table} {c.finger})")
    lines.append("  actuators (kind, drives, max speed, peak torque, efficiency):")
    for a in hand.actuators:
        lines.append(f"    motor.{a.name:14s} {a.kind:6s} {a.drives:16s} {a.speed_rad_s:6.1f} rad/s"
                     f"  {a.peak_torque_nm:.2f} N m  {a.efficiency:.0%}")
    return "\n".join(lines)

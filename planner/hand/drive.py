"""A hand file's ``[drive]`` table: each joint's jerk bound and its margin from its hard
stops, derived from the motor that drives it.

Jerk: a motor's torque follows a change of command with its mechanical time constant
``tau_m`` (first order: the data sheet's "mechanical time constant", line 15 of the
Faulhaber tables in seed 002): the steepest change it makes is its step response's
initial slope, a full step over one ``tau_m`` (followed within e^-n after n of them).
So a joint's acceleration may go from 0 to its limit no faster than over
``ramp_time_constants x tau_m`` of the motor driving it (the hand files: 1, the motor's
own limit): ``jerk = acceleration / (ramp_time_constants x tau_m)``. ``time_constant_ms``
gives ``tau_m`` by actuator kind ("tendon", "gear", "belt", "servo") or by actuator
name (a name wins over a kind); a joint that follows another by a coupling takes the
motor of the joint it follows.

Stop margin: the planner keeps every joint ``stop_margin_deg`` (revolute) or
``stop_margin_m`` (prismatic) inside its hard stops (a joint that follows another by a
coupling, none of its own: it moves only as its source does, whose margin keeps it off
the ends of its range) (``HandModel.plan_lower`` /
``plan_upper``); ``check`` counts the rows closer to a stop than that
(``joint_stop_margin``) and refuses, as before, the rows beyond a stop.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from planner.errors import InputError

DRIVE_TABLE = "drive"


def _number(d: dict[str, Any], key: str, positive: bool = True) -> float:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
            or v < 0.0 or (positive and v == 0.0):
        raise InputError(f"[{DRIVE_TABLE}] {key!r} must be a {'positive' if positive else 'non-negative'} "
                         f"number, got {v!r}")
    return float(v)


def drive_time_constants(data: dict[str, Any], joints, actuators, couplings) -> dict[str, float]:
    """The mechanical time constant (s) of the motor driving each movable joint, by name."""
    drive = data.get(DRIVE_TABLE)
    if not isinstance(drive, dict):
        raise InputError(f"missing table [{DRIVE_TABLE}] (jerk bounds and stop margins)")
    tc = drive.get("time_constant_ms")
    if not isinstance(tc, dict):
        raise InputError(f"[{DRIVE_TABLE}] needs time_constant_ms = {{ kind or motor = ms }}")
    out: dict[str, float] = {}
    for a in actuators:
        key = a.name if a.name in tc else a.kind
        if key not in tc:
            raise InputError(f"[{DRIVE_TABLE}] time_constant_ms names neither motor "
                             f"{a.name!r} nor its kind {a.kind!r}")
        tau = _number(tc, key) * 1e-3
        for j in (a.drives, *(n for n, _ in a.coefficients)):
            out.setdefault(j, tau)
    for _ in couplings:  # (a chain of couplings resolves in as many passes)
        for c in couplings:
            if c.source in out:
                out.setdefault(c.joint, out[c.source])
    return out


def apply_drive(data: dict[str, Any], joints, actuators, couplings) -> list:
    """``joints`` with their jerk bounds and stop margins from the ``[drive]`` table."""
    drive = data.get(DRIVE_TABLE)
    taus = drive_time_constants(data, joints, actuators, couplings)
    ramp = _number(drive, "ramp_time_constants")
    margin_rad = math.radians(_number(drive, "stop_margin_deg", positive=False))
    margin_m = _number(drive, "stop_margin_m", positive=False)
    followers = {c.joint for c in couplings}
    out = []
    for j in joints:
        if not j.movable:
            out.append(j)
            continue
        if j.name not in taus:
            raise InputError(f"joint {j.name!r}: no motor drives it ([{DRIVE_TABLE}])")
        # (a joint that follows another by a coupling has its range from its law: its
        # source's margin keeps it off the ends of it)
        margin = 0.0 if j.name in followers else margin_m if j.kind == "prismatic" else margin_rad
        if math.isfinite(j.lower) and math.isfinite(j.upper) and 2 * margin >= j.upper - j.lower:
            raise InputError(f"joint {j.name!r}: stop margins leave no range")
        out.append(replace(j, jerk=j.acceleration / (ramp * taus[j.name]), stop_margin=margin))
    return out

"""The "Hand Mk5" hand (``kind = "mk5"``): five 2-phalanx fingers coupled by the Mk5 leverism.

Each finger has two revolute joints, both flexing about ``-x`` (positive
flexion bends the fingertip towards the palm side, ``-z``):

* ``<f>_q1`` -- the first phalanx about ``P0`` (the encoder joint, the one
  the finger's motor drives), range ``[0, q1_max]`` from the table;
* ``<f>_q2`` -- the *relative* angle of the second phalanx,
  ``q2(q1) - q1`` (:class:`~planner.hand.spec.Mk5Coupling`; ``q2`` of the
  seed is an absolute angle in the palm frame). Its URDF limits are the
  min/max of that function over ``[0, q1_max]`` widened by ``Q2_MARGIN_RAD``.

One forearm tendon motor per finger drives ``<f>_q1`` through the chain
motor -> crank ``q0`` -> ``q1`` (``planner.hand.mk5.qmot_of_q1``, which
for the Mk5 tables uses a documented linear stand-in for ``q0(q1)``).

Sizes (assumptions, stated in ``hands/mk5.toml``): the first phalanx is
``d = |P1 - P0|`` of the table (true mm, times the file's ``scale``, 1.0),
placed along the finger's +y axis (the 1.5 mm offset of ``P1`` from the
phalanx axis, 2.2-2.5 deg, is not modelled in the URDF); the second
phalanx length is not in the table and is ``second_phalanx_ratio x d``
(0.8). Mount, rail, forearm, wrist and palm are shared with every hand
(:func:`planner.hand.spec.start_hand`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InputError
from planner.hand import mk5
from planner.hand.builders.common import (
    assemble_spec,
    long_fingers,
    seg_link,
    start_hand,
    tip,
)
from planner.hand.builders.values import (
    get_length,
    get_value,
    get_vec,
    rotor_inertia,
)
from planner.hand.mk5_tables import MK5_TABLES, Mk5FingerParams
from planner.hand.spec import (
    FINGERS,
    ROTOR_KEY,
    Actuator,
    HandSpec,
    Joint,
    Link,
    Mk5Coupling,
)

Q2_MARGIN_RAD = 1e-4  # widening of the q2 joint range beyond the coupling's min/max
_SAMPLES = 4001  # grid over [0, q1_max] for the q2 range and the speed bounds


def _finger_law(p: Mk5FingerParams) -> dict[str, float]:
    """Range and bounds of the coupling and the motor ratio over ``q1 in [0, q1_max]``."""
    q1 = np.linspace(0.0, p.q1_max, _SAMPLES)
    rel = np.asarray(mk5.q2_of_q1(p, q1)) - q1
    slope = np.asarray(mk5.dq2_dq1(p, q1)) - 1.0
    # d(slope)/dq1 by finite differences of the analytic slope (for the acceleration bound)
    curv = np.gradient(slope, q1)
    ratio = np.abs(np.asarray(mk5.dqmot_dq1(p, q1), dtype=float))
    return {
        "q2_lo": float(rel.min()) - Q2_MARGIN_RAD,
        "q2_hi": float(rel.max()) + Q2_MARGIN_RAD,
        "slope_max": float(np.abs(slope).max()),
        "curv_max": float(np.abs(curv).max()),
        "ratio_max": float(ratio.max()),
    }


@dataclass(frozen=True)
class _Mk5Drive:
    """What every finger of an Mk5 hand file shares: the table, the phalanx sizes, the
    forearm motor and its tendon, the finger's speed and acceleration caps."""

    table: str
    scale: float
    ratio2: float
    w_motor: float
    tau_peak: float
    eff: float
    v_cap: float
    a_max: float
    rotor: float = 0.0  # the forearm motors' rotor inertia, kg m^2


def _drive(data: dict[str, Any]) -> _Mk5Drive:
    """The ``[mk5]``, ``[tendon]`` and ``[finger_speed]`` sections, checked."""
    m5 = get_value(data, "mk5", dict)
    table = get_value(m5, "table", str)
    if table not in MK5_TABLES:
        raise InputError(f"mk5 table {table!r} unknown; valid: {', '.join(MK5_TABLES)}")
    scale = get_value(m5, "scale")
    ratio2 = get_value(m5, "second_phalanx_ratio")
    if scale <= 0 or ratio2 <= 0:
        raise InputError("mk5: scale and second_phalanx_ratio must be positive")
    tendon = get_value(data, "tendon", dict)
    w_motor = get_value(tendon, "motor_speed_rad_s")
    tau_peak = get_value(tendon, "motor_peak_torque_nm")
    eff = get_value(tendon, "efficiency")
    if not 0 < eff <= 1:
        raise InputError("tendon efficiency must be in (0, 1]")
    if w_motor <= 0 or tau_peak <= 0:
        raise InputError("tendon motor speed and peak torque must be positive")
    fs = get_value(data, "finger_speed", dict)
    return _Mk5Drive(table, scale, ratio2, w_motor, tau_peak, eff,
                     get_value(fs, "velocity_cap_rad_s"), get_value(fs, "acceleration_rad_s2"),
                     rotor_inertia(tendon, "motor_" + ROTOR_KEY))


def build_mk5_hand(data: dict[str, Any]) -> HandSpec:
    """Build the Mk5 hand from its parsed TOML (see ``hands/mk5.toml``)."""
    hp = start_hand(data)
    p_len = get_length(get_value(data, "palm", dict), "length")
    d = _drive(data)
    by_name: dict[str, dict[str, Any]] = {f["name"]: f for f in long_fingers(data)}
    by_name["thumb"] = get_value(data, "thumb", dict)
    for n in FINGERS:
        fl, fj, c, a = _finger(n, by_name[n], p_len, d)
        hp.links += fl
        hp.joints += fj
        hp.couplings.append(c)
        hp.actuators.append(a)
        hp.finger_joints.append((n, (f"{n}_q1", f"{n}_q2")))
    return assemble_spec(data, hp)


def _finger(n: str, fd: dict[str, Any], p_len: float, d: _Mk5Drive
            ) -> tuple[list[Link], list[Joint], Mk5Coupling, Actuator]:
    """One finger: its two phalanges and pad, its q1 and q2 joints (limits from the
    leverism and the motor), the coupling and the finger's motor."""
    p = MK5_TABLES[d.table][n]
    if p.r_mot is None:
        raise InputError(f"mk5 table {d.table!r} has no r_mot: the motor map is undefined")
    law = _finger_law(p)
    l1 = d.scale * p.d_geom
    l2 = d.ratio2 * l1
    w = get_value(fd, "width_m")
    ms = get_value(fd, "masses_kg", dict)
    if n == "thumb":
        xyz = get_vec(fd, "base_xyz_m")
        rpy = tuple(math.radians(a) for a in get_vec(fd, "base_rpy_deg"))
    else:
        xyz = (get_value(fd, "mcp_x_m"), p_len, 0.0)
        rpy = (0.0, 0.0, 0.0)
    links = [seg_link(f"{n}_proximal", l1, w, get_value(ms, "proximal")),
             seg_link(f"{n}_distal", l2, 0.9 * w, get_value(ms, "distal"))]
    # motor-limited speed of q1 (the motor ratio is largest where the motor
    # turns fastest per q1 radian), then the mechanical cap
    v1 = min(d.v_cap, d.w_motor / law["ratio_max"])
    # q2 follows q1: its speed / acceleration limits are those the coupling
    # induces at the q1 limits (|s| v1 and |s| a1 + |s'| v1^2), so any q1
    # motion within q1's limits respects q2's
    v2 = law["slope_max"] * v1
    a2 = law["slope_max"] * d.a_max + law["curv_max"] * v1 * v1
    # effort: joint torque the motor can hold everywhere in the range
    e1 = d.tau_peak * d.eff / law["ratio_max"]
    e2 = e1 / law["slope_max"]
    joints = [
        Joint(f"{n}_q1", "revolute", "palm", f"{n}_proximal", xyz, rpy,
              axis=(-1.0, 0.0, 0.0), lower=0.0, upper=p.q1_max, velocity=v1,
              acceleration=d.a_max, effort=e1),
        Joint(f"{n}_q2", "revolute", f"{n}_proximal", f"{n}_distal", (0.0, l1, 0.0),
              axis=(-1.0, 0.0, 0.0), lower=law["q2_lo"], upper=law["q2_hi"], velocity=v2,
              acceleration=a2, effort=e2),
    ]
    tl, tj = tip(n, f"{n}_distal", l2, 0.9 * w)
    links.append(tl)
    joints.append(tj)
    c = Mk5Coupling(joint=f"{n}_q2", source=f"{n}_q1", table=d.table, finger=n)
    a = Actuator(name=n, kind="tendon", drives=f"{n}_q1", coefficients=(),
                 speed_rad_s=d.w_motor, peak_torque_nm=d.tau_peak, efficiency=d.eff,
                 radius_m=p.r_mot, mk5=c, rotor_inertia_kg_m2=d.rotor)
    return links, joints, c, a

"""The AGH "Mechanical Hand" (``kind = "agh"``, seed 002_c49be7b02b913253): four fingers of
two joints, the base joints paired on two worm-geared shafts, the end joints each geared.

Layout (``hands/agh.toml`` says what is the seed's and what is chosen): the base plate is
the palm; two shafts cross it (x) ``shaft_spacing_m`` apart, centred on ``palm_center``.
Each finger stands out of the plate's grasping face (its frame's +y along the palm
normal at zero) and flexes towards the other shaft (positive angles; the pad, on the
frame's -z side, faces the other pair). Joints per finger ``f``: ``f_base`` (joint A of
the seed, plate -> ``f_proximal``) and ``f_end`` (joint B, ``f_proximal -> f_distal``).

The paired base joints are a coupling: one actuator, two joints. ``middle_base`` follows
``index_base`` and ``ring_base`` follows ``thumb_base`` (``LinearCoupling`` ratio 1, a
URDF mimic); the shaft's motor drives the source, and by virtual work
(``HandModel.motor_torques``) carries the torque of both joints. Every motor turns
``gear_ratio`` (20) times per joint turn through its worm, with the worm's efficiency.

Fingers are the first four of the contract's names (``spec.FINGERS``), in that order:
``check`` reads the fingertips in that order (see ``hands/agh.toml``).
"""

from __future__ import annotations

import math
from typing import Any

from planner.errors import InputError
from planner.hand.builders.common import (
    assemble_spec,
    start_hand,
    tip,
)
from planner.hand.builders.values import (
    get_length,
    get_positive,
    get_range,
    get_value,
    rotor_inertia,
)
from planner.hand.spec import (
    FINGERS,
    Actuator,
    HandSpec,
    Joint,
    LinearCoupling,
    Link,
)

AGH_FINGERS = FINGERS[:4]
# (finger, shaft, x sign): the near shaft (wrist end) carries thumb and ring, the far one
# index (opposite the thumb) and middle (opposite the ring)
_LAYOUT = (("thumb", "near", -1.0), ("index", "far", -1.0), ("middle", "far", 1.0),
           ("ring", "near", 1.0))
_PAIRS = {"near": ("thumb", "ring"), "far": ("index", "middle")}  # (source, follower)
# finger frame in the palm frame: +y along the palm normal (palm -z); the pad's side (-z)
# towards the other shaft. Far shaft: x_f = x, y_f = -z, z_f = +y  -> rpy (-90, 0, 0);
# near shaft: x_f = -x, y_f = -z, z_f = -y -> rpy (-90, 0, 180).
_RPY = {"far": (-math.pi / 2, 0.0, 0.0), "near": (-math.pi / 2, 0.0, math.pi)}


def _pair3(d: dict[str, Any], key: str) -> tuple[float, float]:
    v = get_value(d, key, list)
    if len(v) != 2 or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                              and math.isfinite(x) and x > 0 for x in v):
        raise InputError(f"{key!r} must be 2 positive numbers (base element, end element)")
    return float(v[0]), float(v[1])


def _motor(d: dict[str, Any], key: str) -> tuple[float, float, float]:
    """A motor table's peak torque (N m), speed (rad/s) and rotor inertia (kg m^2)."""
    m = get_value(d, key, dict)
    return get_positive(m, "peak_torque_nm"), get_positive(m, "speed_rad_s"), rotor_inertia(m)


def build_agh_hand(data: dict[str, Any]) -> HandSpec:
    """Build the AGH hand from its parsed TOML (see ``hands/agh.toml``)."""
    hp = start_hand(data)
    links, joints, actuators, couplings = hp.links, hp.joints, hp.actuators, hp.couplings
    palm = get_value(data, "palm", dict)
    p_len, p_thk = get_length(palm, "length"), get_value(palm, "thickness_m")
    g = get_value(data, "agh", dict)
    spacing, x_off = get_positive(g, "shaft_spacing_m"), get_positive(g, "finger_x_m")
    width = get_positive(g, "finger_width_m")
    (l_ab, l_bc), (c_ab, c_bc), (m_ab, m_bc) = (_pair3(g, k) for k in ("lengths_m", "com_m",
                                                                       "masses_kg"))
    if c_ab > l_ab or c_bc > l_bc:
        raise InputError("com_m must lie on each element (at most its length)")
    if spacing >= p_len:
        raise InputError("shaft_spacing_m must be shorter than the palm")
    ratio, eff = get_positive(g, "gear_ratio"), get_positive(g, "gear_efficiency")
    if eff > 1:
        raise InputError("gear_efficiency must be in (0, 1]")
    base_tau, base_w, base_rotor = _motor(g, "base_motor")
    end_tau, end_w, end_rotor = _motor(g, "end_motor")
    acc = get_positive(g, "acceleration_rad_s2")
    ranges = {"base": get_range(g, "base"), "end": get_range(g, "end")}

    shaft_y = {"near": p_len / 2 - spacing / 2, "far": p_len / 2 + spacing / 2}
    for f, shaft, sx in _LAYOUT:
        prox, dist = f"{f}_proximal", f"{f}_distal"
        links += [Link(prox, m_ab, (0.0, c_ab, 0.0), (width, l_ab, 0.8 * width)),
                  Link(dist, m_bc, (0.0, c_bc, 0.0), (0.9 * width, l_bc, 0.72 * width))]
        for jn, parent, child, xyz, rpy, key, tau, w in (
            (f"{f}_base", "palm", prox, (sx * x_off, shaft_y[shaft], -p_thk / 2), _RPY[shaft],
             "base", base_tau, base_w),
            (f"{f}_end", prox, dist, (0.0, l_ab, 0.0), (0.0, 0.0, 0.0), "end", end_tau, end_w),
        ):
            lo, hi = ranges[key]
            # a paired base joint carries half its shaft's torque when both fingers load it
            joints.append(Joint(jn, "revolute", parent, child, xyz, rpy, (-1.0, 0.0, 0.0),
                                lo, hi, w / ratio, acc, tau * ratio * eff))
        tl, tj = tip(f, dist, l_bc, 0.9 * width)
        links.append(tl)
        joints.append(tj)
        actuators.append(Actuator(f"{f}_end", "gear", f"{f}_end", ((f"{f}_end", ratio),), end_w,
                                  end_tau, eff, rotor_inertia_kg_m2=end_rotor))
        hp.finger_joints.append((f, (f"{f}_base", f"{f}_end")))
    for shaft, (src, dep) in _PAIRS.items():
        couplings.append(LinearCoupling(f"{dep}_base", f"{src}_base", 1.0))
        actuators.append(Actuator(f"shaft_{shaft}", "gear", f"{src}_base",
                                  ((f"{src}_base", ratio),), base_w, base_tau, eff,
                                  rotor_inertia_kg_m2=base_rotor))
    return assemble_spec(data, hp)

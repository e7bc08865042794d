"""How hard a move may accelerate the hand where its motors hold it against its inertia
and gravity (``rail_acceleration_cap``, ``path_acceleration_cap``; the moves' and the
arm's: ``planner.play.moves``, ``planner.play.armmoves``, ``planner.play.rest``)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from planner.errors import PlannerError
from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity

RAIL_TORQUE_SHARE = 0.7  # the rail accelerates at most so hard that the motors holding the
# hand against its inertia and gravity use 70 % of their capacity: the rest for the fingers'
# own moves, whose reactions on the wrist reach 0.5 N m in the rows (at 90 % the check's
# inverse dynamics found 8 of 71 songs 3-16 % over the wrist deviation motor's 2 N m).
# Without it the default hand's 40 m/s^2 rail asks that motor 1.19 x its capacity (the
# MuJoCo replay of `leaps` saturates it for 350 ms: docs/history/physics-replay.md)


def rail_acceleration_cap(hand: HandModel, postures) -> float:
    """The largest rail acceleration (m/s^2) at which, in each of ``postures`` (the hand
    still otherwise), every motor stays within ``RAIL_TORQUE_SHARE`` of its capacity
    (``path_acceleration_cap`` along the rail alone)."""
    unit = np.zeros(hand.n)
    unit[hand.index["rail"]] = 1.0
    return path_acceleration_cap(hand, postures, unit)


def path_acceleration_cap(hand: HandModel, postures, dq: np.ndarray) -> float:
    """The largest acceleration ``s''`` of a move along ``dq`` (every joint, q'' = s'' dq)
    at which, in each of ``postures``, every motor's torque (inverse dynamics, RNEA:
    gravity plus the hand's inertia so accelerated, through the actuator model) stays
    within ``RAIL_TORQUE_SHARE`` of its capacity (peak torque or tendon force:
    ``planner.hand.tendon.actuator_capacity``)."""
    m = hand.pin_model
    data = m.createData()
    cap = RAIL_TORQUE_SHARE * actuator_capacity(hand).torque_nm
    vi = hand.pin_v_idx
    best = np.inf
    seen = set()
    v = np.zeros(m.nv)  # (no speed, no acceleration; and the unit acceleration along dq)
    unit = np.zeros(m.nv)
    unit[vi] = dq
    for q in postures:
        qp = hand.pin_q(q)
        tau_g = pin.rnea(m, data, qp, v, v)[vi]
        tau_1 = pin.rnea(m, data, qp, v, unit)[vi] - tau_g
        # (a posture whose torques and transmission equal one's before gives its motor
        # torques: skipped. The arm's line: the rail and the reach, prismatic at the
        # root, move no joint's torque, to the bit)
        key = (hand.transmission_key(q), tau_g.tobytes(), tau_1.tobytes())
        if key in seen:
            continue
        seen.add(key)
        g, k = hand.motor_torques(q, tau_g), hand.motor_torques(q, tau_1)
        room = cap - np.abs(g)
        if np.any(room <= 0.0):
            raise PlannerError(f"hand {hand.name!r}: a motor is past {RAIL_TORQUE_SHARE:.0%} "
                               "of its capacity holding the hand still")
        with np.errstate(divide="ignore"):
            best = min(best, float(np.min(np.where(np.abs(k) > 1e-12, room / np.abs(k),
                                                   np.inf))))
    return best

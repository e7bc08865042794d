"""Tendon tensions: seed 004's statics through the hand's transmissions, and the
cable's design force as a bound beside each motor's peak torque.

Seed 004 (``004_414065b0ee7254f4.txt``, "MSDI Force Analysis") turns a cable's
tension into joint moments: a cable of tension ``T`` leaving a joint at a moment
arm ``L`` and an angle ``delta`` turns it with ``M = L T cos(delta)`` (its
"Moment" line). A hand file gives the perpendicular arm ``a = L cos(delta)`` of
each tendon at each joint it crosses (``moment_arm_m``; the default hand's PIP
tendon is routed through the MCP's axis: no moment there, as its transmission
says), so a cable of tension ``T`` at the joints gives ``tau_j = a_j T``.

Through a coupling the joints a tendon crosses move together (the DIP follows the
PIP by a linkage, the Mk5 phalanges by the leverism): by virtual work over that
motion ``S = dq / dq_drive`` (``HandModel.dq_dindependent``) the tension at the
joints for joint torques ``tau`` is

    T_joint = (S^T tau) / (dl / dq_drive),   dl / dq_drive = sum_j a_j S_j

(the linkage carries the rest of each joint's torque). Seed 004 assumes
frictionless cables; seed 000 loses 50 % in the tendons (line 80), so the motor's
spool pulls ``T = T_joint / efficiency``: the highest tension along the cable, and
exactly ``tau_motor / r`` with ``tau_motor = HandModel.motor_torques`` and ``r``
the spool (pulley) radius. That spool tension is what the cable's design force
bounds (seed 000, line 96: 40 N, PBO 0.25 mm): ``|tau_motor| <= F r``, a linear
bound on the same motor-torque rows the planner already constrains, so the
capacity of a tendon motor is ``min(peak torque, F r)`` (``ActuatorCapacity``).

Sign: a positive tension pulls the flexor side. A tendon motor's spool winds the
antagonist (extensor) in the other sense; a negative tension is carried by it,
the same cable, bounded by the same force.

The planner (the atlas's press forces, the catch's grasp QP) and the check import
the bound from here.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from planner.hand.model import HandModel

MOTOR_TORQUE = "motor torque"
TENDON_FORCE = "tendon force"
GEAR = "gear"  # a geared motor's torque through its gear (the wrist)


@dataclass(frozen=True)
class ActuatorCapacity:
    """What each motor of a hand can hold (motor order of ``HandModel.motor_names``).

    ``tendon_torque_nm`` is the motor torque at which its tendon reaches the
    design force at the spool (``F r``; inf for a motor that pulls no tendon).
    """

    motor_names: tuple[str, ...]
    peak_torque_nm: np.ndarray
    tendon_torque_nm: np.ndarray
    kinds: tuple[str, ...]

    @property
    def torque_nm(self) -> np.ndarray:
        """The motor torque each actuator can hold: the smaller of the two bounds (N m)."""
        return np.minimum(self.peak_torque_nm, self.tendon_torque_nm)

    def limiting(self, m: int) -> str:
        """The part that sets motor ``m``'s capacity: tendon force, gear or motor torque."""
        if self.tendon_torque_nm[m] < self.peak_torque_nm[m]:
            return TENDON_FORCE
        return GEAR if self.kinds[m] == "gear" else MOTOR_TORQUE

    def part(self, m: int) -> str:
        """``limiting(m)`` with the motor it belongs to, e.g. 'tendon force (motor.index_mcp)'."""
        return f"{self.limiting(m)} (motor.{self.motor_names[m]})"


@cache
def actuator_capacity(hand: HandModel) -> ActuatorCapacity:
    """The capacity of every motor of ``hand`` (cached per hand object)."""
    tendon = np.array([a.tendon_force_n * a.radius_m if a.tendon_force_n is not None
                       else np.inf for a in hand.actuators])
    tendon.setflags(write=False)
    peak = np.array(hand.motor_peak_torque, dtype=float)
    peak.setflags(write=False)
    return ActuatorCapacity(hand.motor_names, peak, tendon,
                            tuple(a.kind for a in hand.actuators))


def tendon_motors(hand: HandModel) -> np.ndarray:
    """Indices (motor order) of the motors that pull a tendon."""
    return np.array([m for m, a in enumerate(hand.actuators) if a.tendon_force_n is not None],
                    dtype=int)


@dataclass(frozen=True)
class TendonTensions:
    """The tendons' tensions for one set of joint torques (tendon order of
    ``tendon_motors``; names are the motors'). ``tension_n`` is at the spool (the
    highest along the cable, what ``design_force_n`` bounds), ``joint_end_n`` where
    the cable meets the joints (``efficiency x tension_n``); signed as the module says."""

    names: tuple[str, ...]
    tension_n: np.ndarray
    joint_end_n: np.ndarray
    design_force_n: np.ndarray

    @property
    def load(self) -> np.ndarray:
        """|tension| / design force of each tendon (1 = at its design force)."""
        return np.abs(self.tension_n) / self.design_force_n

    @property
    def ok(self) -> bool:
        return bool(np.all(self.load <= 1.0))

    def worst(self) -> tuple[str, float]:
        """The most loaded tendon and its |tension| at the spool (N)."""
        k = int(np.argmax(self.load))
        return self.names[k], float(abs(self.tension_n[k]))


def spool_tensions_n(hand: HandModel, motor_torques_nm: np.ndarray) -> np.ndarray:
    """Spool tensions (N) of the tendons from motor torques (..., n_motor): tau_m / r."""
    idx = tendon_motors(hand)
    r = np.array([hand.actuators[m].radius_m for m in idx])
    return np.asarray(motor_torques_nm, dtype=float)[..., idx] / r


def tendon_tensions(hand: HandModel, q: np.ndarray, tau_joint: np.ndarray) -> TendonTensions:
    """Every tendon's tension holding joint torques ``tau_joint`` (N m) at ``q``."""
    idx = tendon_motors(hand)
    spool = spool_tensions_n(hand, hand.motor_torques(np.asarray(q, dtype=float),
                                                      np.asarray(tau_joint, dtype=float)))
    eff = np.array([hand.actuators[m].efficiency for m in idx])
    force = np.array([hand.actuators[m].tendon_force_n for m in idx], dtype=float)
    return TendonTensions(tuple(hand.motor_names[m] for m in idx), spool, eff * spool, force)

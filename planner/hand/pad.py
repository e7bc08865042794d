"""The palm's pad: one definition of how far the palm gives while it stops a ball, read
from the hand file's ``[palm]`` by the catch planner, by ``check``'s ball stop
(``planner.check.ballstop``) and by ``simulate``'s palm-ball contact.

* ``pad_give_m``: how far the pad yields while it stops a ball landing at up to
  ``pad_speed_m_s`` relative to the palm. The planner and the check model the stop as a
  constant deceleration over the give (``planner.check.ballstop``); the physics replay
  models the pad as a critically damped contact (MuJoCo's solref, ``contact_time_s``)
  whose deepest compression at the rated speed is the give.
* A hand file that names no pad: the planner and the check assume ``ASSUMED_PAD_GIVE_M``
  (what they assumed before hand files declared the pad) and the replay's palm stays
  rigid (MuJoCo's hard contact) -- as before the pad was declared.

A critically damped contact (dampratio 1, time constant tau: stiffness 1/tau^2, damping
2/tau per unit mass) meeting a ball at speed v compresses by x(t) = v t exp(-t/tau), at
most v tau / e at t = tau; so tau = e give / speed puts the deepest compression at the
rated speed on the give, and a slower ball compresses less (no rebound at any speed:
critical damping).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from planner.errors import InputError

# The catch planner's and check's pad before hand files declared one (the give the soft
# stop and the check's stopping force were designed with: 2 cm of rubber on the palm).
ASSUMED_PAD_GIVE_M = 0.02


@dataclass(frozen=True)
class PalmPad:
    """A declared palm pad: its give (m) at its rated landing speed (m/s)."""

    give_m: float
    speed_m_s: float

    def contact_time_s(self) -> float:
        """The critically damped contact's time constant (s) whose deepest compression at
        ``speed_m_s`` is ``give_m``: e give / speed."""
        return math.e * self.give_m / self.speed_m_s


def palm_pad(data: dict[str, Any]) -> PalmPad | None:
    """The hand file's pad (``[palm] pad_give_m`` and ``pad_speed_m_s``, both or neither),
    None where it names none."""
    palm = data.get("palm")
    if not isinstance(palm, dict) or ("pad_give_m" not in palm and "pad_speed_m_s" not in palm):
        return None
    vals = []
    for key in ("pad_give_m", "pad_speed_m_s"):
        v = palm.get(key)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise InputError(f"palm.{key} must be a positive number (the pad's give and its rated "
                             f"landing speed go together), got {v!r}")
        vals.append(float(v))
    return PalmPad(*vals)


def pad_give_m(pad: PalmPad | None) -> float:
    """The give the planner and the check stop a ball over (m): the declared pad's, else
    ``ASSUMED_PAD_GIVE_M``."""
    return ASSUMED_PAD_GIVE_M if pad is None else pad.give_m

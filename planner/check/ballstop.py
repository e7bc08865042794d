"""How a caught ball is stopped and carried on the palm: one definition, used by ``check``
(``planner.check.ball``) and by the catch planner (``planner.catch.plan.stopping`` and its
self-check) alike.

* The pad. The ball meets the palm with a velocity ``v_rel`` relative to the palm target
  (palm_center + radius * normal: where the ball's centre rides). The padded palm gives
  the hand's pad give d (``HandModel.pad_give_m``: the hand file's ``[palm] pad_give_m``,
  ``planner.hand.pad``) and takes that relative velocity to zero at a constant
  deceleration: it lasts ``pad_time_s`` = 2 d / |v_rel| and the force of the hand on the
  ball meanwhile is ``pad_force_n`` = m (a_palm - |v_rel| v_rel / (2 d) - g), a_palm the
  palm target's own acceleration then. A palm that moves along the ball's path when they
  meet (the soft catch) makes |v_rel|, and this force with its square, smaller.
* Riding. Afterwards the ball moves with the palm target: the hand's force on it is
  m (a - g), a the target's acceleration (``ride_force_n``), while the hand brings it to
  rest and holds it.
* Staying on the palm. Until the fingers hold it, that force must lie inside the palm
  pad's friction cone (rubber, mu = ``PALM_MU``): ``cone_margin_n`` >= 0.
"""

from __future__ import annotations

import math

import numpy as np

from planner.hand.model import GRAVITY_WORLD

PALM_MU = 0.8  # seed (David): friction coefficient of the rubber pads


def pad_time_s(v_rel: np.ndarray, give_m: float) -> float:
    """How long the pad takes to stop the relative velocity ``v_rel``: 2 d / |v_rel| (0 for
    a ball at rest on the palm)."""
    speed = float(np.linalg.norm(v_rel))
    return 2.0 * give_m / speed if speed > 0 else 0.0


def pad_force_n(mass_kg: float, v_rel: np.ndarray, a_palm: np.ndarray | None,
                give_m: float) -> np.ndarray:
    """The hand's force on the ball (N) while the pad stops ``v_rel`` over ``give_m``:
    m (a_palm - |v_rel| v_rel / (2 d) - g)."""
    v = np.asarray(v_rel, dtype=float)
    a = np.zeros(3) if a_palm is None else np.asarray(a_palm, dtype=float)
    return mass_kg * (a - float(np.linalg.norm(v)) * v / (2.0 * give_m) - GRAVITY_WORLD)


def ride_force_n(mass_kg: float, a_palm: np.ndarray) -> np.ndarray:
    """The hand's force on a ball riding the palm target at acceleration ``a_palm``: m (a - g)."""
    return mass_kg * (np.asarray(a_palm, dtype=float) - GRAVITY_WORLD)


def cone_margin_n(force_n: np.ndarray, normal: np.ndarray, mu: float = PALM_MU) -> float:
    """mu F_n - |F_t| of the hand's force on the ball against the palm's normal (N): >= 0
    inside the friction cone (the ball stays on the palm), < 0 when it would slide off or
    the palm would have to pull it."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    f = np.asarray(force_n, dtype=float)
    fn = float(f @ n)
    return mu * fn - float(np.linalg.norm(f - fn * n))


def cone_half_angle_deg(mu: float = PALM_MU) -> float:
    return math.degrees(math.atan(mu))

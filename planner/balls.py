"""The balls a catch is planned for (``Ball``, ``BALLS``), shared by the catch planner and
the readers of a catch file (``planner.check``, ``planner.simulate``): the file's ``ball``
(spec section 4) has its radius and mass but not its inertia, which ``file_inertia_ratio``
gives (one definition for the check's roll rule and the physics replay's ball)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InputError

RHO_AIR = 1.204
"""Density of air, kg/m^3 (20 degC, 101.325 kPa)."""
_SAME_BALL_REL = 1e-9  # a file's radius and mass are its ball's (written as floats: repr)


def finite_float(name: str, value: Any) -> float:
    if isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name} must be a number, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise InputError(f"{name} must be finite, got {x}")
    return x




@dataclass(frozen=True)
class Ball:
    """A ball: SI units, ``drag_coefficient`` is the sphere's Cd (0 for a vacuum),
    ``inertia_ratio`` its moment of inertia about its centre over m R^2 (2/5 a solid ball,
    2/3 a thin shell): how fast it rolls on the palm (``planner.check.ballroll``)."""

    name: str
    mass_kg: float
    radius_m: float
    drag_coefficient: float
    inertia_ratio: float = 0.4  # (a solid ball, as a baseball's or a golf ball's nearly is)

    def __post_init__(self) -> None:
        for attr in ("mass_kg", "radius_m", "drag_coefficient", "inertia_ratio"):
            value = finite_float(f"ball {self.name!r} {attr}", getattr(self, attr))
            object.__setattr__(self, attr, value)
        if self.mass_kg <= 0 or self.radius_m <= 0 or self.drag_coefficient < 0 \
                or not 0.0 < self.inertia_ratio <= 2.0 / 3.0:
            raise InputError(
                f"ball {self.name!r}: need mass_kg > 0, radius_m > 0, drag_coefficient >= 0, "
                f"0 < inertia_ratio <= 2/3 (got {self.mass_kg}, {self.radius_m}, "
                f"{self.drag_coefficient}, {self.inertia_ratio})"
            )

    @property
    def area_m2(self) -> float:
        """Cross-section, m^2."""
        return math.pi * self.radius_m**2

    @property
    def drag_per_m(self) -> float:
        """k = 0.5 rho_air Cd A / m, 1/m: the drag deceleration is k |v|^2."""
        return 0.5 * RHO_AIR * self.drag_coefficient * self.area_m2 / self.mass_kg


TENNIS_INERTIA = 0.61  # a tennis ball's I / (m R^2) (its shell: see BALLS["tennis"])

BALLS: dict[str, Ball] = {
    # ITF ball: 56.0-59.4 g, 6.54-6.86 cm; Cd ~0.55 for a new ball at 10-30 m/s. A hollow
    # rubber core (wall ~3.2 mm) under felt: a thick uniform shell, I = 2/5 m (R^5 - a^5) /
    # (R^3 - a^3) with R = 33.5, a = 30.3 mm: 0.61 m R^2 (between a solid ball's 0.4 and a
    # thin shell's 0.67)
    "tennis": Ball("tennis", 0.057, 0.067 / 2, 0.55, TENNIS_INERTIA),
    # MLB ball: 142-149 g, 73-75 mm; Cd ~0.35 is a typical value (it ranges 0.3-0.5).
    "baseball": Ball("baseball", 0.145, 0.074 / 2, 0.35),
    # The seed's ball: 2.5 in = 63.5 mm diameter. The seed gives no mass: we assume
    # 57 g (a tennis ball: its shell's inertia too) and Cd 0.5 (a smooth sphere at moderate Re).
    "seed": Ball("seed", 0.057, 0.0635 / 2, 0.5, TENNIS_INERTIA),
    # Golf ball (Rules of Golf, Equipment Rules: at most 45.93 g, at least 42.67 mm); Cd ~0.25,
    # typical of a dimpled ball. The seed's 2.5 in ball scaled to a true-size hand (the 1.5x
    # hand's ball / 1.5 = 42.3 mm): the ball the mk5 (seed 003, true size) catches.
    "golf": Ball("golf", 0.04593, 0.04267 / 2, 0.25),
    # The seed's ball in a vacuum: k = 0.
    "vacuum": Ball("vacuum", 0.057, 0.0635 / 2, 0.0, TENNIS_INERTIA),
}


def get_ball(ball: Ball | str | None) -> Ball:
    """A ``Ball`` from a Ball, a name in ``BALLS``, or None (the seed's ball)."""
    if ball is None:
        return BALLS["seed"]
    if isinstance(ball, Ball):
        return ball
    if isinstance(ball, str):
        try:
            return BALLS[ball]
        except KeyError:
            raise InputError(
                f"unknown ball {ball!r}; valid balls: {', '.join(sorted(BALLS))}"
            ) from None
    raise InputError(
        f"ball must be a Ball or one of {', '.join(sorted(BALLS))}, got {type(ball).__name__}"
    )


def file_inertia_ratio(meta: dict[str, Any]) -> float:
    """I / (m R^2) of a catch file's ball: the spec's ``ball`` (radius, mass) has none, so
    the ball the plan names (``catch.throw.ball``, a name in ``BALLS``) when its radius and
    mass are the file's, else the default ball's (``get_ball(None)``: the seed's)."""
    c = meta.get("catch")
    throw = c.get("throw") if isinstance(c, dict) else None
    name = throw.get("ball") if isinstance(throw, dict) else None
    b = meta.get("ball")
    named = BALLS.get(name) if isinstance(name, str) else None
    if named is not None and isinstance(b, dict) and all(
            isinstance(b.get(k), (int, float)) and math.isclose(
                float(b[k]), v, rel_tol=_SAME_BALL_REL)
            for k, v in (("radius", named.radius_m), ("mass", named.mass_kg))):
        return named.inertia_ratio
    return get_ball(None).inertia_ratio

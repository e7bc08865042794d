"""The palm-up catch (issue 31, item 4): where every other plan of a throw loses the ball to
the roll rule (``planner.check.ballroll``: it rolls off the palm's wrist side before the
wrist's turn levels the palm), the palm meets the ball turned up, past facing it, about the
wrist's flexion axis -- as a person catches a short or steep throw palm up.

Why it holds (``docs/history/2026-12-07-catch-palmup.md``): a palm that faces the ball of a
short flat throw stands steep (0 m / 25 deg / 1.0 m: its normal 67 deg from up, the wrist
below the fingers), so the landed ball rolls down towards the wrist under gravity while the
wrist's turn levels the palm, and keeps that speed on the level palm. Turned up by a tilt
beta past facing, the palm is beta less steep when the ball lands (gravity's pull towards
the wrist 5/7 g sin(steepness)), and the ball's own speed along it, |v| sin(beta), points
towards the fingers (a palm turned up receives the ball moving towards its finger side,
where the fingers and the palm's cup stop it; the roll rule counts no roll that way). The
rig's reach axis puts the tilted palm on the ball's path (``find_intercept_square``: the
arm alone places the ball on a tilted palm at few tilts); the soft stop, the turn, the
self-check and the roll rule are the planner's as for any plan. The tilt is bounded by the
palm's friction cone: the pad's stopping force must stay within it, and the larger the tilt
the larger the ball's speed along the palm it must take out (measured, 0 m / 25 deg /
1.0 m: the stop leaves the cone from 50 deg). A tilt that keeps the ball on the palm but is
too fast to stop for the planner's stops is given the stop bound and the stop optimised on
its rows (``planner.stop_stages``; ``docs/history/2026-12-07-catch-roll2.md``: the steep
and flat long throws, facing the ball both rolled off and too fast to stop).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from planner.catch.plan.intercept import Wrist
from planner.catch.plan.reasons import CatchReason, reasons_text
from planner.catch.plan.results import CatchPlan
from planner.catch.plan.stopping import CONTACT_SHARES, StopGrid
from planner.hand.model import GRAVITY_WORLD

PALM_UP_TILTS_DEG = (20.0, 25.0, 30.0, 35.0, 40.0)  # how far the palm is turned up past
# facing the ball, tried in this order (the least first: the plan nearest the facing catch).
# 20 deg is the first beyond the soft stop's own search (TILTS_FINE_DEG: to 15 deg, for the
# motors' load); to 40 deg: further up the pad's stop leaves the palm's friction cone (mu
# 0.8: it must take out the ball's speed along the palm, |v| sin(tilt); measured, 0 m / 25
# deg / 1.0 m leaves it by 2.9 N at 50 deg, 0 m / 20 deg / 1.0 m by 0.2-0.6 N from 25 deg);
# 5 deg apart as the coarse stop's tilts (the least tilt that holds: the palm nearest
# facing the ball)


def palm_up_sign(wrist: Wrist) -> float:
    """The sign of the flexion (rad about ``wrist.e_f``) that turns the palm's normal
    towards up (against gravity) from the zero-flexion palm: +1 or -1. The normal n(theta)
    = Rot(e_f, theta) n0 rises at d(n . up)/d theta = (e_f x n(theta)) . up, taken at
    theta 0 (the tilts stop short of a palm facing straight up, where it changes sign)."""
    up = -np.asarray(GRAVITY_WORLD, dtype=float)
    rise = float(np.cross(wrist.e_f, wrist.n0) @ up)
    return 1.0 if rise >= 0.0 else -1.0


def palm_up_grids(wrist: Wrist) -> tuple[StopGrid, ...]:
    """The soft stop's grids of the palm-up catch: one tilt each (``PALM_UP_TILTS_DEG``, the
    side ``palm_up_sign`` turns up), the contact shares as every plan's."""
    s = palm_up_sign(wrist)
    return tuple(StopGrid((s * tilt,), CONTACT_SHARES) for tilt in PALM_UP_TILTS_DEG)


def palm_up_fallback(plans: Callable[..., CatchPlan], plan: CatchPlan, wrist: Wrist,
                     reach: bool, stop_stages: Callable[[CatchPlan], CatchPlan] | None = None
                     ) -> CatchPlan:
    """``plan`` (infeasible, the roll among its reasons) planned again with the palm turned
    up past facing the ball (``palm_up_grids``): on the rig's reach axis where the hand has
    one (``reach``; the arm alone places the ball on a palm tilted this far at few tilts:
    0 m / 25 deg / 1.0 m at none of 20-50 deg), else by the arm alone; ``plans(rig=, grid=)``:
    ``CatchPlanner._plans`` of the throw. The first feasible, with a note naming the tilt and
    what failed facing the ball. The tilts failing only as too fast to stop are then given
    ``stop_stages`` (``planner.stop_stages``: the stop bound and the stop optimised on
    their rows), the least first: the first feasible, noted; else the least tilt left with
    only "no stop found" (the palm up keeps the ball on the palm: the stop, not the roll, is
    the shortfall), noted with the facing plan's reasons; else ``plan`` with each tilt's
    first reason in a note."""
    if CatchReason.ROLL not in plan.reason_kinds:
        return plan
    tried, stopped = [], []
    for grid in palm_up_grids(wrist):
        tilt = abs(grid.tilts_deg[0])
        other = plans(rig=reach, grid=grid)
        if other.feasible:
            return palm_up_found(other, plan, tilt, reach)
        tried.append(f"{tilt:g} deg: " + reasons_text(other.reasons[:1]))
        if set(other.reason_kinds) == {CatchReason.TOO_FAST_TO_STOP}:
            stopped.append((tilt, other))
    kept = None  # the least tilt that keeps the ball on the palm, only its stop not found
    for tilt, other in stopped if stop_stages is not None else ():
        # the palm up with the stop optimised on its rows (the roll kept, the stop not found)
        other = stop_stages(other)
        if other.feasible:
            return palm_up_found(other, plan, tilt, reach)
        tried.append(f"{tilt:g} deg, the stop optimised on its rows: "
                     + reasons_text(other.reasons[:1]))
        if kept is None and set(other.reason_kinds) == {CatchReason.NO_STOP}:
            kept = (tilt, other)
    if kept is not None:
        # the roll is not what stops the catch: the palm up keeps the ball on the palm, and
        # only its stop is not found (a shortfall the stop bound does not make a limit)
        tilt, other = kept
        return replace(other, notes=other.notes + (
            f"the palm turned up {tilt:g} deg past facing the ball keeps it on the palm, "
            "its stop not found: facing the ball " + reasons_text(plan.reasons)
            + "; the palm turned up past facing it: " + "; ".join(tried),))
    return replace(plan, notes=plan.notes + (
        "the palm turned up past facing the ball: " + "; ".join(tried),))


def palm_up_found(other: CatchPlan, plan: CatchPlan, tilt: float, reach: bool) -> CatchPlan:
    """``other`` (feasible, the palm turned up ``tilt`` deg) noted with what failed facing
    the ball (``plan``'s reasons)."""
    return replace(other, notes=other.notes + (
        f"the palm meets the ball turned up {tilt:g} deg past facing it"
        f"{' (the reach axis placing it)' if reach else ''}: facing the ball "
        + reasons_text(plan.reasons),))


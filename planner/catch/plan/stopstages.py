"""The soft stop's later stages (``CatchPlanner.plan``): where every plan of a throw is
too fast to stop with the coarse search (``stopping.COARSE_STOP``), the same plans again
with the palm's tilts and the contact shares in finer steps (``FINE_STOP``), then, where
the coarse plan's worst motor is within ``JOINT_STOPS_REACH`` of its limit, with per-joint
ramps and recoils (``JOINT_STOPS``: ``planner.catch.plan.ramps``): the first feasible plan,
noted (``joint_stop_fallbacks``)."""

from __future__ import annotations

from dataclasses import replace

from planner.catch.plan.ramps import JointRamps
from planner.catch.plan.reasons import CatchReason, reasons_text
from planner.catch.plan.results import CatchPlan
from planner.catch.plan.stopping import StopGrid

TILTS_FINE_DEG = (0.0, *(-float(k) for k in range(1, 16)), *(float(k) for k in range(1, 16)))
CONTACT_SHARES_FINE = tuple(k / 20 for k in range(19, 3, -1))  # 0.95 ... 0.2
# ... where the coarse ones (``stopping.TILTS_DEG``, ``CONTACT_SHARES``) leave the ball too
# fast to stop (``CatchPlanner.plan``): the tilts in 1 deg
# steps to +-15 deg, the shares in steps of 0.05 to 0.2. Both searches go on while they
# improve, and the rows' load is not monotone at the coarse steps: measured on the wide
# grid's 28 throws too fast to stop (docs/history/2026-12-07-catch-finer.md), the fine grid
# stops three within every motor (0 m / 75 deg / 2.0 m, +0.3 m / 75 deg / 2.5 m: the tilts;
# -0.3 m / 45 deg / 4.0 m: the shares); 2.5 deg tilts only the first, every tilt of the
# 1 deg grid tried (no early end) no more than the 1 deg search, +-20 deg no more.
FINE_STOP = StopGrid(TILTS_FINE_DEG, CONTACT_SHARES_FINE)  # where that is too fast to stop
# ... and where that is too, each arm joint ramping in its own time
# (``ramps.with_joint_ramps``), every tilt's recoil judged; then only the loaded motors'
# joints recoiling (``ramps.recoil_shares``), every tilt's, then the least loaded tilt's (measured on main's 25
# too fast to stop: docs/history/2026-12-07-catch-ramps.md)
JOINT_STOP = StopGrid(TILTS_FINE_DEG, CONTACT_SHARES_FINE, JointRamps.EACH, True)
LOADED_STOP = StopGrid(TILTS_FINE_DEG, CONTACT_SHARES_FINE, JointRamps.LOADED, True)
LOADED_TILT_STOP = StopGrid(TILTS_FINE_DEG, CONTACT_SHARES_FINE, JointRamps.LOADED)
# ... and where those are too, the flexion alone recoiling, every tilt's recoil judged with
# the fingers closing as the rows close them: the open hand's judge is optimistic where the
# closing is under way at the intercept (0 m / 65 deg / 4.0 m, tilt -13 deg: judged headroom
# +0.13 open, the rows' -0.015). Every joint recoiling so judged was measured too and not
# kept: it made -0.3 m / 65 deg / 4.0 m pass the check, and the replay lost the ball at
# 1.82 s (docs/history/2026-12-07-catch-ramps2.md)
LOADED_FINGERS_STOP = replace(LOADED_STOP, fingers_judged=True)
JOINT_STOPS = (JOINT_STOP, LOADED_STOP, LOADED_TILT_STOP, LOADED_FINGERS_STOP)
FINE_STOP_NOTE = "the stop searched in finer steps (the palm's tilt 1 deg, the contact share 0.05)"


def joint_stop_note(grid: StopGrid) -> str:
    """The note of a plan made with per-joint ramps (``JOINT_STOPS``)."""
    who = ("every arm joint recoiling" if grid.per_joint is JointRamps.EACH else
           "the loaded motor's joint alone recoiling")
    how = "every tilt's recoil judged" if grid.every_tilt else "the least loaded tilt"
    how += " with the fingers closing" if grid.fingers_judged else ""
    return f"the stop with per-joint ramps ({who}, {how}, the finer steps)"


JOINT_STOPS_REACH = 0.5  # the most a motor's need may exceed its limit in the coarse plan
# (|torque| / capacity - 1) for ``JOINT_STOPS`` to be tried: on the wide grid the largest
# they took below the limit was 2.83 N m of the wrist flexion's 2.00 (+0.3 m / 75 deg /
# 3.0 m: 0.42 over; docs/history/2026-12-07-catch-ramps2.md); a throw needing 1.5x its
# motor is beyond them, and trying costs 10-60 s of planning (30 deg / 10 m: 13.6 s for an
# infeasible answer that took 1.3 s before they existed)


def joint_stop_fallbacks(replan, plan: CatchPlan) -> CatchPlan:
    """``finer_stop_fallback`` with ``FINE_STOP``, then, where the coarse plan's worst motor
    is within ``JOINT_STOPS_REACH`` of its limit, with each of ``JOINT_STOPS`` in order
    (per-joint ramps and recoils) while none is feasible: the first feasible plan
    (``replan(grid)``), noted; else ``plan``."""
    finer = finer_stop_fallback(lambda: replan(FINE_STOP), plan)
    stop = plan.forces.stop if plan.forces is not None else None
    if stop is not None and stop.headroom < -JOINT_STOPS_REACH:
        return finer  # (beyond what per-joint ramps take off: not tried)
    for grid in JOINT_STOPS:
        if finer.feasible:
            break
        finer = finer_stop_fallback(lambda g=grid: replan(g), plan, joint_stop_note(grid))
    return finer


def finer_stop_fallback(replan, plan: CatchPlan, note: str = FINE_STOP_NOTE) -> CatchPlan:
    """Where ``plan`` is too fast to stop among its reasons, ``replan()`` (the same plans
    with the soft stop's tilts and contact shares in finer steps, ``FINE_STOP``: the rows'
    load is not monotone at the coarse ones; or with per-joint ramps too, ``JOINT_STOPS``),
    noted, if feasible; else ``plan``."""
    if CatchReason.TOO_FAST_TO_STOP not in plan.reason_kinds:
        return plan
    finer = replan()
    if not finer.feasible:
        return plan
    return replace(finer, notes=finer.notes + (
        note + ": in the coarse ones " + reasons_text(plan.reasons),))

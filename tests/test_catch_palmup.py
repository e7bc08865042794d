"""The palm-up catch (``planner.catch.plan.palmup``): where every plan facing the ball loses
it to the roll rule, the palm meets it turned up past facing it. No wall-clock assertions."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pytest

from planner.catch.plan.api import plan_throw, write_plan
from planner.catch.plan.geometry import rot1
from planner.catch.plan.palmup import (
    PALM_UP_TILTS_DEG,
    palm_up_fallback,
    palm_up_grids,
    palm_up_sign,
)
from planner.catch.plan.reasons import CatchReason, Reason
from planner.catch.plan.stopping import CONTACT_SHARES
from planner.check import check_trajectory
from planner.check.ballroll import ROLL_ROOM_M
from planner.hand.model import GRAVITY_WORLD


@pytest.fixture(scope="module")
def caught(pl):
    """0 m / 25 deg / 1.0 m: facing the ball it rolls 213 mm towards the wrist (measured on
    bc6a83a, every fallback tried), turned up 20 deg past facing it is caught."""
    return plan_throw(25.0, 1.0, 0.0, planner=pl)


def test_the_palm_up_side_and_tilts(pl):
    """On the default hand a negative flexion turns the palm's normal up (the hold's turn
    ends at about -1.0 rad, palm up); the grids are 20-40 deg on that side, 5 deg apart,
    one tilt each, the contact shares as every plan's."""
    s = palm_up_sign(pl.wrist)
    assert s == -1.0
    up = -np.asarray(GRAVITY_WORLD) / np.linalg.norm(GRAVITY_WORLD)
    w = pl.wrist
    assert rot1(w.e_f, 0.3 * s, w.n0) @ up > w.n0 @ up > rot1(w.e_f, -0.3 * s, w.n0) @ up
    grids = palm_up_grids(pl.wrist)
    assert [g.tilts_deg for g in grids] == [(-20.0,), (-25.0,), (-30.0,), (-35.0,), (-40.0,)]
    assert PALM_UP_TILTS_DEG == (20.0, 25.0, 30.0, 35.0, 40.0)
    assert all(g.shares == CONTACT_SHARES for g in grids)


@dataclass(frozen=True)
class _Plan:
    """The fields ``palm_up_fallback`` reads of a plan."""

    feasible: bool
    reasons: tuple
    notes: tuple = ()

    @property
    def reason_kinds(self):
        return tuple(r.kind for r in self.reasons)


def test_the_fallback_runs_only_for_the_roll_and_names_each_tilt(pl):
    """A plan whose reasons do not name the roll is returned as it is, nothing planned again;
    one that does is planned at each tilt in order (on the reach axis where the hand has
    one), the first feasible kept with a note naming its tilt, else each tilt's first
    reason in a note."""
    asked = []

    def plans(**kw):
        asked.append(kw)
        return _Plan(False, (Reason(CatchReason.FRICTION, "slides"),))

    fast = _Plan(False, (Reason(CatchReason.TOO_FAST_TO_STOP, "fast"),))
    assert palm_up_fallback(plans, fast, pl.wrist, True) is fast and not asked
    rolled = _Plan(False, (Reason(CatchReason.ROLL, "rolls"),))
    out = palm_up_fallback(plans, rolled, pl.wrist, True)
    assert not out.feasible and out.reasons == rolled.reasons
    assert [(k["rig"], k["grid"].tilts_deg) for k in asked] == [
        (True, (-t,)) for t in PALM_UP_TILTS_DEG]
    assert out.notes[-1] == "the palm turned up past facing the ball: " + "; ".join(
        f"{t:g} deg: slides" for t in PALM_UP_TILTS_DEG)

    def second(**kw):
        return _Plan(kw["grid"].tilts_deg == (-25.0,), ())

    kept = palm_up_fallback(second, rolled, pl.wrist, False)
    assert kept.feasible and kept.notes == (
        "the palm meets the ball turned up 25 deg past facing it: facing the ball rolls",)


def test_a_short_flat_throw_refused_for_the_roll_is_caught_palm_up(pl, caught, tmp_path):
    """0 m / 25 deg / 1.0 m: feasible with the palm turned up 20 deg past facing the ball on
    the reach axis (the note names the roll facing it), the palm's normal 20 deg off the
    ball's path, the roll within the room, ``check`` confirms the written plan."""
    p = caught
    assert p.feasible, p.reasons
    note = p.notes[-1]
    assert note.startswith("the palm meets the ball turned up 20 deg past facing it (the "
                           "reach axis placing it): facing the ball the ball rolls off")
    _confirmed_palm_up(pl, p, tmp_path)


def _confirmed_palm_up(pl, p, tmp_path):
    """``p`` (feasible) meets the ball with the palm's normal 20 deg off its path, the roll
    within the room by the planner's model, and ``check`` confirms the written plan, the
    roll within the room by its own."""
    assert p.intercept.misalignment_deg == pytest.approx(20.0, abs=1.5)
    assert pl.turn.rolled(p.rows.t, p.rows.q, p.intercept.t_s, p.flight) <= ROLL_ROOM_M
    out = tmp_path / "c.csv"
    write_plan(p, str(out))
    rep = check_trajectory(str(out))
    assert rep.ok, rep.problems
    assert rep.catch.roll_m <= ROLL_ROOM_M


@pytest.mark.parametrize("plan, end_m", [("caught", 0.0335), ("steep", 0.044)])
def test_the_palm_up_catch_is_held_in_physics(request, plan, end_m, tmp_path):
    """The palm-up catches (0 m / 25 deg / 1.0 m; 0 m / 75 deg / 3.0 m with the stop
    optimised on its rows) replayed in MuJoCo (full contact): held (measured: 34 and 44 mm
    from the palm centre at the end)."""
    pytest.importorskip("mujoco")
    from planner.simulate import simulate_trajectory

    out = tmp_path / "c.csv"
    write_plan(request.getfixturevalue(plan), str(out))
    c = simulate_trajectory(str(out)).catch
    assert c is not None and c.held and c.end_distance_m < end_m + 0.010


def test_the_tilts_too_fast_to_stop_get_the_stop_stages_least_first(pl):
    """The tilts whose plans fail only as too fast to stop are given ``stop_stages`` after
    every tilt was planned, the least tilt first: the first feasible is kept with its tilt's
    note; where none is, the least tilt left with only "no stop found" is the answer (the
    palm up keeps the ball on the palm: the stop is the shortfall, not the roll), the facing
    plan's reasons in its note; a tilt failing for anything else is never given them, and
    without ``stop_stages`` the facing plan is kept as before."""
    rolled = _Plan(False, (Reason(CatchReason.ROLL, "rolls"),))

    def plans(**kw):
        tilt = -kw["grid"].tilts_deg[0]
        kind = CatchReason.FRICTION if tilt == 20.0 else CatchReason.TOO_FAST_TO_STOP
        return _Plan(False, (Reason(kind, f"at {tilt:g}"),))

    staged = []

    def stop_stages(p):
        staged.append(p.reasons[0].detail)
        tilt = float(p.reasons[0].detail.split()[1])
        return _Plan(tilt == 35.0, (Reason(CatchReason.NO_STOP, f"no stop at {tilt:g}"),))

    out = palm_up_fallback(plans, rolled, pl.wrist, True, stop_stages)
    assert staged == ["at 25", "at 30", "at 35"]
    assert out.feasible and out.notes[-1].startswith(
        "the palm meets the ball turned up 35 deg past facing it")
    staged.clear()

    def never(p):
        staged.append(p.reasons[0].detail)
        return _Plan(False, (Reason(CatchReason.NO_STOP, "no stop " + p.reasons[0].detail),))

    left = palm_up_fallback(plans, rolled, pl.wrist, True, never)
    assert staged == ["at 25", "at 30", "at 35", "at 40"]
    assert not left.feasible and left.reasons == (Reason(CatchReason.NO_STOP, "no stop at 25"),)
    assert left.notes[-1].startswith("the palm turned up 25 deg past facing the ball keeps it "
                                     "on the palm, its stop not found: facing the ball rolls")
    assert palm_up_fallback(plans, rolled, pl.wrist, True).reasons == rolled.reasons


@pytest.fixture(scope="module")
def steep(pl):
    """0 m / 75 deg / 3.0 m: facing the ball it rolls 279 mm towards the wrist and no stop
    is found (measured on main: the stop optimised on its rows 0.78 of the flexion, its roll
    kept); turned up 20 deg the ball stays on the palm and only the stop is not found (the
    planner's 4.45 N m of the flexion's 2.00), which the stop optimised on its rows finds."""
    return plan_throw(75.0, 3.0, 0.0, planner=pl)


def test_a_steep_long_throw_is_caught_palm_up_with_the_stop_optimised(pl, steep, tmp_path):
    """The plan is feasible palm up 20 deg on the reach axis with the stop optimised on its
    rows (both noted), the roll within the room and the stop within every motor by the
    check's rule; ``check`` confirms the written plan."""
    p = steep
    assert p.feasible, p.reasons
    assert p.notes[-1].startswith("the palm meets the ball turned up 20 deg past facing it "
                                  "(the reach axis placing it): facing the ball the ball "
                                  "rolls off")
    assert p.notes[-2].startswith("the stop optimised on the rows")
    _confirmed_palm_up(pl, p, tmp_path)


def test_a_flat_fast_throw_names_the_stop_not_the_roll(pl):
    """+0.3 m / 15 deg / 3.0 m (9.4 m/s): facing the ball it rolls 491 mm towards the wrist
    and no stop is found (measured on main); palm up 20-40 deg every plan keeps the ball on
    the palm and fails only as too fast to stop, and the stop optimised on the least such
    tilt's rows is still over the wrist flexion (measured: 1.04 of its 2.00 N m). The plan is
    that palm-up plan: "no stop found" (not a hard limit: the stop bound's share at most 1),
    its only reason, no roll; the note names the tilt and the facing plan's roll."""
    p = plan_throw(15.0, 3.0, 0.3, planner=pl)
    assert not p.feasible
    assert p.reason_kinds == (CatchReason.NO_STOP,)
    b = re.search(r"the stop bound: motor\.\w+ at ([\d.]+) of its", p.reasons[0].detail)
    o = re.search(r"the stop optimised on the rows \(the check's rule, linearised, at the "
                  r"plan's rate\): motor\.wrist_flex at [\d.]+ N m of its 2\.00 \(([\d.]+) of "
                  r"it\)", p.reasons[0].detail)
    assert b and float(b.group(1)) <= 1.0
    assert o and float(o.group(1)) > 1.0
    note = p.notes[-1]
    assert re.match(r"the palm turned up (20|25|30|35|40) deg past facing the ball keeps it on "
                    r"the palm, its stop not found: facing the ball ", note)
    assert "the ball rolls off the palm's wrist side" in note
    assert p.intercept.misalignment_deg >= 19.0

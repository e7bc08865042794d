"""The stop optimised on the plan's rows (``planner.catch.plan.stoprows``): a linear programme
of the check's stopping rule, the planner's last stage for "no stop found"
(``planner.catch.plan.planner.optimised_stop_plan``)."""

from dataclasses import replace

import numpy as np
import pytest

from planner.catch.plan import planner as catch_planner
from planner.catch.plan import stoprows
from planner.catch.plan.api import plan_throw, write_plan
from planner.catch.plan.reasons import CatchReason, Reason
from planner.check import check_trajectory
from planner.trajectory import LIMIT_MARGIN

THROW = (15.0, 4.0, -0.3)  # 7.5 m/s at the palm: the planner's stops need 3.11 N m of the
# wrist flexion's 2.00 (main's "no stop found")


@pytest.fixture(scope="module")
def before(pl):
    """The throw's plan as the planner makes it without the optimised stop (the stage
    replaced by the identity): infeasible, "no stop found" its only reason."""
    mp = pytest.MonkeyPatch()
    mp.setattr(catch_planner, "optimised_stop_plan", lambda _pl, plan: plan)
    try:
        p = plan_throw(*THROW, planner=pl)
    finally:
        mp.undo()
    assert p.reason_kinds == (CatchReason.NO_STOP,)
    return p


def _model(pl, p):
    return stoprows.RowStopModel(pl.kin, list(pl.rig_dyn.arm), stoprows.ball_of(p.flight),
                                 float(p.intercept.t_s), p.timing.grasp_t)


def test_a_no_stop_throw_is_caught_and_the_check_confirms_it(pl, tmp_path):
    """The grid's -0.3 m / 15 deg / 4.0 m, "no stop found" on main: feasible with the stop
    optimised on its rows, noted, its stop within every motor (measured: the most loaded at
    0.48 of its capacity), and the independent check passes the written file."""
    p = plan_throw(*THROW, planner=pl)
    assert p.feasible, p.reasons
    assert any(n.startswith("the stop optimised on the rows") for n in p.notes)
    assert p.forces.stop.headroom >= 0.2
    path = tmp_path / "c.csv"
    write_plan(p, str(path))
    rep = check_trajectory(str(path))
    assert rep.ok, rep.problems


def test_the_optimised_rows_keep_every_rule_the_programme_states(pl, before):
    """The programme's rows, judged apart from it: the rows outside its window, the two about
    the intercept and every finger's column unchanged; every arm joint's row speed (first
    differences: the last guard's) within 98 % of its limit (``LIMIT_MARGIN``), its second
    differences within 98 % of the acceleration limit and its third within 98 % of the jerk
    bound (or no worse than the planner's rows there); positions within the planned range; the check's own stopping rule
    (``ball_load_instants``, the full dynamics at every row) within every motor and the
    force in the cone, at the share the linear model said (within 0.02)."""
    h = pl.hand
    t, Q = before.rows.t, before.rows.q
    model = _model(pl, before)
    assert stoprows.check_stop(model, t, Q).headroom < 0  # the planner's rows: over
    rs = stoprows.optimise_stop(model, t, Q)
    assert rs.Q is not None and rs.failure == ""
    Qn, dt = rs.Q, float(t[1] - t[0])
    W = stoprows.Window(t, model.t_i, len(model.arm))
    moved = np.flatnonzero(np.any(Qn != Q, axis=1))
    assert moved.size and moved[0] >= W.first and moved[-1] <= W.last
    assert np.array_equal(Qn[W.k0:W.k0 + 2], Q[W.k0:W.k0 + 2])
    others = np.setdiff1d(np.arange(h.n), model.arm)
    assert np.array_equal(Qn[:, others], Q[:, others])
    arm = model.arm
    lo, hi = np.minimum(h.plan_lower, Q)[:, arm], np.maximum(h.plan_upper, Q)[:, arm]
    assert np.all(Qn[:, arm] >= lo - 1e-9) and np.all(Qn[:, arm] <= hi + 1e-9)
    for X0, X1, lim in ((np.diff(Q, 1, axis=0), np.diff(Qn, 1, axis=0), h.velocity * dt),
                        (np.diff(Q, 2, axis=0), np.diff(Qn, 2, axis=0),
                         h.acceleration * dt ** 2),
                        (np.diff(Q, 3, axis=0), np.diff(Qn, 3, axis=0), h.jerk * dt ** 3)):
        lim = LIMIT_MARGIN * lim  # (the planner's 98 %)
        allowed = np.maximum(lim[arm], np.abs(X0[:, arm])) * (1 + 1e-6) + 1e-12
        assert np.all(np.abs(X1[:, arm]) <= allowed)
    stop = stoprows.check_stop(model, t, Qn)
    assert stop.headroom >= 0.0
    assert stop.cone_margin_n is None or stop.cone_margin_n >= 0.0
    assert rs.share == pytest.approx(1.0 - stop.headroom, abs=0.02)


def test_where_the_rows_cannot_be_caught_the_plan_keeps_its_stop(pl, before):
    """The fallback: a plan that loses the ball for another reason too (here the roll added)
    keeps the planner's rows, infeasible, the optimum's numbers in its "no stop found"
    reason; a programme with too few rows after the touch fails and says so."""
    other = Reason(CatchReason.ROLL, "the ball rolls off (added)")
    p = replace(before, reasons=before.reasons + (other,))
    out = catch_planner.optimised_stop_plan(pl, p)
    assert not out.feasible and out.rows is p.rows
    assert out.reasons[1] is other
    r = out.reasons[0]
    assert r.kind is CatchReason.NO_STOP and r.detail.startswith(before.reasons[0].detail)
    assert "the stop optimised on the rows" in r.detail
    t, Q = before.rows.t, before.rows.q
    k = int(np.searchsorted(t, before.intercept.t_s))
    model = _model(pl, before)
    dq, share, why = stoprows.solve_offset(model, t[:k + 3], Q[:k + 3])
    assert dq is None and share == float("inf") and why == "too few rows after the touch"

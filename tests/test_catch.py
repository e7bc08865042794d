"""Catch planner (planner.catch.plan.api) and grasp force QP (planner.catch.grasp), on the
default hand. (Its thumb CMC flexion range is 110 deg: with the earlier 90 deg the thumb
tip stayed ~17 mm outside a tennis ball held on the palm, so no grasp could form;
``test_thumb_reaches_a_ball_on_the_palm`` checks the geometry independently.)

No wall-clock assertions.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize

from cli import main as cli_main
from planner.catch import grasp as gq
from planner.catch.flight.path import predict_throw
from planner.catch.plan.api import (
    GRASP_TOL_M,
    GRASP_WINDOW_S,
    INTERCEPT_TOL_M,
    CatchPlanner,
    catch_mount,
    default_mount,
    get_planner,
    plan_catch,
    plan_throw,
    write_plan,
)
from planner.catch.plan.reasons import CatchReason
from planner.errors import InfeasibleError, InputError
from planner.hand.model import load_hand
from planner.trajfile import read_trajectory

RADIUS = {"tennis": 0.0335}


# ------------------------------------------------------------------ fixtures


@pytest.fixture(scope="module")
def thumb110() -> str:
    """The hand the catch tests use (the shipped default hand)."""
    return "default"


@pytest.fixture(scope="module")
def seed_plan(tmp_path_factory, thumb110):
    out = tmp_path_factory.mktemp("catch") / "seed.csv"
    res = plan_catch(30.0, 1.5, 0.0, thumb110, str(out))
    return res, str(out)


def _rows_at(t: np.ndarray, Q: np.ndarray, ti: float) -> np.ndarray:
    return np.array([np.interp(ti, t, Q[:, j]) for j in range(Q.shape[1])])


def _mounted_from_file(path: str, hand_source: str):
    tr = read_trajectory(path)
    hand = load_hand(hand_source).mounted(np.array(tr.metadata["T_world_root"]))
    return tr, hand


def _ball(meta, t):
    b = meta["ball"]
    assert b["drag"] == 0.0
    t = np.atleast_1d(t)[:, None]
    return np.array(b["p0"]) + np.array(b["v0"]) * t + 0.5 * np.array([0, 0, -9.81]) * t * t


# ------------------------------------------------------------------ seed numbers, file


def test_seed_numbers(seed_plan):
    res, _ = seed_plan
    # seed: 30 deg over 1.5 m -> 4.122 m/s, 0.42 s
    assert res.plan.intercept.launch_speed_m_s == pytest.approx(4.122, abs=5e-4)
    assert res.plan.intercept.flight_time_s == pytest.approx(0.42, abs=5e-3)
    assert res.feasible, res.reasons


def test_file_metadata(seed_plan, thumb110):
    res, path = seed_plan
    tr = read_trajectory(path)
    m = tr.metadata
    for k in ("format", "version", "task", "hand", "urdf_sha256", "T_world_root", "rate_hz",
              "ball", "intercept_t"):
        assert k in m
    assert m["task"] == "catch" and m["format"] == "hand-trajectory" and m["version"] == 2
    hand = load_hand(thumb110)
    assert m["hand"] == hand.name and m["urdf_sha256"] == hand.urdf_sha256
    assert set(m["ball"]) >= {"p0", "v0", "radius", "mass", "drag"}
    assert m["ball"]["radius"] == pytest.approx(RADIUS["tennis"])
    T = np.array(m["T_world_root"])
    assert np.allclose(T, res.plan.T_world_root)
    assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    # the mount is the hand file's [catch] section placed at the catch point (1.5, 0, 0)
    mount = catch_mount(hand, thumb110)
    assert np.allclose(T[:3, 3], np.array([1.5, 0.0, 0.0]) + mount.offset_m)
    assert tr.complete and tr.joint_names == hand.joint_names
    assert tr.motor_names == hand.motor_names
    assert m["rate_hz"] == 100.0
    assert np.allclose(np.diff(tr.t_s), 0.01) and tr.t_s[0] == 0.0
    assert tr.t_s[-1] >= m["intercept_t"] + 0.5 - 0.01


def test_rows_within_limits_and_couplings(seed_plan, thumb110):
    _, path = seed_plan
    tr = read_trajectory(path)
    hand = load_hand(thumb110)
    Q = tr.q
    assert np.all(Q >= hand.lower - 1e-6) and np.all(Q <= hand.upper + 1e-6)
    dt = np.diff(tr.t_s)[:, None]
    V = np.diff(Q, axis=0) / dt
    assert np.all(np.abs(V) <= hand.velocity * 1.0 + 2e-6 / dt)
    A = np.diff(V, axis=0) / dt[1:]
    assert np.all(np.abs(A) <= hand.acceleration * 1.01 + 4e-6 / dt[1:] ** 2)
    assert np.max(np.abs(hand.coupling_errors(Q))) < 2e-6  # exact up to the 6 decimals
    assert np.allclose(tr.q_motor, hand.motor_angles(Q), atol=1e-4)


def test_palm_meets_ball_and_grasp(seed_plan, thumb110):
    """Own FK: ball centre within 15 mm of palm_center + r n at intercept_t; no fingertip
    inside the ball before it; thumb + 2 within r + 10 mm within 150 ms, held to the end."""
    _, path = seed_plan
    tr, hand = _mounted_from_file(path, thumb110)
    m = tr.metadata
    r = m["ball"]["radius"]
    ti = m["intercept_t"]
    qi = _rows_at(tr.t_s, tr.q, ti)
    P = hand.palm_pose(qi)
    target = P[:3, 3] + r * P[:3, 2]
    assert np.linalg.norm(_ball(m, ti)[0] - target) < INTERCEPT_TOL_M
    assert np.linalg.norm(_ball(m, ti)[0] - target) < 0.002  # planned to ~0
    thumb = hand.fingers.index("thumb")
    grasp_rows = []
    for t, q in zip(tr.t_s, tr.q):
        tips = hand.tip_positions(q)
        if t < ti:
            assert np.min(np.linalg.norm(tips - _ball(m, t)[0], axis=1)) >= r
        else:
            Pq = hand.palm_pose(q)
            c = Pq[:3, 3] + r * Pq[:3, 2]
            close = np.linalg.norm(tips - c, axis=1) <= r + GRASP_TOL_M
            grasp_rows.append((t, bool(close[thumb] and close.sum() >= 3)))
    first = next(t for t, ok in grasp_rows if ok)
    assert first <= ti + GRASP_WINDOW_S
    assert all(ok for t, ok in grasp_rows if t >= first)


def test_palm_faces_ball(seed_plan):
    res, _ = seed_plan
    p = res.plan
    n = p.hand.palm_pose(_rows_at(p.rows.t, p.rows.q, p.intercept.t_s))[:3, 2]
    v = p.intercept.arrival_velocity
    tilt = 0.0 if p.forces.soft is None else abs(math.degrees(p.forces.soft.tilt_rad))
    assert abs(math.degrees(math.acos(-(v @ n) / np.linalg.norm(v))) - tilt) < 1.0
    assert p.timing.close_s >= 0.150 - 1e-9  # closing time within the seed's 150-300 ms
    assert p.timing.close_s <= 0.300


def test_independent_check_passes(seed_plan, thumb110):
    from planner.check import check_trajectory

    _, path = seed_plan
    rep = check_trajectory(path, hand_override=thumb110)
    assert rep.ok, rep.problems


# ------------------------------------------------------------------ default hand


def test_thumb_reaches_a_ball_on_the_palm():
    """Independent geometry: somewhere in the thumb's joint box its tip is within
    radius + the grasp tolerance of a tennis ball resting on the palm."""
    hand = load_hand("default")
    q = hand.q_neutral.copy()
    P = hand.palm_pose(q)
    r = RADIUS["tennis"]
    c = P[:3, 3] + r * P[:3, 2]
    js = hand.joint_slice("thumb")
    bounds = list(zip(hand.lower[js], hand.upper[js]))

    def dist(x):
        qq = q.copy()
        qq[js] = x
        return float(np.linalg.norm(hand.tip_positions(qq)[0] - c))

    axes = [np.linspace(lo, hi, 19) for lo, hi in bounds]
    grid = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(js), -1).T
    d = np.array([dist(x) for x in grid])
    starts = grid[np.argsort(d)[:4]]
    best = min((minimize(dist, x0, bounds=bounds) for x0 in starts), key=lambda s: s.fun)
    assert best.fun - r < GRASP_TOL_M


def test_default_hand_catch_is_feasible_and_strict_passes(tmp_path):
    out = tmp_path / "c.csv"
    res = plan_catch(30.0, 1.5, 0.0, "default", str(out))
    assert out.exists() and res.feasible, res.reasons
    assert res.plan.intercept.error_m < 0.001
    assert res.plan.timing.min_clearance_before_m > 0
    plan_catch(30.0, 1.5, 0.0, "default", str(tmp_path / "s.csv"), strict=True)
    assert (tmp_path / "s.csv").exists()


# ------------------------------------------------------------------ grid


@pytest.mark.parametrize("hand_kind", ["default"])
def test_grid(hand_kind, thumb110):
    """Angles 20-60 deg (step 10) x distances 1-3 m (step 0.5): with the soft catch every
    throw is reached, closed in time and stopped within every motor (before issue 15 the
    3 m throws needed 2.07-2.80 N m of the 2 N m wrist flexion motor); the steep short throws
    whose ball would roll off the palm's wrist side (``planner.check.ballroll``: 20 deg from
    1.0 and 1.5 m) are infeasible for that alone."""
    from planner.catch.plan.reasons import CatchReason

    pl = get_planner(thumb110)
    n_ok = 0
    for a in range(20, 61, 10):
        for d in np.arange(1.0, 3.01, 0.5):
            p = plan_throw(a, d, 0.0, planner=pl)
            assert p.intercept.error_m < 0.001
            assert p.timing.min_clearance_before_m > 0.0
            assert p.timing.grasp_t is not None and p.timing.grasp_t <= p.intercept.t_s + GRASP_WINDOW_S
            if not p.feasible:  # only a ball faster than the joints can stop, or its roll
                assert p.reason_kinds in ((CatchReason.TOO_FAST_TO_STOP,),
                                          (CatchReason.NO_STOP,),
                                          (CatchReason.ROLL,)), (a, d, p.reasons)
                assert p.reason_kinds != (CatchReason.ROLL,) or a == 20, (a, d)
                continue
            n_ok += 1
            assert p.forces.stop.headroom >= 0 and len(p.forces.stop.motor_headroom) == len(p.hand.motor_names)
            if p.forces.soft is not None:  # None: the palm waits at rest (no motion fits, none needed)
                assert np.linalg.norm(p.forces.soft.v_rel) < np.linalg.norm(p.intercept.arrival_velocity)
    assert n_ok >= 23  # measured: 23 of 25 (25 before the roll rule)
    hard = plan_throw(30, 3.0, 0.0, planner=pl, soft=False)
    soft = plan_throw(30, 3.0, 0.0, planner=pl)
    assert soft.forces.stop.force_n < hard.forces.stop.force_n
    assert soft.forces.stop.headroom >= 0.2  # issue 15's target
    # (before the stop on the rows: "no stop found", the planner's stops over the flexion's
    # 2.00 N m; the stop optimised on its rows catches it, ``planner.catch.plan.stoprows``:
    # docs/history/2026-12-07-catch-stoprows.md). Within the joints' stop margins the grid's
    # 0 m / 15 deg / 4.0 m, caught so before, rolls 176 mm towards the wrist (the wrist's
    # turn within its margin; docs/history/2026-12-07-catch-pad.md): the same stop shown on
    # its -0.3 m neighbour, the one ``tests/test_catch_stoprows.py`` measures. Turned up
    # 20 deg the palm keeps the 0 m throw's ball (docs/history/2026-12-07-catch-roll2.md):
    # the roll is not its reason; its stop, optimised on those rows, is not found within the
    # margins (the programme infeasible at the least tilt)
    far = plan_throw(15, 4.0, -0.3, planner=pl)
    assert far.feasible and far.forces.stop.headroom >= 0, far.reasons
    assert any(n.startswith("the stop optimised on the rows") for n in far.notes)
    level = plan_throw(15, 4.0, 0.0, planner=pl)
    assert level.reason_kinds == (CatchReason.NO_STOP,), level.reasons
    assert any(n.startswith("the palm turned up 20 deg past facing the ball keeps it on the palm")
               for n in level.notes), level.notes


def test_catch_plan_is_frozen(seed_plan):
    import dataclasses

    p = seed_plan[0].plan
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.feasible = False
    assert isinstance(p.reasons, tuple) and isinstance(p.notes, tuple)


# ------------------------------------------------------------------ grasp QP


@pytest.fixture(scope="module")
def closed(thumb110):
    p = plan_throw(40.0, 2.0, 0.0, hand=thumb110)
    return p


def _check_grasp(res: gq.GraspResult, hand, q):
    prob = res.problem
    # equilibrium
    assert np.allclose(res.total_force, prob.required_force, atol=1e-4)
    if prob.moment_balance:
        M = sum(np.cross(c.point - prob.centre, f) for c, f in zip(prob.contacts, res.forces))
        assert np.allclose(M, 0.0, atol=1e-5)
    # inside every friction cone (the true cone, mu = 0.8)
    for c, f in zip(prob.contacts, res.forces):
        fn = f @ c.normal
        assert fn >= -1e-5
        assert np.linalg.norm(f - fn * c.normal) <= prob.mu * fn + 1e-5
    assert res.cone_margin() >= -1e-5
    # motor torques recomputed from the forces with the hand model
    tau = hand.gravity_torques(q)
    for c, f in zip(prob.contacts, res.forces):
        tau = tau + c.jacobian.T @ f
    tm = hand.motor_torques(q, tau)
    assert np.allclose(tm, res.motor_torques, atol=1e-6)
    # capacity: the motor's peak, or for a tendon motor its cable's design force at the
    # spool (40 N x 5 mm = 0.2 N m on the default hand, half the 0.4 N m peak)
    cap = np.array([min(a.peak_torque_nm, a.tendon_force_n * a.radius_m)
                    if a.tendon_force_n is not None else a.peak_torque_nm
                    for a in hand.actuators])
    assert np.all(np.abs(tm) <= cap * (1 + 1e-4))
    ratio = np.abs(tm) / cap
    assert res.headroom == pytest.approx(1 - ratio.max(), abs=1e-9)
    m = int(np.argmax(ratio))
    assert res.limiting_motor == hand.motor_names[m]
    tendon = hand.actuators[m].tendon_force_n is not None
    assert res.limiting_part == ("tendon force" if tendon else
                                 "gear" if hand.actuators[m].kind == "gear" else "motor torque")


def test_grasp_hold(closed):
    p = closed
    hand = p.hand
    r = p.flight.ball.radius_m
    P = hand.palm_pose(p.poses.q_closed)
    c = P[:3, 3] + r * P[:3, 2]
    res = gq.grasp_forces(hand, p.poses.q_closed, c, r, gq.hold_force(p.flight.ball.mass_kg))
    names = [ct.name for ct in res.problem.contacts]
    assert names[0] == "palm" and "thumb" in names and len(names) >= 4
    assert res.problem.facets == 8 and res.problem.mu == 0.8
    assert np.allclose(res.total_force, [0, 0, 1.5 * 0.057 * 9.81], atol=1e-4)
    _check_grasp(res, hand, p.poses.q_closed)


def test_grasp_stop(closed):
    p = closed
    hand = p.hand
    r = p.flight.ball.radius_m
    q_i = _rows_at(p.rows.t, p.rows.q, p.intercept.t_s)
    P = hand.palm_pose(q_i)
    c = P[:3, 3] + r * P[:3, 2]
    F = gq.stop_force(p.flight.ball.mass_kg, 0.5 * p.intercept.arrival_velocity, hand.pad_give_m)
    v = np.linalg.norm(0.5 * p.intercept.arrival_velocity)
    # m v^2 / (2 d) against the velocity, plus the weight
    assert np.linalg.norm(F + 0.057 * np.array([0, 0, -9.81])) == pytest.approx(
        0.057 * v * v / (2 * hand.pad_give_m))
    res = gq.grasp_forces(hand, q_i, c, r, F, case="stop", tip_tol_m=0.001,
                          moment_balance=False)
    assert [ct.name for ct in res.problem.contacts] == ["palm"]
    _check_grasp(res, hand, q_i)
    assert res.limiting_motor == "wrist_flex"


def test_grasp_infeasible_huge_mass(closed):
    p = closed
    hand = p.hand
    r = p.flight.ball.radius_m
    P = hand.palm_pose(p.poses.q_closed)
    c = P[:3, 3] + r * P[:3, 2]
    with pytest.raises(InfeasibleError) as ei:
        gq.grasp_forces(hand, p.poses.q_closed, c, r, gq.hold_force(50.0))
    prob = ei.value.problem
    assert isinstance(prob, gq.GraspProblem)
    assert prob.required_force[2] == pytest.approx(1.5 * 50.0 * 9.81)
    assert "motor." in str(ei.value)


def test_grasp_bad_input(closed):
    p = closed
    with pytest.raises(InputError):
        gq.build_grasp_problem(p.hand, p.poses.q_closed, [], np.zeros(3), np.zeros(3))
    cts = gq.ball_contacts(p.hand, p.poses.q_closed, np.zeros(3), 0.03, 0.01)
    with pytest.raises(InputError):
        gq.build_grasp_problem(p.hand, p.poses.q_closed, cts, np.zeros(3), np.zeros(3), facets=3)


# ------------------------------------------------------------------ bad arguments


@pytest.mark.parametrize("args", [
    (0.0, 1.5, 0.0), (90.0, 1.5, 0.0), (-10.0, 1.5, 0.0), (120.0, 1.5, 0.0),
    (float("nan"), 1.5, 0.0), (float("inf"), 1.5, 0.0), (30.0, 0.0, 0.0), (30.0, -1.0, 0.0),
    (30.0, float("nan"), 0.0), (30.0, float("inf"), 0.0), (30.0, 1.5, float("nan")),
    (30.0, 1.5, float("-inf")), ("x", 1.5, 0.0),
])
def test_bad_arguments(tmp_path, args):
    out = tmp_path / "c.csv"
    with pytest.raises(InputError):
        plan_catch(*args, "default", str(out))
    assert list(tmp_path.iterdir()) == []


def test_bad_rate_ball_hand_obs(tmp_path):
    out = str(tmp_path / "c.csv")
    for kw in ({"rate_hz": 0.0}, {"rate_hz": float("nan")}, {"ball": "football"},
               {"observations": str(tmp_path / "none.csv")}):
        with pytest.raises(InputError):
            plan_catch(30.0, 1.5, 0.0, "default", out, **kw)
    with pytest.raises(InputError):
        plan_catch(30.0, 1.5, 0.0, "no_such_hand", out)
    assert list(tmp_path.iterdir()) == []


def test_cli_exit_codes(tmp_path, capsys):
    out = tmp_path / "c.csv"
    assert cli_main(["catch", "--angle", "0", "--dist", "1.5", "-o", str(out)]) == 2
    assert not out.exists()
    assert "error:" in capsys.readouterr().err
    assert cli_main(["catch", "--angle", "30", "--dist", "1.5", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    for s in ("launch speed 4.122 m/s", "flight time 0.420 s", "intercept t =", "close start",
              "margins:", "torque headroom", "feasible: yes"):
        assert s in err
    assert out.exists()
    out.unlink()
    # a throw the planner cannot catch (15 deg from 3 m to +0.3 m: no stop found, palm up):
    # written, exit 1 under --strict (15 deg from 4 m and 75 deg from 3 m, this test's throws
    # before, are caught now: docs/history/2026-12-07-catch-stoprows.md,
    # docs/history/2026-12-07-catch-roll2.md)
    assert cli_main(["catch", "--angle", "15", "--dist", "3", "--height", "0.3", "-o",
                     str(out), "--strict"]) == 1
    assert "feasible: NO" in capsys.readouterr().err
    assert out.exists()


# ------------------------------------------------------------------ observations, drag, rate


def test_observations(tmp_path, thumb110):
    fl = predict_throw(35.0, 2.0, 0.1, "tennis")
    ts = np.arange(0.0, 0.16, 1 / 120)
    ps = fl.position(ts) + np.random.default_rng(3).normal(0, 0.002, (len(ts), 3))
    csv = tmp_path / "obs.csv"
    csv.write_text("t,x,y,z\n" + "".join(f"{t},{x},{y},{z}\n" for t, (x, y, z) in zip(ts, ps)))
    out = tmp_path / "c.csv"
    res = plan_catch(35.0, 2.0, 0.1, thumb110, str(out), observations=str(csv))
    p = res.plan
    u = p.uncertainty
    assert u is not None and 0 < u["sigma_t_s"] < 0.05 and 0 < u["sigma_z_m"] < 0.05
    assert p.timing.t_info_s == pytest.approx(ts[-1])
    assert p.timing.move_start_s == pytest.approx(ts[-1] + 0.030)
    ref = plan_throw(35.0, 2.0, 0.1, hand=thumb110)
    assert p.intercept.t_s == pytest.approx(ref.intercept.t_s, abs=0.02)
    tr = read_trajectory(str(out))
    assert tr.metadata["ball"]["v0"] == pytest.approx(list(p.flight.v0))
    assert res.plan.intercept.error_m < 0.002  # on the fitted flight


def test_drag_and_rate(tmp_path, thumb110):
    out = tmp_path / "c.csv"
    res = plan_catch(40.0, 2.0, 0.0, thumb110, str(out), drag=True, rate_hz=250.0)
    tr = read_trajectory(str(out))
    assert tr.metadata["ball"]["drag"] > 0 and tr.metadata["rate_hz"] == 250.0
    assert np.allclose(np.diff(tr.t_s), 0.004)
    assert res.plan.intercept.error_m < 0.001
    assert res.feasible, res.reasons


def test_mount_defaults(thumb110):
    hand = load_hand("default")
    m_file = catch_mount(hand)
    assert m_file.source.startswith("default.toml")
    m_code = default_mount(hand)
    assert np.allclose(m_file.offset_m, m_code.offset_m, atol=1e-4)
    assert np.allclose(m_file.rpy_deg, m_code.rpy_deg)
    # a hand file without [catch] (mk5 ships none) gets the computed default
    mk5 = load_hand("mk5")
    assert catch_mount(mk5).source.startswith("default (")


def test_out_of_reach_is_reported(tmp_path, thumb110):
    """A mount far from the path: the plan is still written, the reason says why."""
    from planner.catch.plan.api import CatchMount

    hand = load_hand(thumb110)
    far = CatchMount((-0.2287, 0.0, -0.8), (126.0, 0.0, 90.0), "test: 0.5 m too low")
    pl = CatchPlanner(hand, far)
    p = pl.plan(predict_throw(30.0, 1.5, 0.0, "tennis"), np.array([1.5, 0.0, 0.0]))
    assert not p.feasible
    assert any(r.kind is CatchReason.OUT_OF_REACH and r.detail.startswith("out of reach")
               for r in p.reasons)
    assert len(p.rows.t) > 0 and np.all(np.isfinite(p.rows.q))


# ------------------------------------------------------------------ independent check on a grid


def test_independent_check_confirms_grid(tmp_path):
    """Issue 4's done-when, with issue 15's dynamic check: the independent replay check
    (planner.check, which shares only the hand model) passes every feasible catch of the
    grid 20-60 deg x 1-3 m, and rejects for the stopping force or the ball's roll
    (``planner.check.ballroll``, one rule) exactly the throws the planner calls infeasible for
    them (20 deg from 1.0 and 1.5 m: the roll)."""
    from planner import check
    from planner.catch.plan.reasons import CatchReason

    pl = get_planner("default")
    disagree, rejected, infeasible = [], 0, 0
    for a in range(20, 61, 10):
        for d in (1.0, 1.5, 2.0, 2.5, 3.0):
            p = plan_throw(a, d, 0.0, planner=pl)
            path = tmp_path / f"c{a}_{d}.csv"
            write_plan(p, str(path))
            rep = check.check_trajectory(str(path))
            assert p.feasible or set(p.reason_kinds) <= {CatchReason.TOO_FAST_TO_STOP,
                                                         CatchReason.NO_STOP,
                                                         CatchReason.ROLL}, p.reasons
            rejected += not rep.ok
            infeasible += not p.feasible
            if rep.ok != p.feasible or (not rep.ok and not all(x.startswith((
                    "stopping the ball needs", "the ball rolls off",
                    "the plan says the catch is infeasible")) for x in rep.problems)):
                disagree.append((a, d, p.reasons, rep.problems))
    assert disagree == []
    assert rejected == infeasible <= 3  # measured: 2 (the roll)


def test_independent_check_rejects_a_hand_elsewhere(tmp_path):
    """The same plan with the rail moved 5 cm: the check reports the palm off the ball."""
    from planner import check

    p = plan_throw(30.0, 1.5, 0.0, hand="default")
    path = tmp_path / "c.csv"
    write_plan(p, str(path))
    tr = read_trajectory(str(path))
    hand = load_hand("default")
    lines = path.read_text().splitlines()
    j = 1 + hand.index["rail"]
    out = lines[:2]
    for ln in lines[2:-1]:
        v = ln.split(",")
        v[j] = f"{float(v[j]) + 0.05:.6f}"
        out.append(",".join(v))
    out.append(lines[-1])
    (tmp_path / "moved.csv").write_text("\n".join(out) + "\n")
    assert len(tr.t_s) == len(out) - 3
    rep = check.check_trajectory(str(tmp_path / "moved.csv"))
    assert not rep.ok
    assert any("palm" in pr or "ball" in pr for pr in rep.problems), rep.problems

"""Tests of planner.catch.flight.path: throws, drag integration, observation fits, errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from planner.catch.flight.observe import (
    FitResult,
    fit_observations,
    load_observations_csv,
    predict_intercept,
)
from planner.catch.flight.path import (
    BALLS,
    GRAVITY_M_S2,
    RHO_AIR,
    Ball,
    Flight,
    flight_time_to,
    get_ball,
    predict_throw,
)
from planner.errors import InfeasibleError, InputError, PlannerError

# --------------------------------------------------------------------------- seed


def test_seed_api_numbers():
    """Seed, "API" section: 30 deg over 1.5 m -> 4.122 m/s, flight time .42 s."""
    flight = predict_throw(30.0, 1.5)
    assert flight.speed == pytest.approx(4.122, abs=1e-3)
    assert flight_time_to(flight, 1.5) == pytest.approx(0.42, abs=0.005)
    assert flight.drag_per_m == 0.0
    # vacuum closed form: same launch and landing height
    assert flight.speed == pytest.approx(math.sqrt(9.81 * 1.5 / math.sin(math.radians(60))))


def test_seed_ball_and_catalogue():
    seed = BALLS["seed"]
    assert seed.radius_m == pytest.approx(0.0635 / 2)  # 2.5 in
    assert seed.mass_kg == pytest.approx(0.057)
    assert BALLS["tennis"].radius_m == pytest.approx(0.0335)
    assert BALLS["baseball"].mass_kg == pytest.approx(0.145)
    assert BALLS["vacuum"].drag_per_m == 0.0
    t = BALLS["tennis"]
    k = 0.5 * RHO_AIR * 0.55 * math.pi * 0.0335**2 / 0.057
    assert t.drag_per_m == pytest.approx(k)
    assert get_ball(None) is seed
    assert get_ball("baseball") is BALLS["baseball"]


def test_launch_state_in_catch_frame():
    flight = predict_throw(40.0, 2.0, 0.3)
    np.testing.assert_array_equal(flight.p0, np.zeros(3))
    assert flight.v0[1] == 0.0
    assert math.degrees(math.atan2(flight.v0[2], flight.v0[0])) == pytest.approx(40.0)
    with pytest.raises(ValueError):
        flight.p0[0] = 1.0  # read-only


# --------------------------------------------------------------------------- through the point

ANGLES = [10.0, 30.0, 45.0, 60.0, 80.0]
DISTS = [0.3, 1.5, 4.0]
HEIGHTS = [-1.0, 0.0, 0.25]


@pytest.mark.parametrize("drag", [False, True])
@pytest.mark.parametrize("ball", ["seed", "tennis", "baseball"])
def test_passes_through_target(drag, ball):
    n = 0
    for a in ANGLES:
        for d in DISTS:
            for h in HEIGHTS:
                if d * math.tan(math.radians(a)) <= h:
                    continue
                flight = predict_throw(a, d, h, ball=ball, drag=drag)
                t = flight.time_at_x(d)
                assert t > 0
                np.testing.assert_allclose(flight.position(t), [d, 0.0, h], rtol=0, atol=1e-4)
                n += 1
    assert n >= 40


def test_drag_needs_more_speed_and_time():
    vac = predict_throw(30.0, 1.5, ball="tennis")
    air = predict_throw(30.0, 1.5, ball="tennis", drag=True)
    assert air.drag_per_m == pytest.approx(BALLS["tennis"].drag_per_m)
    assert air.speed > vac.speed
    assert air.time_at_x(1.5) > vac.time_at_x(1.5)


def test_vacuum_ball_with_drag_is_closed_form():
    f = predict_throw(30.0, 1.5, ball="vacuum", drag=True)
    assert f.drag_per_m == 0.0 and f.step_s is None
    assert f.speed == pytest.approx(predict_throw(30.0, 1.5).speed, rel=1e-15)


def test_vectorised_evaluation():
    for drag in (False, True):
        f = predict_throw(45.0, 2.0, ball="tennis", drag=drag)
        ts = np.linspace(0.0, 0.6, 7)
        P = f.position(ts)
        V = f.velocity(ts)
        assert P.shape == (7, 3) and V.shape == (7, 3)
        assert f.position(0.3).shape == (3,)
        np.testing.assert_allclose(P[3], f.position(ts[3]), atol=1e-15)
        np.testing.assert_allclose(f.position(0.0), f.p0, atol=1e-15)
        np.testing.assert_allclose(f.velocity(0.0), f.v0, atol=1e-15)
        assert f.position(ts.reshape(7, 1)).shape == (7, 1, 3)
        np.testing.assert_allclose(
            f.time_at_x(np.array([0.5, 1.0])), [f.time_at_x(0.5), f.time_at_x(1.0)]
        )


@pytest.mark.parametrize("drag", [False, True])
def test_one_time_evaluation_is_the_array_evaluation(drag):
    """position1 / velocity1 / state1 (floats, for the live re-plan) give the very numbers
    of the array path, inside the table, beyond it (it grows) and before t = 0."""
    f = Flight(np.array([0.1, -0.2, 0.3]), np.array([3.0, 0.7, 2.5]), BALLS["tennis"],
               BALLS["tennis"].drag_per_m if drag else 0.0)
    ts = np.concatenate([np.linspace(0.0, 1.3, 131), [2.7, -0.05, 0.0137]])
    for t in ts.tolist():
        p, v = f.position1(t), f.velocity1(t)
        assert p == tuple(f.position(np.array([t]))[0]) and v == tuple(f.velocity(np.array([t]))[0])
        assert f.state1(t) == p + v
        np.testing.assert_array_equal(f.position(t), p)  # a float goes the one-time way
    with pytest.raises(InputError, match="finite"):
        f.position1(math.nan)
    if drag:
        with pytest.raises(InputError, match="within"):
            f.velocity1(1e3)


def test_nodes_are_the_table_the_flight_interpolates():
    f = predict_throw(30.0, 1.5, ball="tennis", drag=True)
    nd = f.nodes(0.5)
    h, i0 = nd.step_s, nd.i0
    n = int(0.5 / h)
    assert len(nd.sz) - i0 > n + 1
    np.testing.assert_allclose(f.position(n * h) - f.p0,
                               [nd.direction[0] * nd.sz[i0 + n, 0],
                                nd.direction[1] * nd.sz[i0 + n, 0], nd.sz[i0 + n, 1]],
                               atol=1e-15)
    np.testing.assert_allclose(f.velocity(n * h)[2], nd.uw[i0 + n, 1], atol=1e-15)
    with pytest.raises(PlannerError, match="no drag table"):
        predict_throw(30.0, 1.5).nodes(0.5)


def test_velocity_is_derivative_of_position():
    f = predict_throw(50.0, 3.0, 0.5, ball="tennis", drag=True)
    eps = 1e-5
    for t in (0.0123, 0.3, 0.777, 1.4):
        num = (f.position(t + eps) - f.position(t - eps)) / (2 * eps)
        np.testing.assert_allclose(f.velocity(t), num, atol=1e-6)


# --------------------------------------------------------------------------- drag -> 0


def test_tiny_drag_reproduces_vacuum():
    tiny = Ball("tiny", 0.057, 0.03175, 1e-9)
    assert 0 < tiny.drag_per_m < 1e-10
    for a, d, h in [(30.0, 1.5, 0.0), (60.0, 3.0, 1.0), (15.0, 5.0, -0.5)]:
        vac = predict_throw(a, d, h, ball=tiny)
        air = predict_throw(a, d, h, ball=tiny, drag=True)
        assert air.drag_per_m > 0 and air.step_s is not None
        assert air.speed == pytest.approx(vac.speed, rel=1e-6)
        ts = np.linspace(0.0, 1.2 * vac.time_at_x(d), 25)
        scale = np.max(np.abs(vac.position(ts)))
        assert np.max(np.abs(air.position(ts) - vac.position(ts))) <= 1e-6 * scale
        np.testing.assert_allclose(
            air.velocity(ts), vac.velocity(ts), rtol=0, atol=1e-6 * vac.speed
        )
        assert air.time_at_x(d) == pytest.approx(vac.time_at_x(d), rel=1e-6)


# --------------------------------------------------------------------------- RK4 accuracy


def _reference(flight: Flight, ts: np.ndarray) -> np.ndarray:
    """(len(ts), 6) positions and velocities from DOP853 at rtol 1e-13."""
    k = flight.drag_per_m

    def rhs(_t, y):
        v = y[3:]
        return np.concatenate([v, GRAVITY_M_S2 - k * np.linalg.norm(v) * v])

    y0 = np.concatenate([flight.p0, flight.v0])
    out = np.empty((ts.size, 6))
    for sel in (ts >= 0, ts < 0):
        if sel.any():
            end = ts[sel][np.argmax(np.abs(ts[sel]))]
            sol = solve_ivp(
                rhs, (0.0, end), y0, method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True
            )
            out[sel] = sol.sol(ts[sel]).T
    return out


@pytest.mark.parametrize(
    "throw",
    [
        (30.0, 1.5, 0.0, "seed"),
        (45.0, 3.0, 0.5, "tennis"),
        (10.0, 20.0, 1.0, "tennis"),
        (60.0, 30.0, 0.0, "baseball"),
        (5.0, 60.0, -5.0, "tennis"),  # ~70 m/s
        (80.0, 4.0, 1.0, "tennis"),
    ],
)
def test_rk4_table_matches_solve_ivp(throw):
    a, d, h, ball = throw
    f = predict_throw(a, d, h, ball=ball, drag=True)
    T = f.time_at_x(d)
    rng = np.random.default_rng(7)
    # inside the shooting's table, beyond it (table grows), and before t = 0
    ts = np.concatenate([rng.uniform(0.0, T, 20), rng.uniform(T, 2.0 * T, 10), [-0.05, -0.2]])
    ref = _reference(f, ts)
    np.testing.assert_allclose(f.position(ts), ref[:, :3], rtol=0, atol=1e-6)
    np.testing.assert_allclose(f.velocity(ts), ref[:, 3:], rtol=0, atol=1e-6)


def test_drag_flight_out_of_plane():
    """A general drag state (y velocity, p0 off origin): the planar reduction holds in 3D."""
    f = Flight(np.array([0.1, -0.2, 1.0]), np.array([3.0, 1.0, 2.5]), BALLS["tennis"], 0.05)
    ts = np.linspace(-0.1, 1.0, 12)
    ref = _reference(f, ts)
    np.testing.assert_allclose(f.position(ts), ref[:, :3], rtol=0, atol=1e-6)
    np.testing.assert_allclose(f.velocity(ts), ref[:, 3:], rtol=0, atol=1e-6)
    t = f.time_at_x(2.0)
    assert f.position(t)[0] == pytest.approx(2.0, abs=1e-9)


def test_metadata():
    f = predict_throw(30.0, 1.5, ball="tennis", drag=True)
    md = f.to_metadata()
    assert set(md) == {"p0", "v0", "radius", "mass", "drag"}
    assert md["radius"] == pytest.approx(0.0335) and md["mass"] == pytest.approx(0.057)
    assert md["drag"] == pytest.approx(BALLS["tennis"].drag_per_m)
    assert md["v0"] == pytest.approx(list(f.v0))
    json.dumps(md)
    assert predict_throw(30.0, 1.5, ball="tennis").to_metadata()["drag"] == 0.0


# --------------------------------------------------------------------------- observations


def _observe(flight: Flight, seed: int, n: int = 30, rate_hz: float = 100.0, sigma: float = 0.005):
    rng = np.random.default_rng(seed)
    ts = np.arange(n) / rate_hz
    return ts, flight.position(ts) + rng.normal(0.0, sigma, (n, 3))


@pytest.mark.parametrize("drag", [False, True])
def test_fit_recovers_throw_and_intercept(drag):
    """30 samples at 100 Hz, 5 mm noise; intercept within 2 cm and 3 sigma."""
    true = predict_throw(30.0, 1.5, ball="seed", drag=drag)
    ts, ps = _observe(true, seed=2024)
    fit = fit_observations(ts, ps, ball="seed", drag_per_m=true.drag_per_m)
    assert isinstance(fit, FitResult)
    assert fit.covariance.shape == (6, 6)
    np.testing.assert_allclose(fit.covariance, fit.covariance.T)
    assert np.all(np.linalg.eigvalsh(fit.covariance) > 0)
    assert 0.003 < fit.residual_rms < 0.007
    assert fit.flight.drag_per_m == true.drag_per_m
    sig_v = np.sqrt(np.diag(fit.covariance)[3:])
    assert np.all(np.abs(fit.flight.v0 - true.v0) <= 4 * sig_v)

    t, p, cov_p, sigma_t = predict_intercept(fit, 1.5)
    t_true = true.time_at_x(1.5)
    p_true = true.position(t_true)
    assert p[0] == 1.5 and cov_p.shape == (3, 3)
    assert cov_p[0, 0] == 0.0
    assert np.linalg.norm(p - p_true) < 0.02
    assert abs(t - t_true) < 0.01
    assert abs(t - t_true) <= 3 * sigma_t
    for ax in (1, 2):
        assert abs(p[ax] - p_true[ax]) <= 3 * math.sqrt(cov_p[ax, ax])


def test_fit_uncertainty_is_calibrated():
    """Over 100 noise draws the vacuum intercept errors scale with the reported sigma."""
    true = predict_throw(45.0, 3.0, ball="tennis")
    t_true = true.time_at_x(3.0)
    p_true = true.position(t_true)
    z = []
    for seed in range(100):
        fit = fit_observations(*_observe(true, seed))
        t, p, cov_p, sigma_t = predict_intercept(fit, 3.0)
        z.append([(t - t_true) / sigma_t, *((p[1:] - p_true[1:]) / np.sqrt(np.diag(cov_p)[1:]))])
    z = np.array(z)
    assert np.all((z.std(axis=0) > 0.75) & (z.std(axis=0) < 1.3))
    assert np.mean(np.abs(z) < 3) > 0.97


def test_fit_exact_data_is_exact():
    true = Flight(np.array([0.2, 0.1, 1.0]), np.array([4.0, -0.5, 3.0]), BALLS["seed"], 0.0)
    ts = np.linspace(0.0, 0.2, 5)
    fit = fit_observations(ts, true.position(ts))
    np.testing.assert_allclose(fit.flight.p0, true.p0, atol=1e-12)
    np.testing.assert_allclose(fit.flight.v0, true.v0, atol=1e-12)
    assert fit.residual_rms < 1e-12


def test_csv_round_trip_to_intercept(tmp_path):
    true = predict_throw(30.0, 1.5, ball="tennis", drag=True)
    ts, ps = _observe(true, seed=5)
    path = tmp_path / "obs.csv"
    lines = ["t,x,y,z"] + [f"{t:.4f},{x:.6f},{y:.6f},{z:.6f}" for t, (x, y, z) in zip(ts, ps)]
    path.write_text("\n".join(lines) + "\n")
    ts2, ps2 = load_observations_csv(path, min_rows=6)
    np.testing.assert_allclose(ts2, ts, atol=1e-9)
    np.testing.assert_allclose(ps2, ps, atol=1e-6)
    fit = fit_observations(ts2, ps2, ball="tennis", drag_per_m=true.drag_per_m)
    _, p, _, _ = predict_intercept(fit, 1.5)
    assert np.linalg.norm(p - true.position(true.time_at_x(1.5))) < 0.02


# --------------------------------------------------------------------------- errors


@pytest.mark.parametrize("angle", [0.0, 90.0, -5.0, float("nan"), float("inf"), 120.0, "abc"])
def test_bad_angle(angle):
    with pytest.raises(InputError, match="angle"):
        predict_throw(angle, 1.5)


@pytest.mark.parametrize("dist", [0.0, -1.0, float("nan"), float("inf"), None])
def test_bad_dist(dist):
    with pytest.raises(InputError, match="dist"):
        predict_throw(30.0, dist)


@pytest.mark.parametrize("height", [10.0, -10.0, 12.0, float("nan"), float("-inf")])
def test_bad_height(height):
    with pytest.raises(InputError, match="height"):
        predict_throw(80.0, 1.5, height)


@pytest.mark.parametrize("drag", [False, True])
def test_unreachable_height(drag):
    # 30 deg over 1.5 m rises at most to 1.5 tan 30 = 0.866 m
    for h in (0.866026, 1.0, 5.0):
        with pytest.raises(InputError, match="tan"):  # no such throw: bad input (issue 14)
            predict_throw(30.0, 1.5, h, drag=drag)
    assert issubclass(InfeasibleError, PlannerError)


def test_too_fast():
    # reachable in principle, but only just below the line of sight: > 100 m/s
    with pytest.raises(InputError, match="m/s"):
        predict_throw(30.0, 1.5, 0.8659)
    # vacuum needs ~50 m/s, drag more than 100 m/s
    predict_throw(45.0, 250.0)
    with pytest.raises(InputError, match="100 m/s"):
        predict_throw(45.0, 250.0, ball="tennis", drag=True)


def test_unknown_ball():
    with pytest.raises(InputError, match="baseball, golf, seed, tennis, vacuum"):
        predict_throw(30.0, 1.5, ball="football")
    with pytest.raises(InputError):
        predict_throw(30.0, 1.5, ball=3)


def test_bad_ball_and_flight():
    with pytest.raises(InputError):
        Ball("x", 0.0, 0.03, 0.5)
    with pytest.raises(InputError):
        Ball("x", 0.05, 0.03, -0.1)
    with pytest.raises(InputError):
        Ball("x", 0.05, float("nan"), 0.5)
    with pytest.raises(InputError):
        Flight(np.zeros(2), np.ones(3), BALLS["seed"], 0.0)
    with pytest.raises(InputError):
        Flight(np.zeros(3), np.array([1.0, np.nan, 0.0]), BALLS["seed"], 0.0)
    with pytest.raises(InputError):
        Flight(np.zeros(3), np.ones(3), BALLS["seed"], -0.1)
    f = predict_throw(30.0, 1.5)
    with pytest.raises(InputError):
        f.position(float("nan"))
    with pytest.raises(InputError):
        predict_throw(30.0, 1.5, drag=True).position(1e4)
    # quadratic drag blows up going back in time (v ~ 1/(1 + k v0 t)): refused, table intact
    fast = Flight(np.zeros(3), np.array([10.0, 0.0, 0.0]), BALLS["tennis"], 0.5)
    with pytest.raises(InputError, match="diverges"):
        fast.position(-1.0)
    assert np.all(np.isfinite(fast.position(np.array([-0.01, 0.5]))))


def test_plane_never_crossed():
    f = predict_throw(30.0, 1.5)
    with pytest.raises(InfeasibleError, match="never reaches"):
        f.time_at_x(-1.0)
    g = Flight(np.zeros(3), np.array([0.0, 0.0, 5.0]), BALLS["seed"], 0.02)
    with pytest.raises(InfeasibleError):
        g.time_at_x(1.0)
    assert f.time_at_x(0.0) == 0.0


def test_bad_observations():
    ts = np.linspace(0, 0.1, 5)
    ps = np.zeros((5, 3))
    with pytest.raises(InputError, match="at least 3"):
        fit_observations(ts[:2], ps[:2])
    with pytest.raises(InputError, match="at least 6"):
        fit_observations(ts, ps, drag_per_m=0.02)
    with pytest.raises(InputError, match="increasing"):
        fit_observations(ts[::-1], ps)
    bad = ps.copy()
    bad[2, 1] = np.nan
    with pytest.raises(InputError, match="finite"):
        fit_observations(ts, bad)
    with pytest.raises(InputError, match=r"\(N, 3\)"):
        fit_observations(ts, ps[:, :2])
    with pytest.raises(InputError, match="drag_per_m"):
        fit_observations(ts, ps, drag_per_m=-1.0)


BAD_CSV = {
    "missing": (None, "not found"),
    "empty": ("", "empty"),
    "header": ("time,x,y,z\n0,0,0,0\n0.01,0,0,0\n0.02,0,0,0\n", "header"),
    "short_header": ("t,x,y\n0,0,0\n0.01,0,0\n0.02,0,0\n", "header"),
    "non_numeric": ("t,x,y,z\n0,0,0,0\n0.01,abc,0,0\n0.02,0,0,0\n", "line 3: x = 'abc'"),
    "nan": ("t,x,y,z\n0,0,0,0\n0.01,0,nan,0\n0.02,0,0,0\n", "line 3: y = 'nan' is not finite"),
    "inf": ("t,x,y,z\n0,0,0,0\n0.01,0,0,inf\n0.02,0,0,0\n", "not finite"),
    "columns": ("t,x,y,z\n0,0,0,0\n0.01,0,0\n0.02,0,0,0\n", "line 3: expected 4 values"),
    "too_few": ("t,x,y,z\n0,0,0,0\n0.01,0,0,0\n", "2 observation rows, need at least 3"),
    "not_increasing": ("t,x,y,z\n0,0,0,0\n0.02,0,0,0\n0.01,0,0,0\n", "line 4: time"),
    "repeated_time": ("t,x,y,z\n0,0,0,0\n0,0,0,0\n0.01,0,0,0\n", "not after"),
}


@pytest.mark.parametrize("case", sorted(BAD_CSV))
def test_bad_csv(tmp_path, case):
    text, message = BAD_CSV[case]
    path = tmp_path / f"{case}.csv"
    if text is not None:
        path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        load_observations_csv(path)
    assert "\n" not in str(info.value)


def test_csv_min_rows_for_drag(tmp_path):
    path = tmp_path / "five.csv"
    path.write_text("t,x,y,z\n" + "".join(f"{i / 100},{i / 10},0,1\n" for i in range(5)))
    ts, ps = load_observations_csv(path)
    assert ts.shape == (5,) and ps.shape == (5, 3)
    with pytest.raises(InputError, match="need at least 6"):
        load_observations_csv(path, min_rows=6)


def test_csv_tolerates_spaces_and_blank_lines(tmp_path):
    path = tmp_path / "ok.csv"
    path.write_text(" t , x , y , z \n0, 0, 0, 1\n\n0.01, 0.04, 0, 1.03\n0.02,0.08,0,1.06\n\n")
    ts, ps = load_observations_csv(path)
    np.testing.assert_allclose(ts, [0.0, 0.01, 0.02])
    np.testing.assert_allclose(ps[:, 0], [0.0, 0.04, 0.08])


# ------------------------------------------------------------------ impossible observations


DATA = Path(__file__).resolve().parent / "data"


@pytest.mark.parametrize("drag", [False, True])
def test_huge_observations_are_bad_input_with_no_warning(drag):
    """Issue 14 (shared/repro/observations_huge_values.csv): finite positions of 4e298 m."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy overflow warning would fail here
        ts, ps = load_observations_csv(DATA / "observations_huge_values.csv",
                                       min_rows=6 if drag else 3)
        with pytest.raises(InputError, match="observation 2: .* farther than any throw"):
            fit_observations(ts, ps, "tennis", 0.5 if drag else 0.0)


def test_observations_faster_than_any_throw_are_bad_input():
    t = np.linspace(0.0, 0.05, 6)
    ps = np.stack([1e4 * t, 0 * t, 0 * t], axis=1)  # 10 km/s: within range, no throw
    with pytest.raises(InputError, match="faster than any throw"):
        fit_observations(t, ps, "tennis", 0.0)
    with pytest.raises(InputError, match="more than 100 s from the launch"):
        fit_observations(np.array([0.0, 1.0, 200.0]), np.zeros((3, 3)), "tennis", 0.0)

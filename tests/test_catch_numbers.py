"""Honest numbers (issue 31, item 5): the impact at contact and the riding ball named apart
with every motor's headroom at each; ``--observations`` without ``--angle``; the live drag
fit's uncertainty, and the ball's known drag when the window cannot see it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cli import main as cli_main
from planner.catch import CatchSession, plan_throw
from planner.catch.flight.dragfit import KNOWN_REL_SIGMA, estimate_drag
from planner.catch.flight.observe import fit_observations
from planner.catch.flight.path import Flight, get_ball, predict_throw
from planner.trajfile import parse_trajectory

BALL = get_ball("tennis")


def test_impact_and_riding_are_named_apart(pl, capsys, tmp_path):
    """30 deg from 1.5 m: the pad's impact at contact (m v^2 / 2d at the relative speed,
    ~17 N) and the ball riding the palm afterwards (about its weight), each with every
    motor's headroom; the summary and --json name both."""
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    c = p.forces.contact
    v = c.impact.speed_m_s
    assert c.impact.time_s == pytest.approx(p.intercept.t_s)
    assert c.impact.force_n == pytest.approx(BALL.mass_kg * v * v / (2 * pl.hand.pad_give_m), rel=0.1)
    assert c.impact.force_n > 10.0 and c.riding.force_n < 3.0 and c.riding.speed_m_s == 0.0
    assert c.riding.time_s > c.impact.time_s
    n = len(pl.hand.motor_names)
    assert len(c.impact.motor_headroom) == len(c.riding.motor_headroom) == n
    assert cli_main(["catch", "--angle", "30", "--dist", "1.5", "--json",
                     "-o", str(tmp_path / "c.csv")]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["impact"]["force_n"] == pytest.approx(c.impact.force_n)
    assert d["riding"]["force_n"] == pytest.approx(c.riding.force_n)
    assert set(d["impact"]["motor_headroom"]) == set(pl.hand.motor_names)
    assert d["stopping"]["worst_is"] == "riding the palm"
    assert cli_main(["catch", "--angle", "30", "--dist", "1.5",
                     "-o", str(tmp_path / "c.csv")]) == 0
    err = capsys.readouterr().err
    assert "impact at contact: " in err and "riding the palm: " in err


def _obs_csv(path, angle=35.0, dist=2.0, n=30):
    fl = predict_throw(angle, dist, 0.0, BALL)
    ts = np.arange(1, n + 1) / 100
    ps = fl.position(ts)
    path.write_text("t,x,y,z\n" + "".join(f"{t},{x},{y},{z}\n" for t, (x, y, z) in zip(ts, ps)))
    return path


def test_observations_without_angle(tmp_path, capsys):
    """The throw is the observations': no --angle needed; one given is said, not used."""
    obs = _obs_csv(tmp_path / "o.csv")
    out = str(tmp_path / "c.csv")
    assert cli_main(["catch", "--observations", str(obs), "--dist", "2.0", "--json",
                     "-o", out]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["throw"]["angle_deg"] == pytest.approx(35.0, abs=0.01)
    assert d["throw"]["observations"] == 30
    assert cli_main(["catch", "--observations", str(obs), "--angle", "10", "--dist", "2.0",
                     "--json", "-o", out]) == 0
    d2 = json.loads(capsys.readouterr().out)
    assert d2["intercept_t_s"] == d["intercept_t_s"]  # the angle changes nothing planned
    assert any("--angle 10 said, not used" in x for x in d2["notes"])
    assert cli_main(["catch", "--dist", "2.0", "-o", out]) == 2


def test_drag_fit_reports_what_the_window_sees():
    """A ball with half the tennis ball's drag (k 0.010): noiseless, the window's fit finds
    it; at 5 mm noise 0.25 s cannot see it (1-sigma above half of k) and the ball's known k
    is what is flown, with its own uncertainty; 0.5 s at 200 Hz sees it."""
    fl = predict_throw(35.0, 2.0, 0.0, BALL, drag=True)
    true = Flight(fl.p0, fl.v0, BALL, 0.010)
    rng = np.random.default_rng(1)
    for until, seen in ((0.25, False), (0.5, True)):
        ts = np.arange(1, int(until * 200)) / 200
        ps = true.position(ts)
        e = estimate_drag(ts, ps, fit_observations(ts, ps, BALL, BALL.drag_per_m).flight, BALL)
        assert e.fit_per_m == pytest.approx(0.010, abs=0.0005) and e.fit_sigma_per_m < 1e-5
        noisy = ps + rng.normal(0.0, 0.005, ps.shape)
        e = estimate_drag(ts, noisy, fit_observations(ts, noisy, BALL, BALL.drag_per_m).flight,
                          BALL)
        assert e.seen is seen and e.used_per_m == BALL.drag_per_m
        assert e.known_sigma_per_m == pytest.approx(KNOWN_REL_SIGMA * BALL.drag_per_m)
        assert abs(e.fit_per_m - 0.010) < 3 * e.fit_sigma_per_m
        assert ("cannot see it" in e.describe()) is not seen


def test_a_live_session_states_its_drag(pl):
    """The end marker of a live drag session: the drag flown (the ball's known), its
    uncertainty, the window's fit; the plan's notes say it."""
    fl = predict_throw(35.0, 2.0, 0.0, BALL, drag=True)
    rng = np.random.default_rng(3)
    s = CatchSession(2.0, 0.0, ball=BALL, drag=True, planner=pl)
    for k in range(1, 300):
        t = k / 200
        s.observe(t, fl.position(t) + rng.normal(0.0, 0.005, 3))
        if s.done:
            break
    end = parse_trajectory(s.text).end
    de = end["drag_estimate"]
    assert de["used_per_m"] == end["ball"]["drag"] == BALL.drag_per_m
    assert de["fit_sigma_per_m"] > 0 and isinstance(de["seen"], bool)
    assert any(n.startswith("live: drag k") for n in s.plan.notes)

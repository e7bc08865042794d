"""The catch planner of one hand and mount (``planner.catch.plan.planner``): the soft stop
made once per plan for what it depends on (``stop_of``), the plan the same as with every
stop made anew. No wall-clock assertions."""

from __future__ import annotations

import planner.catch.plan.planner as catch_planner
from planner.catch.plan.api import plan_throw, write_plan
from planner.catch.plan.planner import stop_of


def test_stop_of_makes_each_key_once_within_one_plan():
    """``stop_of``: with one plan's dict, ``make`` runs once per key and the same result is
    given back; without (None), every call makes it anew."""
    made = []

    def make(key):
        return lambda: made.append(key) or (key, len(made))

    stops: dict = {}
    first = stop_of(stops, ("arm", 30.0), make("arm"))
    again = stop_of(stops, ("arm", 30.0), make("arm"))
    other = stop_of(stops, ("rig", 30.0), make("rig"))
    assert again is first and other == ("rig", 2) and made == ["arm", "rig"]
    assert stop_of(None, ("arm", 30.0), make("arm")) == ("arm", 3)
    assert made == ["arm", "rig", "arm"] and len(stops) == 2


def test_the_plan_is_the_same_with_its_stops_made_once(pl, tmp_path, monkeypatch):
    """0 m / 75 deg / 1.0 m (the arm alone fails, the rig's reach axis catches it: the
    turn's modes and the reach's fallbacks ask for the same stops): its file is the same
    byte for byte with the stops made once per plan and with every stop made anew, and
    fewer stops are searched (none twice for one key)."""
    searched = []
    plan_stop = catch_planner.plan_stop

    def counted(*args, **kwargs):
        searched.append((args[0] is pl.rig_dyn, id(args[6]), args[10], args[11], kwargs["grid"]))
        return plan_stop(*args, **kwargs)

    monkeypatch.setattr(catch_planner, "plan_stop", counted)
    once = plan_throw(75.0, 1.0, 0.0, planner=pl)
    made_once = list(searched)
    searched.clear()
    monkeypatch.setattr(catch_planner, "stop_of", lambda stops, key, make: make())
    anew = plan_throw(75.0, 1.0, 0.0, planner=pl)
    assert once.feasible and anew.feasible
    write_plan(once, str(tmp_path / "once.csv"))
    write_plan(anew, str(tmp_path / "anew.csv"))
    assert (tmp_path / "once.csv").read_bytes() == (tmp_path / "anew.csv").read_bytes()
    assert len(made_once) < len(searched)
    assert len(set(made_once)) == len(made_once)

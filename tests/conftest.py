"""Fixtures shared by the test modules: the shipped hands, loaded once per module, the
default hand's catch planner, and a trajectory file as the command line plans it."""

import contextlib
import io
from pathlib import Path

import pytest

from planner.hand.model import HandModel, load_hand

# the helper modules' asserts explain their failures as a test module's do
pytest.register_assert_rewrite("tests.midibytes", "tests.handfiles", "tests.trajbuild",
                               "tests.hardening")


@pytest.fixture(scope="module")
def hand() -> HandModel:
    """The default hand (the seed's 1.5x tendon hand)."""
    return load_hand("default")


@pytest.fixture(scope="module")
def mk5() -> HandModel:
    """The Mk5 hand (four-bar couplings, seed 003)."""
    return load_hand("mk5")


@pytest.fixture(scope="module")
def pl():
    """The default hand's catch planner (``planner.catch.plan.api.get_planner``: built once
    per process, shared by the catch tests)."""
    from planner.catch.plan.api import get_planner

    return get_planner("default")


@pytest.fixture(scope="module")
def facing(pl):
    """``plan_throw`` on the default planner with the palm-up stage replaced by the identity:
    the plan facing the ball after every other stage (the throws the palm-up catch now
    catches, as they were planned before it: their facing plans' numbers)."""
    from planner.catch.plan import palmup
    from planner.catch.plan.api import plan_throw

    def plan(angle_deg: float, dist_m: float, height_m: float = 0.0):
        mp = pytest.MonkeyPatch()
        mp.setattr(palmup, "palm_up_fallback", lambda plans, plan, *a, **kw: plan)
        try:
            return plan_throw(angle_deg, dist_m, height_m, planner=pl)
        finally:
            mp.undo()

    return plan


@pytest.fixture(scope="module")
def planned(tmp_path_factory) -> Path:
    """A real planned trajectory: ``cli.py play songs/scale.mid -o X`` (the hardening
    tests' undamaged file; test_play_stream.py has a ``planned`` of its own)."""
    import cli
    from tests.hardening import SCALE

    path = tmp_path_factory.mktemp("planned") / "scale.csv"
    with contextlib.redirect_stderr(io.StringIO()):
        assert cli.main(["play", str(SCALE), "-o", str(path)]) == 0
    return path

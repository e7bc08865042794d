"""Fixtures shared by the test modules: the shipped hands, loaded once per module."""

import pytest

from planner.hand.model import HandModel, load_hand

# the helper modules' asserts explain their failures as a test module's do
pytest.register_assert_rewrite("tests.midibytes", "tests.handfiles", "tests.trajbuild")


@pytest.fixture(scope="module")
def hand() -> HandModel:
    """The default hand (the seed's 1.5x tendon hand)."""
    return load_hand("default")


@pytest.fixture(scope="module")
def mk5() -> HandModel:
    """The Mk5 hand (four-bar couplings, seed 003)."""
    return load_hand("mk5")

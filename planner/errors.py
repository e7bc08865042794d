"""The planner's one exception family.

``PlannerError`` is the root. ``InputError`` means the user gave us something
we cannot use (exit status 2); ``InfeasibleError`` means the request is valid
but the hand cannot do it (exit status 1 under ``--strict``). Errors that
come out of a solver carry the problem they failed on in ``.problem``.
"""

from __future__ import annotations

from typing import Any


class PlannerError(Exception):
    """Base class of every error the planner raises on purpose."""

    def __init__(self, message: str, problem: Any = None) -> None:
        super().__init__(message)
        self.problem = problem


class InputError(PlannerError):
    """Bad input: a file, an argument or a hand description we cannot use."""


class InfeasibleError(PlannerError):
    """A valid request the hand cannot carry out (reach, speed, torque)."""


class SolverError(PlannerError):
    """A numerical solver failed; ``problem`` holds what it was given."""

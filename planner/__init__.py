"""Task planner for a tendon-driven humanoid robot hand.

Pipeline: midi -> notes -> fingering -> targets -> IK -> trajectory -> writer,
with the hand model and the catch planner beside it. See README.md.
"""

from planner.errors import InfeasibleError, InputError, PlannerError, SolverError

__all__ = ["InfeasibleError", "InputError", "PlannerError", "SolverError"]

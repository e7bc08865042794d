"""Task planner for a tendon-driven humanoid robot hand.

Play: music (MIDI -> notes) -> play (atlas -> fingering -> motion -> stream) -> trajfile,
the plan's own replay (selfcheck) as its summary; catch beside it; check replays any
file independently; the hand model under all of them. See README.md and docs/.
"""

from planner.errors import InfeasibleError, InputError, PlannerError, SolverError

__all__ = ["InfeasibleError", "InputError", "PlannerError", "SolverError"]

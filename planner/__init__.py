"""Task planner for a tendon-driven humanoid robot hand.

Play: music (MIDI -> notes) -> play (atlas -> fingering -> motion -> stream) -> trajfile,
the plan's own replay (selfcheck) as its summary; catch beside it; check replays any
file independently; the hand model under all of them. See README.md and docs/.

The public API (imported on first use, so that ``import planner`` stays light):

* ``load_hand(name_or_path)`` -> ``HandModel``; ``load_song(path, track=, channel=,
  transpose=)`` -> ``Song``;
* ``plan_song(song, hand, out_path=None, rate_hz=100.0)`` -> ``PlayPlan`` (rows streamed
  to ``out_path``, ``'-'`` for stdout; without one, in memory: ``.trajectory``,
  ``.write(path)``), with a ``Planner(hand)`` to reuse across songs;
* ``plan_catch(angle_deg, dist_m, height_m, hand, out_path, ...)`` -> ``CatchResult``;
* ``check_trajectory(traj_path or Trajectory, song_path or Song=None)`` -> ``CheckReport``;
* ``read_trajectory(path)`` -> ``Trajectory`` (times, joint and motor arrays, metadata).
"""

from __future__ import annotations

from planner.errors import InfeasibleError, InputError, PlannerError, SolverError
from planner.lazy import lazy_names

_API = {
    "load_hand": "planner.hand.model",
    "HandModel": "planner.hand.model",
    "load_song": "planner.music.midi",
    "Song": "planner.music.midi",
    "Note": "planner.music.midi",
    "Planner": "planner.play",
    "PlayPlan": "planner.play",
    "plan_song": "planner.play",
    "plan_catch": "planner.catch",
    "check_trajectory": "planner.check",
    "read_trajectory": "planner.trajfile",
}

__all__ = [
    "HandModel",
    "InfeasibleError",
    "InputError",
    "Note",
    "Planner",
    "PlannerError",
    "PlayPlan",
    "SolverError",
    "Song",
    "check_trajectory",
    "load_hand",
    "load_song",
    "plan_catch",
    "plan_song",
    "read_trajectory",
]


__getattr__ = lazy_names(__name__, _API)

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
* ``check_trajectory(traj_path or Trajectory, song_path or Song=None)`` -> ``CheckReport``
  (a two-hand file: ``PairReport``, each hand's ``CheckReport`` and both together);
* ``plan_two_hands(song, PairPlanner(left, right), out_path=None)`` -> ``TwoHandPlan``:
  a song (``load_song(path, every_part=True)``) planned on two hands into one two-hand
  file (``play --hands 2``);
* ``PairWriter(path, (left, right), metadata)``: a two-hand plan written (version 3);
  ``read_plan(path)`` -> ``PlanFile``, or ``PairPlan`` for a two-hand file;
* ``read_trajectory(path)`` -> ``Trajectory`` (times, joint and motor arrays, metadata);
* ``CatchSession(dist_m, height_m, ...)``: a catch planned live, ``observe(t_s, xyz)``
  per observation, ``finish()``;
* ``simulate_trajectory(traj_path, song_path=None, contact="full")`` ->
  ``SimulateReport`` (the physics replay; needs the ``physics`` extra, MuJoCo).

Every name, its fields and units: docs/user/api.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from planner.errors import InfeasibleError, InputError, PlannerError, SolverError
from planner.lazy import lazy_dir, lazy_names

if TYPE_CHECKING:  # (what editors and type checkers see; at run time: on first use)
    from planner.catch import CatchSession, plan_catch
    from planner.check import CheckReport, check_trajectory
    from planner.check.pairreport import PairReport
    from planner.hand.model import HandModel, load_hand
    from planner.music.midi import Note, Song, load_song
    from planner.pairfile import PairPlan, PairWriter
    from planner.planfile import read_plan
    from planner.play import Planner, PlayPlan, plan_song
    from planner.play.twohands import PairPlanner, plan_two_hands
    from planner.play.twoplan import TwoHandPlan
    from planner.simulate import simulate_trajectory
    from planner.simulate.report import SimulateReport
    from planner.trajfile import Trajectory, read_trajectory

_API = {
    "load_hand": "planner.hand.model",
    "HandModel": "planner.hand.model",
    "load_song": "planner.music.midi",
    "Song": "planner.music.midi",
    "Note": "planner.music.midi",
    "Planner": "planner.play",
    "PlayPlan": "planner.play",
    "plan_song": "planner.play",
    "PairPlanner": "planner.play.twohands",
    "TwoHandPlan": "planner.play.twoplan",
    "plan_two_hands": "planner.play.twohands",
    "plan_catch": "planner.catch",
    "CatchSession": "planner.catch",
    "check_trajectory": "planner.check",
    "CheckReport": "planner.check",
    "PairReport": "planner.check.pairreport",
    "PairWriter": "planner.pairfile",
    "PairPlan": "planner.pairfile",
    "read_plan": "planner.planfile",
    "read_trajectory": "planner.trajfile",
    "Trajectory": "planner.trajfile",
    "simulate_trajectory": "planner.simulate",
    "SimulateReport": "planner.simulate.report",
}

__all__ = [
    "CatchSession",
    "CheckReport",
    "HandModel",
    "InfeasibleError",
    "InputError",
    "Note",
    "PairPlan",
    "PairPlanner",
    "PairReport",
    "PairWriter",
    "Planner",
    "PlannerError",
    "PlayPlan",
    "SimulateReport",
    "SolverError",
    "Song",
    "Trajectory",
    "TwoHandPlan",
    "check_trajectory",
    "load_hand",
    "load_song",
    "plan_catch",
    "plan_song",
    "plan_two_hands",
    "read_plan",
    "read_trajectory",
    "simulate_trajectory",
]


__getattr__ = lazy_names(__name__, _API)
__dir__ = lazy_dir(globals(), _API)

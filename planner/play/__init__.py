"""Play: a MIDI song -> a hand trajectory, as one optimisation (docs/play-second-design.md).

The stages, in order: ``atlas`` (press, hover and crossing poses per finger and key,
computed once per hand and shipped), ``profile`` and ``moves`` (time-optimal joint moves
between atlas poses, timed at their key crossings), ``costs`` and ``fingering`` (fingers
and hand positions as one dynamic programme whose costs are frames of music lost),
``motion`` (the fingering's notes as timed segments of every finger and the rail),
``stream`` (rows written as they are final, the planner's own replay as its verdict) and
``summary`` (what ``cli.py play`` prints and returns).
"""

from planner.play.stream import Planner, PlayPlan, plan_song
from planner.play.summary import format_summary, play_cli

__all__ = ["Planner", "PlayPlan", "format_summary", "plan_song", "play_cli"]

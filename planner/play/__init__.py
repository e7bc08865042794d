"""Play: a MIDI song -> a hand trajectory, as one optimisation (docs/history/play-second-design.md).

The stages, in order: ``atlas`` (press, hover and crossing poses per finger and key,
computed once per hand and shipped), ``profile`` and ``moves`` (time-optimal joint moves
between atlas poses, timed at their key crossings), ``costs`` and ``fingering`` (fingers
and hand positions as one dynamic programme whose costs are frames of music lost),
``motion`` (the fingering's notes as timed segments of every finger and the rail),
``stream`` (rows written as they are final, the planner's own replay as its verdict) and
``summary`` (what ``cli.py play`` prints and returns).

The package's names are imported on first use (as ``planner``'s): a catch imports
``planner.play.fingerbody`` alone, not the play planner (its MIDI reader, mido, the
fingering's costs: 60 ms of ``cli.py catch``'s start, ``python -X importtime``).
"""

from __future__ import annotations

from planner.lazy import lazy_names

_API = {
    "Planner": "planner.play.stream",
    "PlayPlan": "planner.play.stream",
    "plan_song": "planner.play.stream",
    "format_summary": "planner.play.summary",
}

__all__ = ["Planner", "PlayPlan", "format_summary", "plan_song"]


__getattr__ = lazy_names(__name__, _API)

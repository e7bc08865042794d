"""Play: a MIDI song -> a hand trajectory.

``legacy`` is the first planner (rules and repairs on a chunked timeline); the second
design grows beside it (issue 13): ``atlas`` (press and hover configurations per finger
and key, computed once per hand), ``profile`` (time-optimal joint moves), then the
fingering and motion stages. The CLI runs ``legacy`` until the second design is better on
every benchmark set.
"""

from planner.play.legacy import Planner, PlayResult, format_summary, plan_song, play_cli

__all__ = ["Planner", "PlayResult", "format_summary", "plan_song", "play_cli"]

"""Where within the row grid the plan puts a note's key down and lets it up.

A note sounds over the rows from the first row at or after its onset to the last row
before its offset (``planner.check.criteria.expected_keys``); ``check`` sees a key down at
a row when a body of the hand is ``DOWN_DEPTH_M`` into it there. So the rows must cross
the key-down depth going down somewhere in the row interval before the note's first row,
and going up somewhere in the interval after its last row: anywhere inside those
intervals the check scores the same frames. Where inside them decides what the hardware
does with the rows.

The hand the servos drive sits above its rows wherever it pushes keys: each servo is a
position loop of finite stiffness (``planner.simulate.actuators``: peak torque at a few
degrees of motor error) and the keys' springs push back (0.5-1.4 N per key), a load the
rows' feedforward (the hand's own inverse dynamics) does not carry. Measured on the
sample songs in the physics replay (``docs/history/2026-12-06-press-timing.md``): the
wrist gives 1.1-1.3 mm at the fingertip with one key down and one resting, 2.2 mm with
three keys held; the pressing finger's MCP 0.4-0.6 mm static and up to 1.6 mm while the
key is struck. So a key goes down 2-2.5 mm of descent after the rows' crossing (0.5-0.8
of a 10 ms row at the descent's 3-4.5 mm per row) and comes up before it. Crossing at the
middle of the interval (as the plan did) left the physics one frame short at about a
third of the fast notes' starts and the chords' ends.

The plan therefore leads by that lag where its rows leave room: the key-down crossing
that much before the note's first row (``down_rows``) and the key-up crossing that much
after its last (``up_rows`` before the row after it), ``DRIVE_LAG_S`` in rows but never less than half a row (the interval's
middle, where the plan crossed before) nor closer than ``ROW_MARGIN_S`` to the
neighbouring row (which the check then sees up). At 100 Hz that is 0.9 of a row each
way; at 50 Hz and slower the middle, as before. The check judges the rows as they are
and scores them the same; the physics gains the margin it lacks.
"""

from __future__ import annotations

import math

# The hand's lag on a key in the physics replay, as a time: 2-2.5 mm of descent at the
# crossing's 0.3-0.45 m/s, 4.4-8.3 ms on the sample songs (the history page above); 10 ms bounds it.
DRIVE_LAG_S = 0.010
# Kept from the neighbouring row: the key crossing is found to ``moves.CROSS_TOL`` of its
# move's path (microseconds) and the rows are floats written to 1e-9; 1 ms (the physics
# replay's step) keeps the row before a note up and the row after it free by the rows,
# three orders of magnitude to spare.
ROW_MARGIN_S = 0.001


def down_rows(dt_s: float) -> float:
    """How far (rows) the key-down crossing precedes a note's first row, at rows ``dt_s``
    apart: the lag in rows, at least half a row, at most a row less the margin."""
    rate = 1.0 / dt_s
    return max(0.5, min(DRIVE_LAG_S * rate, 1.0 - ROW_MARGIN_S * rate))


def up_rows(dt_s: float) -> float:
    """How far (rows) the key-up crossing precedes the first row after a note: a row less
    ``down_rows`` (the lag after its last row), computed from the margin side."""
    rate = 1.0 / dt_s
    return min(0.5, max(1.0 - DRIVE_LAG_S * rate, ROW_MARGIN_S * rate))


def first_row(t_s: float, dt_s: float) -> int:
    """The index of the first row at or after ``t_s`` (rows ``dt_s`` apart from 0; the
    check's frames of a note are its rows from ``first_row(onset)`` to before
    ``first_row(offset)``)."""
    return math.ceil(t_s / dt_s - 1e-9)


def key_down_s(onset_s: float, dt_s: float) -> float:
    """When the rows put a key down for a note starting at ``onset_s``."""
    return (first_row(onset_s, dt_s) - down_rows(dt_s)) * dt_s


def key_up_s(offset_s: float, dt_s: float) -> float:
    """When the rows let a key up for a note (or a hold) ending at ``offset_s``."""
    return (first_row(offset_s, dt_s) - up_rows(dt_s)) * dt_s


def sounding_frames(down_s: float, up_s: float, dt_s: float) -> float:
    """The rows a key put down at ``down_s`` (``key_down_s``) and let up at ``up_s``
    (``key_up_s``) sounds: the frames between the two crossings, less the parts of a row
    they sit inside the neighbouring row intervals."""
    return (up_s - down_s) / dt_s - (down_rows(dt_s) - up_rows(dt_s))

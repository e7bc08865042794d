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

The lead is all the row allows, about the lag itself: a key that goes down later than its
``key_down_s`` by any amount is down in the physics after the note's first row, and the
physics loses that frame, where the check (judging the rows) loses none until the
lateness passes the lead. The fingering's programme counts a late key the physics' way
(``late_frames``): a whole frame from the first millisecond (``LATE_MIN_S``), a frame
more for each row's time later. And the rows say so: a key that cannot go down by its
target but could before the note's first row goes down just after that row instead
(``struck_s``): the physics loses that row either way, and the check, judging the rows,
now loses it too (it must never confirm a frame the physics refutes).
"""

from __future__ import annotations

import math

from planner.check.criteria import NOTE_HIT_FRACTION

# The hand's lag on a key in the physics replay, as a time: 2-2.5 mm of descent at the
# crossing's 0.3-0.45 m/s, 4.4-8.3 ms on the sample songs (the history page above); 10 ms bounds it.
DRIVE_LAG_S = 0.010
# Kept from the neighbouring row: the key crossing is found to ``moves.CROSS_TOL`` of its
# move's path (microseconds) and the rows are floats written to 1e-9; 1 ms (the physics
# replay's step) keeps the row before a note up and the row after it free by the rows,
# three orders of magnitude to spare.
ROW_MARGIN_S = 0.001
# A key down this much after its target is on time: far below a frame (10 ms at 100 Hz),
# above the float noise of the times it is worked out from.
LATE_MIN_S = 1e-3


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


def held_enough_s(onset_s: float, offset_s: float, down_s: float, cut_s: float,
                  up_s: float, dt_s: float) -> float:
    """The key-up of a note (``onset_s`` to ``offset_s``; down at ``down_s``, due up at
    ``up_s``) cut to ``cut_s`` (a move needs the finger), kept down long enough that the
    hardware still sounds the note where the check's rule does: a note the cut leaves
    down in at least ``NOTE_HIT_FRACTION`` of its frames (a hit by the rows) stays down
    until that share holds with the drive's lag at both ends (``DRIVE_LAG_S``: the key
    goes down later and comes up earlier than the rows); a cut that loses the note
    anyway is left as it is (the replay names it missed). The motion's rule
    (``Motion._to_high``, ``Motion.place``) and the programme's estimate of it
    (``ArmCosts._rail_loss``: a finger that lifts early for a move of the arm to strike
    again on time): ``held_enough_at`` of ``held_enough_parts``."""
    return held_enough_at(held_enough_parts(onset_s, offset_s, down_s, up_s, dt_s), cut_s)


def held_enough_parts(onset_s: float, offset_s: float, down_s: float, up_s: float,
                      dt_s: float) -> tuple:
    """What ``held_enough_s`` works out of a note and its key's down and up whatever the
    cut (the programme cuts one note many times: ``ArmCosts._cut_lifts``): its key-up,
    its last row, its first row the key is down at, the rows to hit it, the key-up that
    hits it, the rows' spacing."""
    k0, k1 = first_row(onset_s, dt_s), first_row(offset_s, dt_s)
    need = math.ceil(NOTE_HIT_FRACTION * (k1 - k0) - 1e-9)  # the note's rows to hit it
    first = max(k0, first_row(down_s + DRIVE_LAG_S, dt_s))
    return (up_s, k1, max(k0, first_row(down_s, dt_s)), need,
            (first + need - 1) * dt_s + DRIVE_LAG_S + ROW_MARGIN_S, dt_s)


def held_enough_at(parts: tuple, cut_s: float) -> float:
    """``held_enough_s`` of a note's ``held_enough_parts``, cut to ``cut_s``."""
    up_s, k1, start, need, hit_s, dt_s = parts
    if cut_s >= up_s:
        return cut_s
    # (its rows k with down_s <= k dt < cut_s: a hit by the rows, or lost anyway)
    if max(0, min(k1, first_row(cut_s, dt_s)) - start) < need:
        return cut_s
    return min(up_s, max(cut_s, hit_s))


def late_frames(late_s: float, dt_s: float) -> float:
    """The frames a note loses in the physics when its key goes down ``late_s`` after its
    ``key_down_s`` (rows ``dt_s`` apart): none when on time (within ``LATE_MIN_S``), else
    the rows from its first row to the one the drive's lag puts the key down before: the
    target leads the first row by about the lag, so a row for every row's time late,
    begun."""
    if late_s <= LATE_MIN_S:
        return 0.0
    return float(math.ceil(late_s / dt_s - 1e-9))


def struck_s(onset_s: float, down_s: float, dt_s: float) -> float:
    """When the rows put down the key of a note starting at ``onset_s`` that its moves
    could bring down at ``down_s`` at the earliest: then; or, when that is late (past
    ``key_down_s`` by more than ``LATE_MIN_S``) but before the note's first row,
    ``ROW_MARGIN_S`` after that row (the drive's lag loses the row in the physics either
    way: the rows lose it too). The motion's rule (``Motion.place``) and the programme's
    (``State.late``)."""
    edge = first_row(onset_s, dt_s) * dt_s + ROW_MARGIN_S
    if key_down_s(onset_s, dt_s) + LATE_MIN_S < down_s < edge:
        return edge
    return down_s

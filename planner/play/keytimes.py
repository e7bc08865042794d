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

The plan therefore crosses as early as the row grid allows going down and as late as it
allows going up: ``KEY_DOWN_ROWS`` before the note's first row (``ROW_MARGIN`` of a row
after the row before it, which the check then sees up), ``KEY_UP_ROWS`` before the first
row after the note (``ROW_MARGIN`` of a row before it). The check judges the rows as they
are and scores them the same; the physics gains the margin it lacks.
"""

from __future__ import annotations

import math

# Kept from the neighbouring row, in rows: the key crossing is found to ``moves.CROSS_TOL``
# of its move's path (microseconds) and the rows are floats written to 1e-9; a tenth of a
# row (1 ms at 100 Hz, the physics replay's step) keeps the row before a note up and the
# row after it free by the rows, with three orders of magnitude to spare.
ROW_MARGIN = 0.1
KEY_DOWN_ROWS = 1.0 - ROW_MARGIN  # the key-down crossing, rows before the note's first row
KEY_UP_ROWS = ROW_MARGIN  # the key-up crossing, rows before the first row after the note


def key_down_s(onset_s: float, dt_s: float) -> float:
    """When the rows put a key down for a note starting at ``onset_s``."""
    return (math.ceil(onset_s / dt_s - 1e-9) - KEY_DOWN_ROWS) * dt_s


def key_up_s(offset_s: float, dt_s: float) -> float:
    """When the rows let a key up for a note (or a hold) ending at ``offset_s``."""
    return (math.ceil(offset_s / dt_s - 1e-9) - KEY_UP_ROWS) * dt_s


def sounding_frames(down_s: float, up_s: float, dt_s: float) -> float:
    """The rows a key put down at ``down_s`` (``key_down_s``) and let up at ``up_s``
    (``key_up_s``) sounds: the frames between the two crossings, less the parts of a row
    they sit inside the neighbouring row intervals."""
    return (up_s - down_s) / dt_s - (KEY_DOWN_ROWS - KEY_UP_ROWS)

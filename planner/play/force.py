"""How hard a key is pressed: MIDI velocity -> press force at the fingertip.

``force_n = 0.5 + 2.5 (v/127)^2``: 0.5 N is a real key's weight (the force that just
holds a piano key down), 3 N a forte press on this hand. The atlas's poses carry the
largest force each can press within the motors' torque (``AtlasEntry.max_force_n``);
the fingering uses a pose only for the notes it can press that hard.
"""

from __future__ import annotations

MIN_FORCE_N = 0.5
MAX_FORCE_N = 3.0


def press_force_n(velocity: int) -> float:
    """Press force (N) for a MIDI velocity 0..127."""
    v = min(max(velocity, 0), 127) / 127.0
    return MIN_FORCE_N + (MAX_FORCE_N - MIN_FORCE_N) * v * v

"""The plan's own finger bodies against the keys: which keys the planned rows already put a
finger's body on (``planner.play.fingerbody``: the replay's shapes, the keys at rest, a
finger's own key -- the key under its pad point -- pressed to its bed), before any
physics. A wrong key of the full-contact replay that the plan's bodies already reach is
the plan's geometry (a finger wider than the key where it presses, a curled pad whose
sphere reaches past its point); one they do not reach comes from the dynamics (the hand
lagging its plan, a finger held up and sliding off)."""

from __future__ import annotations

import numpy as np

from planner.check.criteria import KeyContacts
from planner.hand.model import HandModel
from planner.music.keyboard import LOWEST_PITCH
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M, FingerBodies

N_KEYS = 88


def plan_body_keys(hand: HandModel, q_rows: np.ndarray, kc: KeyContacts) -> np.ndarray:
    """(T, 88) bool: some finger's planned body reaches the key by more than
    ``OTHER_KEY_TOLERANCE_M`` at that row, its own key (``kc.tip_key``) excepted."""
    bodies = FingerBodies(hand)
    out = np.zeros((len(q_rows), N_KEYS), dtype=bool)
    for t, q in enumerate(q_rows):
        for fi, f in enumerate(hand.fingers):
            own = int(kc.tip_key[t, fi])
            own_pitch = own + LOWEST_PITCH if own >= 0 else None
            pen = bodies.penetration(q, f, own_pitch, update=fi == 0)
            hit = pen > OTHER_KEY_TOLERANCE_M
            if own_pitch is not None:
                hit &= bodies.box_pitch != own_pitch
            out[t, bodies.box_pitch[hit] - LOWEST_PITCH] = True
    return out

"""The check's frame F1 of a pair's rows, as ``check`` will score the two-hand file:
each hand's keys down by the body rule (spec section 2: ``planner.check.bodykeys``, a key
down while any body of either hand holds it down), the two hands' keys as one, scored
against the whole song in the file's time by the check's own ``score_song`` (the pair
check: ``planner.check.pair``). ``plan_two_hands`` compares its closest ways by it: the
frames of music a way's plans play (each one-hand plan's own replay, against its own
notes) miss what one hand's keys do to the other's notes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from planner.check.bodykeys import body_keys, body_names
from planner.check.keys import score_song
from planner.check.kinematics import Kinematics
from planner.hand.bodies import collision_bodies
from planner.hand.model import HandModel
from planner.music.midi import Song
from planner.play.twoplan import PairRows


class PairScorer:
    """The pair's rows scored by the check's rules, built once per pair: each hand's
    kinematics and bodies as the check builds them (``planner.check.pair``)."""

    def __init__(self, left: HandModel, right: HandModel) -> None:
        self._kins = tuple(Kinematics(h, h.T_world_root) for h in (left, right))
        self._bodies = tuple(collision_bodies(h.spec) for h in (left, right))
        self._names = tuple(body_names(b)[0] for b in self._bodies)

    def frame_f1(self, rows: PairRows, song: Song, rate_hz: float) -> float:
        """The check's frame F1 of ``rows`` (both hands on one clock) against ``song``."""
        notes = [replace(n, onset_s=n.onset_s + rows.song_start_s,
                         offset_s=n.offset_s + rows.song_start_s) for n in song.notes]
        down = np.zeros((len(rows.t_s), 0), dtype=bool)
        for kin, bodies, q in zip(self._kins, self._bodies, rows.q):
            d = body_keys(kin, q, bodies).down
            down = d if down.shape[1] == 0 else (down | d)
        names = self._names[0] + self._names[1]
        return float(score_song(rows.t_s, down, None, notes, rate_hz, names).f1)

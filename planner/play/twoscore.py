"""The check's frame F1 of a pair's rows, as ``check`` will score the two-hand file:
each hand's keys down by the body rule (spec section 2: ``planner.check.bodykeys``, a key
down while any body of either hand holds it down), the two hands' keys as one, scored
against the whole song in the file's time by the check's own ``score_song`` (the pair
check: ``planner.check.pair``). ``plan_two_hands`` compares its closest ways by it: the
frames of music a way's plans play (each one-hand plan's own replay, against its own
notes) miss what one hand's keys do to the other's notes."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from planner.check.bodykeys import body_keys, body_names
from planner.check.keys import score_song
from planner.check.kinematics import Kinematics
from planner.hand.bodies import collision_bodies
from planner.hand.model import HandModel
from planner.music.midi import Song
from planner.play.twoplan import READS_HELD, PairRows, clock_of, held_twin

if TYPE_CHECKING:
    from planner.play.stream import PlayPlan
    from planner.trajfile import Trajectory


class PairScorer:
    """The pair's rows scored by the check's rules, built once per pair: each hand's
    kinematics and bodies as the check builds them (``planner.check.pair``). ``plans_f1``
    keeps each plan's keys (by identity, the plan held with them; a plan of the same text
    shares them) until ``clear``."""

    def __init__(self, left: HandModel, right: HandModel) -> None:
        self._kins = tuple(Kinematics(h, h.T_world_root) for h in (left, right))
        self._bodies = tuple(collision_bodies(h.spec) for h in (left, right))
        self._names = tuple(body_names(b)[0] for b in self._bodies)
        self._downs: tuple[dict[int, tuple[PlayPlan, np.ndarray]], ...] = ({}, {})

    def frame_f1(self, rows: PairRows, song: Song, rate_hz: float) -> float:
        """The check's frame F1 of ``rows`` (both hands on one clock) against ``song``."""
        down = np.zeros((len(rows.t_s), 0), dtype=bool)
        for kin, bodies, q in zip(self._kins, self._bodies, rows.q):
            d = body_keys(kin, q, bodies).down
            down = d if down.shape[1] == 0 else (down | d)
        return self._f1(rows.t_s, down, rows.song_start_s, song, rate_hz)

    def plans_f1(self, plans: tuple[PlayPlan, PlayPlan], song: Song, rate_hz: float,
                 read: Callable[[PlayPlan], Trajectory]) -> float:
        """``frame_f1`` of the plans' rows on one clock (``one_clock(plans, rate_hz,
        read)``), the same number: the body rule judges row by row, so a plan's keys are
        found once, on its own rows, and padded on the clock as its rows are (a way and
        its hand-back share the second hand's plan)."""
        trs = tuple(read(p) for p in plans)
        c = clock_of(plans, (len(trs[0].t_s), len(trs[1].t_s)), rate_hz)
        down = c.pad(0, self._down(0, plans[0], trs[0].q)) | c.pad(
            1, self._down(1, plans[1], trs[1].q))
        return self._f1(np.arange(c.n) / rate_hz, down, c.song_start_s, song, rate_hz)

    def clear(self) -> None:
        """Let every plan's keys go."""
        for held in self._downs:
            held.clear()

    def _down(self, k: int, plan: PlayPlan, q: np.ndarray) -> np.ndarray:
        """Hand ``k``'s keys down per row of ``plan`` (its rows ``q``), found once for a
        plan's text (its keys are its rows', and its rows its text's: ``held_twin``)."""
        held = self._downs[k]
        got = held.get(id(plan))
        if got is None:
            twin = held_twin(held, plan)
            if len(held) >= READS_HELD:
                held.clear()
            got = held[id(plan)] = (plan, body_keys(self._kins[k], q, self._bodies[k]).down
                                    if twin is None else twin[1])
        return got[1]

    def _f1(self, t_s: np.ndarray, down: np.ndarray, song_start_s: float, song: Song,
            rate_hz: float) -> float:
        """The check's frame F1 of both hands' keys ``down`` at ``t_s`` against ``song``
        (shifted by ``song_start_s``: the file's time)."""
        notes = [replace(n, onset_s=n.onset_s + song_start_s,
                         offset_s=n.offset_s + song_start_s) for n in song.notes]
        names = self._names[0] + self._names[1]
        return float(score_song(t_s, down, None, notes, rate_hz, names).f1)

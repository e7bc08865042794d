"""A two-hand plan (``planner.play.twohands``): what was planned (``TwoHandPlan``), both
hands' rows on one clock (``one_clock``) and the two-hand file (``write_two_hands``,
version 3: ``planner.pairfile``).

**One clock.** The two hands' plans are made apart; each starts its song when its way
in allows (``song_start_s``). The one that starts the song sooner waits at rest for the
difference (rows of its rest pose, every speed zero), and the shorter plan holds its last
row (rest) to the end, so both hands' rows are on one clock with one ``song_start_s``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from planner.errors import InputError
from planner.music.midi import Song
from planner.play.costs import SkipReason
from planner.play.handgap import HandGap
from planner.play.hands import LEFT, RIGHT, SIDES, HandAssignment
from planner.play.stream import ROW_BLOCK, PlayPlan
from planner.trajfile import Trajectory

if TYPE_CHECKING:
    from planner.play.twohands import PairPlanner


@dataclass(frozen=True)
class PairRows:
    """Both hands' rows on one clock: times ``t_s`` (from 0 at the rate), each hand's
    joints (``q``: left, right) and the common ``song_start_s``."""

    t_s: np.ndarray
    q: tuple[np.ndarray, np.ndarray]
    song_start_s: float


@dataclass(frozen=True)
class TwoHandPlan:
    """What ``plan_two_hands`` did: the assignment, each hand's one-hand plan (in memory,
    ``plans``, left then right), each hand's notes as indices of the song (``notes_of``:
    the hand each note was last planned on), the rows on one clock, and the clock after
    set-up. ``planned_of``: each plan's song as indices of the song (None: ``notes_of``);
    the hand planned first's holds the notes it left out and handed over too."""

    assignment: HandAssignment
    gap: HandGap
    plans: tuple[PlayPlan, PlayPlan]
    notes_of: tuple[tuple[int, ...], tuple[int, ...]]
    rows: PairRows
    planning_s: float
    least_rail_gap_m: float  # the rails' least distance apart over the rows
    text: str | None = None  # the file, planned in memory (no path)
    first: str = RIGHT  # the hand planned first
    # (every way planned, ``PairPass.way``, and the frames of music it played)
    tried: tuple[tuple[str, float], ...] = ()
    planned_of: tuple[tuple[int, ...], tuple[int, ...]] | None = None
    way: str = ""  # the way kept (``PairPass.way``)

    def left_out(self) -> list[tuple[int, object]]:
        """Every note not played, as (song index, ``Skip`` of its hand's plan), by note."""
        return left_out_of(self.plans, self.planned_of or self.notes_of, self.notes_of)

    def played_of(self, side: str) -> list[int]:
        """The song indices of the notes ``side`` plays (its notes but those left out)."""
        i = SIDES.index(side)
        out = {s.note for s in self.plans[i].verdict.skipped}
        return [n for k, n in enumerate((self.planned_of or self.notes_of)[i]) if k not in out]


def left_out_of(plans, planned_of, notes_of) -> list[tuple[int, object]]:
    """(song index, ``Skip``) of every note its hand (``notes_of``) left out, by note: a
    note the hand planned first left out and handed over is the other hand's. A handed
    note the other hand refused for the first one's bodies (``SkipReason.OTHER_HAND``:
    the first hand over its key, as it was when it left the note out) is named by why the
    first hand left it out, the refusal added to the detail: the loss is the first hand's."""
    mine = [set(idx) for idx in notes_of]
    skips = [{idx[s.note]: s for s in p.verdict.skipped} for idx, p in zip(planned_of, plans)]
    out = []
    for k in range(len(plans)):
        for i, s in skips[k].items():
            if i not in mine[k]:
                continue
            before = skips[1 - k].get(i)
            if s.reason is SkipReason.OTHER_HAND and before is not None:
                s = replace(before, detail=f"{before.detail}; handed to the other hand, "
                                           f"which could not take it: {s.detail}")
            out.append((i, s))
    return sorted(out, key=lambda x: x[0])


def two_hand_metadata(song: Song, plan: TwoHandPlan, rate_hz: float, song_name: str) -> dict:
    """The two-hand file's own metadata (the pair's keys are the writer's,
    ``planner.pairfile``): the song read with every part, the common ``song_start_s``,
    the pair's rail gap and how the hint was read."""
    return {"task": "play", "rate_hz": rate_hz,
            "song": song_name or os.path.basename(song.source), "notes": len(song.notes),
            "track": None, "channel": None, "transpose": song.transpose, "every_part": True,
            "song_start_s": plan.rows.song_start_s, "rail_gap_m": plan.gap.rail_gap_m,
            "hint": plan.assignment.source.value, "first_hand": plan.first}


def end_claims(plan: TwoHandPlan, notes) -> tuple[dict, dict[str, list[int]]]:
    """The end marker's claims for the whole song (``notes``, ``played``, ``left_out``,
    each hand's limit violations should one reach the end) and ``by_hand`` (per prefix,
    the notes that hand plays)."""
    left_out = plan.left_out()
    info: dict = {"notes": len(notes), "played": len(notes) - len(left_out),
                  "left_out": [{"note": i, "reason": s.reason.value, "detail": s.detail}
                               for i, s in left_out]}
    for side, p in zip(SIDES, plan.plans):
        bad = p.verdict.end_info().get("limit_violations")
        if bad:
            info.setdefault("limit_violations", []).extend(
                {**v, "name": f"{side}.{v['name']}"} for v in bad)
    return info, {f"{side}.": plan.played_of(side) for side in SIDES}


def write_two_hands(plan: TwoHandPlan, song: Song, pp: PairPlanner, out_path: str | None,
                    rate_hz: float, song_name: str = "") -> str | None:
    """The two-hand file (version 3, ``planner.pairfile.PairWriter``: the one writer and
    its guard) of ``plan``'s rows, into ``out_path`` ('-': stdout; None: returned)."""
    from planner.pairfile import PairWriter

    w = PairWriter(out_path, (pp.hands[LEFT], pp.hands[RIGHT]),
                   two_hand_metadata(song, plan, rate_hz, song_name))
    try:
        t, (ql, qr) = plan.rows.t_s, plan.rows.q
        for a in range(0, len(t), ROW_BLOCK):
            w.write_rows(t[a:a + ROW_BLOCK], ql[a:a + ROW_BLOCK], qr[a:a + ROW_BLOCK])
        info, by_hand = end_claims(plan, song.notes)
        w.close(info, by_hand)
    except BaseException as e:
        w.abort(discard=isinstance(e, InputError))
        raise
    return w.text


READS_HELD = 32  # plans ``PlanReads`` holds at most (a pair plans at most 14 one-hand
# plans: four ways, each its first hand once and its second up to 1 + MAX_ROUNDS times;
# past this it starts afresh, so calls outside ``plan_two_hands`` never grow it unbounded)


class PlanReads:
    """Each one-hand plan's rows read back from its text once (``KeptText.trajectory``
    parses the whole text at every call; a plan is read by ``first_edge``, by each
    loosened round's ``one_clock`` and by the kept way's): by the plan's identity, the
    plan held with its rows so that identity is never reused while it is held. A plan
    made again with the same text (a hand planned again to the same rows) shares the rows
    read of its twin (``held_twin``: the rows are the text's alone)."""

    def __init__(self) -> None:
        self._got: dict[int, tuple[PlayPlan, Trajectory]] = {}

    def __call__(self, plan: PlayPlan) -> Trajectory:
        """``plan.trajectory``, parsed at the first call for ``plan`` (or its text)."""
        got = self._got.get(id(plan))
        if got is None:
            twin = held_twin(self._got, plan)
            if len(self._got) >= READS_HELD:
                self._got.clear()
            got = self._got[id(plan)] = (plan, plan.trajectory if twin is None else twin[1])
        return got[1]

    def clear(self) -> None:
        """Let every plan held go."""
        self._got.clear()

    def __len__(self) -> int:
        return len(self._got)


def held_twin(held: dict, plan: PlayPlan) -> tuple | None:
    """The entry of ``held`` (by a plan's identity: (plan, what was found from its rows))
    whose plan has ``plan``'s text, None when none has (or ``plan`` has no text)."""
    if plan.text is None:
        return None
    for got in held.values():
        if got[0].text == plan.text:
            return got
    return None


def same_plan(a: PlayPlan, b: PlayPlan) -> bool:
    """Whether two one-hand plans are the same for what a pair reads of them: their rows
    (the file's text), the notes they left out and why, and the song's start."""
    return a is b or (a.text is not None and b.text is not None and len(a.text) == len(b.text)
                      and a.song_start_s == b.song_start_s
                      and a.verdict.skipped == b.verdict.skipped and a.text == b.text)


class SecondPlans:
    """The plans of the hand planned second made while a pair is planned
    (``twohands._plan_second``), by what each is planned from: its side, its notes (song
    indices), the first hand's plan (``same_plan``: its rows and the notes it left out),
    the rate, the song's name and its notes. A way's first hand planned with its room settled often
    comes out as with the windows' room, and a way's hand-back is planned from the second
    plan it shares with that way's twin: asked again for the same, the plan made is
    given back (planning is deterministic: the same input, the same bytes), not planned
    again. ``plan_two_hands`` lets them go when it is done; past ``READS_HELD`` it starts
    afresh."""

    def __init__(self) -> None:
        self._got: list[tuple[tuple, PlayPlan, PlayPlan]] = []

    def get(self, key: tuple, first: PlayPlan) -> PlayPlan | None:
        """The plan made for ``key`` (side, its notes, rate, name, the song's notes) and
        ``first`` (or its like), None when none was."""
        for k, f, plan in self._got:
            if k == key and same_plan(f, first):
                return plan
        return None

    def put(self, key: tuple, first: PlayPlan, plan: PlayPlan) -> None:
        """``plan``, made for ``key`` and ``first``."""
        if len(self._got) >= READS_HELD:
            self._got.clear()
        self._got.append((key, first, plan))

    def clear(self) -> None:
        """Let every plan held go."""
        self._got.clear()

    def __len__(self) -> int:
        return len(self._got)


class Clock(NamedTuple):
    """Two plans on one clock (module docstring): the common ``song_start_s``, the rows of
    rest each plan waits first (``lead``) and the rows of both (``n``)."""

    song_start_s: float
    lead: tuple[int, int]
    n: int

    def pad(self, k: int, a: np.ndarray) -> np.ndarray:
        """Plan ``k``'s per-row array ``a`` on the clock: its first row repeated ``lead[k]``
        times before it, its last repeated to ``n`` rows."""
        a = np.concatenate([np.repeat(a[:1], self.lead[k], axis=0), a])
        return np.concatenate([a, np.repeat(a[-1:], self.n - len(a), axis=0)])


def clock_of(plans: tuple[PlayPlan, PlayPlan], rows: tuple[int, int], rate_hz: float
             ) -> Clock:
    """``plans``' ``Clock``, each plan ``rows[k]`` rows long."""
    start = max(p.song_start_s for p in plans)
    lead = tuple(round((start - p.song_start_s) * rate_hz) for p in plans)
    return Clock(start, (lead[0], lead[1]), max(r + k for r, k in zip(rows, lead)))


def one_clock(plans: tuple[PlayPlan, PlayPlan], rate_hz: float,
              read: Callable[[PlayPlan], Trajectory] | None = None) -> PairRows:
    """Both plans' rows on one clock (module docstring); ``read``: a plan's rows
    (``PlanReads``; None: ``plan.trajectory``)."""
    trs = tuple(p.trajectory if read is None else read(p) for p in plans)
    c = clock_of(plans, (len(trs[0].t_s), len(trs[1].t_s)), rate_hz)
    return PairRows(np.arange(c.n) / rate_hz, (c.pad(0, trs[0].q), c.pad(1, trs[1].q)),
                    c.song_start_s)

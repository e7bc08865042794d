"""What the programme keeps of a move of the arm (planner/play/armcost.py): the parts kept
per state before (``Prev.up_parts``, ``Prev.lift_parts``: a cut key's) and per posture
and place (``ArmTimes._afters_of``) give the answer worked out afresh, to the bit, on
real songs' transitions."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from planner.music.midi import load_song
from planner.play.armcost import FLOOR_SLACK, TIE_RAIL_PER_M
from planner.play.costs import Prev
from planner.play.fingering import FingeringProblem
from planner.play.places import Places

SONGS = Path(__file__).resolve().parents[1] / "songs"


@pytest.fixture(scope="module")
def places(hand) -> Places:
    return Places(hand)


class _Checked(FingeringProblem):
    """The programme, every move of the arm costed twice: by the state before it weighs
    (its memos filled by the transitions before) and by a fresh ``Prev`` of the same
    state (its memos empty); every new note's descent after the move also worked out
    plainly (``Costs._times``' column by ``_descent_column``)."""

    def __init__(self, *args) -> None:
        super().__init__(*args)
        self.checked = 0
        self.parts = 0  # (moves whose state before had kept a cut key's parts)
        self.cut = 0  # (moves that let a key up early for the arm)
        self.rode = 0  # (moves a note rode along on)

    def _rail_loss(self, prev, new, place, kept=(), lates=None, rode=None, limit=math.inf,
                   tie_rail=None):
        # (every move costed in full, whatever its floor: ``limit`` not passed on)
        self.parts += bool(prev.up_parts or prev.lift_parts)
        got_lates, got_rode = [], []
        loss = super()._rail_loss(prev, new, place, kept, got_lates, got_rode)
        fresh = Prev(self, prev.state, _event_of(self, prev))
        plain_lates, plain_rode = [], []
        plain = super()._rail_loss(fresh, new, place, kept, plain_lates, plain_rode)
        assert (loss, got_lates, got_rode) == (plain, plain_lates, plain_rode)
        here = prev.state.place
        assert self._afters_of(prev, place, new) == [
            self._times(n, f, place)[self._descent_column(here, place, n, f)]
            for n, f in new.items()]
        self.checked += 1
        self.cut += bool(self._release(fresh, new, place)[2])
        self.rode += bool(plain_rode)
        if lates is not None:
            lates.extend(got_lates)
        if rode is not None:
            rode.extend(got_rode)
        return loss


def _event_of(costs, prev) -> float:
    """The event time ``prev`` was made for (``Costs.prev``' memo holds it)."""
    return next(t for t, at in costs._ctx.items() if at.get(prev.state) is prev)


@pytest.mark.parametrize("name", ["fast.mid", "leaps.mid", "chords.mid"])
def test_what_is_kept_per_state_before_and_place_is_the_fresh_answer(places, name):
    p = _Checked(list(load_song(SONGS / name).notes), places, 100.0)
    assert p.solve().assignments
    # (the memos were read, not only filled: a cut key's parts kept; keys cut occur, and
    # notes riding along (on ``fast.mid``: 543 of 9,820 moves))
    assert p.checked > 200 and p.parts > 0
    assert p.cut > 0
    if name == "fast.mid":
        assert p.rode > 0


class _Floored(FingeringProblem):
    """The programme, every move of the arm it weighs also costed in full: the floor
    (``ArmFloor._arm_floor``, with the rail's tie-break, as ``_rail_loss`` weighs it)
    against the loss, and every move the floor rules out against the ``limit`` it was
    ruled out for. ``floored``: False plans with no floor at all (``limit`` dropped)."""

    def __init__(self, *args, floored: bool = True) -> None:
        super().__init__(*args)
        self.floored = floored
        self.moves = 0
        self.above_zero = 0  # (moves whose floor is above the rail's tie-break)
        self.ruled_out = 0
        self.least_margin = math.inf  # (frames: the loss less the floor, least of all)

    def _rail_loss(self, prev, new, place, kept=(), lates=None, rode=None, limit=math.inf,
                   tie_rail=None):
        full = super()._rail_loss(prev, new, place, kept)
        _, arrive, T, lifts, cands = self._arm_setup(prev, new, place)
        floor = (TIE_RAIL_PER_M * self.places.distance_m(place, prev.state.place)
                 + self._arm_floor(prev, lifts, cands, T, arrive))
        assert floor - FLOOR_SLACK <= full
        self.moves += 1
        self.above_zero += floor > TIE_RAIL_PER_M * self.places.distance_m(
            place, prev.state.place)
        self.least_margin = min(self.least_margin, full - floor)
        if not self.floored:
            limit = math.inf
        got = super()._rail_loss(prev, new, place, kept, lates, rode, limit, tie_rail)
        if got is None:  # (ruled out: it could not have been kept)
            self.ruled_out += 1
            assert full > limit
        else:
            assert got == full
        return got


@pytest.mark.parametrize("name", ["fast.mid", "leaps.mid", "fur_elise.mid"])
def test_the_arm_floor_is_never_above_the_loss_and_rules_out_no_move_kept(places, name):
    """Every move of the arm the programme weighs on a real song: the floor it is ruled
    out by is at or below its loss, and a move ruled out costs more than the limit it was
    ruled out for (its shape's best or the beam's bound, less its state before's cost):
    it could not have been kept. The plan is the one made with no floor, to the bit."""
    notes = list(load_song(SONGS / name).notes)
    p = _Floored(notes, places, 100.0)
    got = p.solve()
    plain = _Floored(notes, places, 100.0, floored=False)
    want = plain.solve()
    assert (got.assignments, got.skipped, got.expected_loss_frames) == (
        want.assignments, want.skipped, want.expected_loss_frames)
    # (the floor is worth its cost: it rules moves out, and it is above the tie-break
    # on many; none is ruled out with no floor; the floor is tight on some move)
    assert p.ruled_out > 0 and plain.ruled_out == 0
    assert p.above_zero > p.moves // 10
    assert 0.0 <= p.least_margin < 1.0


class _Overed(FingeringProblem):
    """The programme, every move of the arm it weighs also asked plainly: the latest lift
    of a finger that cannot ride along (``ArmFloor._first_clear``, which asks ``_rider``
    of the lifts down to the first that cannot) against the one read from every rider
    candidate (``_ride_cands``), the floor's part whatever is cut (``_over_frames``)
    against the whole floor (``_arm_floor``), and the striking fingers' floor
    (``_gap_floor``, with the rail's tie-break) against the move's loss costed in full."""

    def __init__(self, *args) -> None:
        super().__init__(*args)
        self.moves = 0
        self.skipped_riders = 0  # (moves whose latest lift is of a rider candidate)
        self.above = 0  # (moves whose part of the floor is above nothing)
        self.gap_above = 0  # (moves whose striking fingers' floor is above nothing)

    def _rail_loss(self, prev, new, place, kept=(), lates=None, rode=None, limit=math.inf,
                   tie_rail=None):
        _, arrive, T, lifts, cands = self._arm_setup(prev, new, place)
        start = arrive - T
        riding = {c[0] for c in cands}
        plain = next((v for v, m, f in lifts[0] if (m, f) not in riding), None)
        if plain is not None and plain <= start:
            plain = None
        got = self._first_clear(prev, lifts[0], place, new, start)
        assert got == plain
        if got is not None:
            part = self._over_frames(got, start)
            assert part <= self._arm_floor(prev, lifts, cands, T, arrive)
            self.above += part > 0.0
            self.skipped_riders += got != lifts[0][0][0]
        self.moves += 1
        full = super()._rail_loss(prev, new, place, kept)
        gap = self._gap_floor(prev, new, place)
        assert TIE_RAIL_PER_M * self.places.distance_m(place, prev.state.place) + gap \
            - FLOOR_SLACK <= full
        self.gap_above += gap > 0.0
        return super()._rail_loss(prev, new, place, kept, lates, rode, limit, tie_rail)


@pytest.mark.parametrize("name", ["fast.mid", "chords.mid"])
def test_the_floors_first_part_is_the_one_read_from_every_rider(places, name):
    """On a real song, every move of the arm the programme weighs: the lift the floor's
    first part is worked from is the latest clear after the arm's start of the fingers
    no rider candidate holds (so what it rules out, the whole floor rules out: it is at
    or below it); the part is above nothing on many moves, and a note that rides is
    passed over on some. The striking fingers' floor is at or below the move's loss, and
    above nothing on some moves."""
    p = _Overed(list(load_song(SONGS / name).notes), places, 100.0)
    assert p.solve().assignments
    assert p.moves > 200 and p.above > p.moves // 10 and p.gap_above > 0
    if name == "chords.mid":  # (3 of its 998 moves; none on ``fast.mid``)
        assert p.skipped_riders > 0

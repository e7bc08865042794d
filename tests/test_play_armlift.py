"""Keys let up early for a move of the arm (planner/play/armcost.py ``ArmCosts._cut_lifts``):
the programme's estimate of the new key's down and of the cut key's up is the motion's
(planner/play/motion.py ``Motion.lift_by_s``): a finger whose key is due up after the arm
must start, to put the next key down on time, lets it up that early, held as long as its
note still sounds (``keytimes.held_enough_s``)."""

from __future__ import annotations

import pytest

from planner.music.midi import Note
from planner.play.costs import Costs, State
from planner.play.fingering import Assignment
from planner.play.motion import Motion
from planner.play.places import Places


@pytest.fixture(scope="module")
def places(hand) -> Places:
    return Places(hand)


def _case(places, start_s: float, pitch: int, posture: int, finger: str, start: int = 0,
          first: int = 60, holder: str = "index"):
    """The index (or ``holder``) holds C4 (or ``first``) from ``start_s`` to 1.0 s (from
    the nearest place of posture ``start`` to the rail's 0), then ``finger`` strikes
    ``pitch`` at 1.0 s from the nearest place of ``posture`` (the rail's move too long to
    start after C4's key is due up); the programme's and the motion's key times."""
    notes = (Note(first, start_s, 1.0, 80), Note(pitch, 1.0, 1.5, 80))
    costs = Costs(notes, places, 100.0)
    here = min((p for p in costs.rails(holder, 0) if places.posture_of(p) == start),
               key=lambda p: abs(places.rail_i(p)))
    there = min((p for p in costs.rails(finger, 1) if places.posture_of(p) == posture),
                key=lambda p: abs(places.rail_i(p) - places.rail_i(here)))
    assert costs.entry(0, holder, there) is None  # (C4 cannot ride along)
    state = State(here, ((0, holder),))
    prev = costs.prev(state, notes[1].onset_s)
    lates: list = []
    loss = costs._rail_loss(prev, {1: finger}, there, (), lates, [])
    _, _, cut_loss, ups = costs._release(prev, {1: finger}, there)
    planned_down = costs.t_down(1) + dict(lates).get(1, 0.0)
    planned_up = ups.get(0, costs.t_up(0))

    motion = Motion(notes, places, 100.0, places.rail_m(here), start)
    plays = [Assignment(0, holder, places.rail_m(here), posture=start),
             Assignment(1, finger, places.rail_m(there), posture=posture)]
    motion.expect(plays)
    for a in plays:
        assert motion.place(a).down_s is not None
    motion.finish(2.0)
    return (planned_down, planned_up, cut_loss, loss), motion.outcomes, costs


@pytest.mark.parametrize(("pitch", "posture", "finger"), [
    (76, 0, "middle"),  # (E5, far along the rail in the same posture)
    (76, 0, "index"),  # (the cut finger strikes again)
    (72, 1, "pinky"),  # (C5, into another posture: the black rule's lift)
])
def test_the_arm_starts_on_time_when_the_programme_says(places, pitch, posture, finger):
    (down, up, cut_loss, loss), out, costs = _case(places, 0.4, pitch, posture, finger)
    assert out[1].down_s == pytest.approx(down, abs=1e-6)
    assert out[0].up_s == pytest.approx(up, abs=1e-6)
    assert up < costs.t_up(0) - 0.03  # (cut: the move takes longer than C4 leaves it)
    assert cut_loss == pytest.approx((costs.t_up(0) - up) / costs.dt)
    assert loss >= cut_loss


def test_a_move_out_of_the_keyboard_lifts_by_the_front_rule(places):
    """The index on C4's front in the second posture, then E5 in the first (the hand
    moves out of the keyboard): the index's body, in front of the black keys once its
    lift is clear by the front rule, only goes further out, so the arm may start then
    (``highclear.front_rules``), earlier than by the black rule; the middle's descent onto
    E5 after it keeps the black rule (its room, below, is less than the reach axis's
    travel over its descent: ``HighClear.descent_front``). The middle's body on E5's front in the first
    posture lies 9.2 mm in front of the black keys' front less the tolerance
    (``HighClear.front_room_m``): less than the 25 mm the reach moves and than the
    reach axis goes between its lift's front and black moments, so its lift before the
    move back in keeps the black rule (``HighClear.lift_front``). The programme's key
    times are the motion's."""
    (down, up, cut_loss, loss), out, costs = _case(places, 0.4, 76, 0, "middle", start=1)
    assert out[1].down_s == pytest.approx(down, abs=1e-6)
    assert out[0].up_s == pytest.approx(up, abs=1e-6)
    assert up < costs.t_up(0) - 0.03
    assert cut_loss == pytest.approx((costs.t_up(0) - up) / costs.dt)
    assert loss >= cut_loss
    here = min((p for p in costs.rails("index", 0) if places.posture_of(p) == 1),
               key=lambda p: abs(places.rail_i(p)))
    there = min((p for p in costs.rails("middle", 1) if places.posture_of(p) == 0),
                key=lambda p: abs(places.rail_i(p) - places.rail_i(here)))
    e = costs.entry(0, "index", here)
    assert places.rail_lift_s(e) < places.rail_lift_s(e, False) - 0.010  # (this case
    # tests the front rule's moment: earlier)
    em = costs.entry(1, "middle", there)
    assert places.high.front_room_m(em) == pytest.approx(0.0092, abs=1e-4)
    assert places.reach_m(1) - places.reach_m(0) == pytest.approx(0.025)
    assert (costs._lift_col(here, there, 0, "index", here),
            costs._descent_column(here, there, 1, "middle")) == (0, 3)
    assert (costs._lift_col(there, here, 1, "middle", there),
            costs._descent_column(there, here, 0, "index")) == (2, 3)
    assert (costs._lift_col(here, here + 1, 0, "index", here),
            costs._descent_column(here, here + 1, 0, "index")) \
        == (0, 1)  # (the same posture, a step along the rail: the front rule both ways)


def test_a_lift_into_the_keyboard_keeps_the_front_rule_where_its_body_stays_in_front(
        places, monkeypatch):
    """The index on E4's front in the first posture, then the middle on C#5 in the second
    (the hand moves 25 mm into the keyboard): every body of the index that the front rule
    counts clear below the black tops lies 30.4 mm in front of the black keys' front less
    the tolerance (``HighClear.front_room_m``), so the arm carrying it 25 mm in leaves it
    in front, and its lift is timed by the front rule (``lift_front``): E4's key, cut for
    the arm's start, comes up 21 ms later than by the black rule, the frames cut fewer by
    as much, in the programme as in the motion."""
    (down, up, cut_loss, _), out, costs = _case(places, 0.4, 73, 1, "middle", first=64)
    here = min((p for p in costs.rails("index", 0) if places.posture_of(p) == 0),
               key=lambda p: abs(places.rail_i(p)))
    e = costs.entry(0, "index", here)
    assert places.high.front_room_m(e) == pytest.approx(0.0304, abs=1e-4)
    assert places.high.lift_front(e, places.reach_m(0), places.reach_m(1))
    assert places.high.lift_front(e, places.reach_m(0), places.reach_m(2))  # (75 mm in:
    # further than the room, but the arm moves at most the reach's bound from the lift's
    # front moment to its black one)
    gain_s = places.rail_lift_s(e, False) - places.rail_lift_s(e)
    assert gain_s == pytest.approx(0.0212, abs=2e-4)
    assert out[1].down_s == pytest.approx(down, abs=1e-6)
    assert out[0].up_s == pytest.approx(up, abs=1e-6)
    assert up < costs.t_up(0) - 0.03  # (cut)
    monkeypatch.setattr(type(places.high), "lift_front", lambda self, e, a, b: a >= b)
    (down_b, up_b, cut_b, _), out_b, _ = _case(places, 0.4, 73, 1, "middle", first=64)
    assert out_b[0].up_s == pytest.approx(up_b, abs=1e-6)
    assert up == pytest.approx(up_b + gain_s, abs=1e-6)  # (held that much longer)
    assert cut_loss == pytest.approx(cut_b - gain_s / costs.dt, abs=1e-6)
    assert down == pytest.approx(down_b, abs=1e-6)


def test_a_descent_after_a_move_out_of_the_keyboard_keeps_the_front_rule_where_it_stayed_in_front(
        places, monkeypatch):
    """The middle holds C#4 in the second posture, then the pinky strikes E4 in the first
    (the hand moves 25 mm out of the keyboard; the middle presses no black key there and
    lifts): every body of the pinky's descent that the front rule counts clear below the
    black tops lies 41.2 mm in front of the black keys' front less the tolerance, more
    than the 25 mm the arm can still be further in, so the arm may end as late as the
    descent's front moment (``HighClear.descent_front``): its part after the arm is 19 ms
    shorter, the arm starts that much later and C#4's key, cut for it, comes up as much
    later, in the programme as in the motion; the new key goes down on time either way."""
    kw = {"first": 61, "holder": "middle", "start": 1}
    (down, up, cut_loss, _), out, costs = _case(places, 0.4, 64, 0, "pinky", **kw)
    here = min((p for p in costs.rails("middle", 0) if places.posture_of(p) == 1),
               key=lambda p: abs(places.rail_i(p)))
    there = min((p for p in costs.rails("pinky", 1) if places.posture_of(p) == 0),
                key=lambda p: abs(places.rail_i(p) - places.rail_i(here)))
    e = costs.entry(1, "pinky", there)
    assert places.high.front_room_m(e) == pytest.approx(0.0412, abs=1e-4)
    assert places.high.descent_front(e, places.reach_m(1), places.reach_m(0))
    assert costs._descent_column(here, there, 1, "pinky") == 1
    gain_s = places.rail_descent_s(e, False) - places.rail_descent_s(e)
    assert gain_s == pytest.approx(0.0189, abs=5e-4)
    assert out[1].down_s == pytest.approx(down, abs=1e-6)
    assert down == pytest.approx(costs.t_down(1), abs=1e-6)  # (on time)
    assert out[0].up_s == pytest.approx(up, abs=1e-6)
    assert up < costs.t_up(0) - 0.03  # (cut)
    monkeypatch.setattr(type(places.high), "descent_front", lambda self, e, a, b: a == b)
    (down_b, up_b, cut_b, _), out_b, _ = _case(places, 0.4, 64, 0, "pinky", **kw)
    assert out_b[0].up_s == pytest.approx(up_b, abs=1e-6)
    assert up == pytest.approx(up_b + gain_s, abs=1e-6)  # (held that much longer)
    assert cut_loss == pytest.approx(cut_b - gain_s / costs.dt, abs=1e-6)
    assert down == pytest.approx(down_b, abs=1e-6)


def test_a_shorter_note_is_held_until_it_sounds(places):
    """C4 from 0.58 s: cut to the arm's start (as from 0.4 s) it would sound too few of its
    rows for a hit with the drive's lag; the motion holds it that much longer and the new
    key goes down late, as the programme says."""
    (_, cut_up, _, _), _, _ = _case(places, 0.4, 76, 0, "middle")
    (down, up, _, _), out, costs = _case(places, 0.58, 76, 0, "middle")
    assert out[1].down_s == pytest.approx(down, abs=1e-6)
    assert out[0].up_s == pytest.approx(up, abs=1e-6)
    assert up > cut_up + 0.005  # (held past the arm's wish)
    assert down > costs.t_down(1) + 0.005  # (late)


def test_a_chord_after_the_arm_goes_down_when_the_programme_says(places):
    """A chord struck after a move of the arm (C5 by the index, F5 by the middle, whose
    descent's part below the clear height is 20 ms longer): the move ends by the latest that lets each
    of its keys go down on time after its own descent's part below the clear height (the
    programme's ``arrive``); the motion once timed it by the first note's descent alone,
    and a note whose descent has the longer part went down late (10-17 ms, the pinky and
    ring on ``chorale_duo_bwv274``) where the programme said on time."""
    notes = (Note(60, 0.4, 1.0, 80), Note(72, 1.0, 1.5, 80), Note(77, 1.0, 1.5, 80))
    costs = Costs(notes, places, 100.0)
    here = min((p for p in costs.rails("index", 0) if places.posture_of(p) == 0),
               key=lambda p: abs(places.rail_i(p)))
    both = [p for p in costs.rails("index", 1) & costs.rails("middle", 2)
            if places.posture_of(p) == 0]
    descents = {p: [places.rail_descent_s(costs.entry(n, f, p))
                    for n, f in ((1, "index"), (2, "middle"))] for p in both}
    there = min(both, key=lambda p: (descents[p][0] - descents[p][1], p))
    assert descents[there][1] > descents[there][0] + 0.01  # (the second's part longer)
    prev = costs.prev(State(here, ((0, "index"),)), 1.0)
    lates: list = []
    costs._rail_loss(prev, {1: "index", 2: "middle"}, there, (), lates, [])
    motion = Motion(notes, places, 100.0, places.rail_m(here))
    plays = [Assignment(0, "index", places.rail_m(here)),
             Assignment(1, "index", places.rail_m(there)),
             Assignment(2, "middle", places.rail_m(there))]
    motion.expect(plays)
    for a in plays:
        assert motion.place(a).down_s is not None
    for n in (1, 2):
        want = costs.t_down(n) + dict(lates).get(n, 0.0)
        assert motion.outcomes[n].down_s == pytest.approx(want, abs=1e-6)


@pytest.mark.parametrize(("pitch", "finger", "here", "there", "up_tol_s"), [
    (67, "ring", 6, 14, 1e-6),
    (72, "pinky", 6, 15, 1e-3),  # (the cut key's up 0.73 ms early: left, the page)
])
def test_a_rider_keeps_its_key_and_the_others_are_cut(places, pitch, finger, here, there,
                                                      up_tol_s):
    """The middle holds E4 through a move of the rail (it rides along), the index's C4 is
    due up at the move's note: the index lets it up early for the arm to start on time
    (``ArmCosts._riders`` then ``_cut_lifts``), and the new key goes down when the
    programme says."""
    notes = (Note(60, 0.4, 1.0, 80), Note(64, 0.4, 1.6, 80), Note(pitch, 1.0, 1.5, 80))
    costs = Costs(notes, places, 100.0)
    prev = costs.prev(State(here, ((0, "index"), (1, "middle"))), 1.0)
    lates: list = []
    rode: list = []
    costs._rail_loss(prev, {2: finger}, there, (), lates, rode)
    _, riders, _, ups = costs._release(prev, {2: finger}, there)
    assert riders == {(1, "middle")} and set(ups) == {0}
    assert ups[0] < costs.t_up(0) - 0.1
    motion = Motion(notes, places, 100.0, places.rail_m(here))
    plays = [Assignment(0, "index", places.rail_m(here)),
             Assignment(1, "middle", places.rail_m(here)),
             Assignment(2, finger, places.rail_m(there))]
    motion.expect(plays)
    for a in plays:
        assert motion.place(a).down_s is not None
    motion.finish(2.0)
    assert motion.outcomes[2].down_s == pytest.approx(
        costs.t_down(2) + dict(lates).get(2, 0.0), abs=1e-6)
    assert motion.outcomes[0].up_s == pytest.approx(ups[0], abs=up_tol_s)
    assert motion.outcomes[1].up_s == costs.t_up(1)  # (it rode along to its end)

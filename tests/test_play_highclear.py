"""When a finger going up or down is clear above every key (planner/play/highclear.py):
the arm may move from the lift's clear moment on and until the descent's, by the black
rule (every body above the black tops) and by the front rule (a body in front of the
black keys above the white tops); the moments shipped in the move tables are those the
search finds."""

from __future__ import annotations

import numpy as np
import pytest

from planner.play.highclear import (
    BODY_CLEAR_Z_M,
    CLEAR_MOVES,
    CLEAR_RULES,
    FRONT_CLEAR_Z_M,
    FRONT_Y_M,
    ROOM_COLUMN,
    HighClear,
    params,
)
from planner.play.places import Places
from planner.play.tendonload import slowed


@pytest.fixture(scope="module")
def places(hand) -> Places:
    return Places(hand)


def _bodies(places: Places, e, move, t_s: float):
    h, atlas = places.hand, places.atlases[e.posture]
    q = atlas.base.copy()
    q[h.joint_slice(e.finger)] = move.at(t_s)[0]
    return atlas.bodies.points(h.apply_couplings(q), e.finger)


def _lowest_body_z(places: Places, e, move, t_s: float) -> float:
    p, r = _bodies(places, e, move, t_s)
    return float(np.min(p[:, 2] - r))


def _front_clear(places: Places, e, move, t_s: float, dy_m: float = 0.0) -> bool:
    """Every body clear above the black tops, or in front of the black keys (less the
    body rule's tolerance) and clear above the white tops: computed here from the
    keyboard's numbers (``dy_m``: with the hand that much further into the keyboard)."""
    p, r = _bodies(places, e, move, t_s)
    low = p[:, 2] - r
    front = p[:, 1] + dy_m + r <= 0.060 - 0.0005
    return bool(np.all((low >= 0.0125 + 0.001 - 1e-9) | (front & (low >= 0.001 - 1e-9))))


def test_the_front_rule_numbers():
    assert FRONT_CLEAR_Z_M == pytest.approx(0.001)  # 1 mm above the white tops
    assert FRONT_Y_M == pytest.approx(0.0595)  # the black keys' front less 0.5 mm
    assert BODY_CLEAR_Z_M == pytest.approx(0.0135)


def _entries(places: Places):
    for posture, atlas in enumerate(places.atlases):
        for finger in ("index", "middle", "ring", "pinky"):
            for pitch in (60, 61, 64, 66):
                e = atlas.entry(finger, pitch, 0.0)
                if e is not None:
                    yield e


def test_a_lift_is_clear_from_its_clear_moment_to_its_end(places):
    seen = 0
    for e in _entries(places):
        u = places.lift(e, "high")
        t_clear = places.high.rise_clear_s(e, u.move, front=False)
        # (the key comes up first; the last part of the lift overlaps the arm's move)
        assert u.cross_s < t_clear < u.move.duration_s
        assert places.rail_lift_s(e, False) < places.before_rail_s(e)
        for t in np.linspace(t_clear, u.move.duration_s, 25):
            assert _lowest_body_z(places, e, u.move, t) >= BODY_CLEAR_Z_M - 1e-9
        # (just before it, the finger is still lower: the moment is not too late by much)
        assert _lowest_body_z(places, e, u.move, t_clear - 0.002) < BODY_CLEAR_Z_M + 3e-4
        seen += 1
    assert seen >= 8


def test_a_descent_is_clear_until_its_clear_moment(places):
    for e in _entries(places):
        d = places.descend(e, "high")
        t_clear = places.high.descent_clear_s(e, d.move, front=False)
        assert 0.0 < t_clear < d.cross_s
        assert places.rail_descent_s(e, False) == pytest.approx(d.cross_s - t_clear)
        for t in np.linspace(0.0, t_clear, 25):
            assert _lowest_body_z(places, e, d.move, t) >= BODY_CLEAR_Z_M - 1e-9
        assert _lowest_body_z(places, e, d.move, t_clear + 0.002) < BODY_CLEAR_Z_M + 3e-4


def test_the_front_rule_is_clear_from_its_moments_and_earlier_in_front(places):
    """By the front rule a lift is clear from its moment to its end and a descent from
    its start to its moment (tested at 41 points, finer than the search's 33); never
    later than the black rule's; earlier on the default hand's white-key entries in
    front of the black keys (posture 0, rail 0: the middle finger on C4, the ring and
    pinky on D4 and E4), the same on its black-key entries."""
    earlier = 0
    for e in _entries(places):
        u, d = places.lift(e, "high"), places.descend(e, "high")
        t_up = places.high.rise_clear_s(e, u.move)
        t_down = places.high.descent_clear_s(e, d.move)
        assert t_up <= places.high.rise_clear_s(e, u.move, front=False)
        assert t_down >= places.high.descent_clear_s(e, d.move, front=False)
        for t in np.linspace(t_up, u.move.duration_s, 41):
            assert _front_clear(places, e, u.move, t)
        for t in np.linspace(0.0, t_down, 41):
            assert _front_clear(places, e, d.move, t)
        if e.pitch_class in (1, 6):
            assert places.rail_lift_s(e) == places.rail_lift_s(e, False)
        if places.rail_lift_s(e) < places.rail_lift_s(e, False) - 0.010:
            assert places.rail_descent_s(e) < places.rail_descent_s(e, False) - 0.010
            earlier += 1
    assert earlier >= 4


def test_a_body_in_front_stays_in_front_while_the_arm_moves_by_its_room(places):
    """``HighClear.front_room_m``: with the hand carried that far into the keyboard (the
    reach axis), every point of the entry's lift from its front-rule moment to its end,
    and of its descent from its start to its moment, is still clear by the front rule
    (tested at 41 points, finer than the 33 the room is measured at; so a lift before a
    move of the arm into the keyboard, or a descent after a move out, no longer than the
    room keeps the front rule's moments); 1 mm further, some point is not (the room is
    the bound). At rail 0 on the default hand: in the first posture the pinky on E4 has
    41.2 mm, the ring 20.9 mm, the middle on C4 9.0 mm (its body reaches further in); in
    the second the pinky on E4 16.9 mm; a black-key entry's bodies are never in front
    (inf: its moments are the black rule's)."""
    rooms = {}
    for e in _entries(places):
        room = places.high.front_room_m(e)
        rooms[e.posture, e.finger, e.pitch_class] = room
        if not np.isfinite(room):
            assert places.rail_lift_s(e) == places.rail_lift_s(e, False)
            continue
        assert room > 0.0
        u, d = places.lift(e, "high"), places.descend(e, "high")
        t_up = places.high.rise_clear_s(e, u.move)
        t_down = places.high.descent_clear_s(e, d.move)
        for t in np.linspace(t_up, u.move.duration_s, 41):
            assert _front_clear(places, e, u.move, t, room)
        for t in np.linspace(0.0, t_down, 41):
            assert _front_clear(places, e, d.move, t, room)
        assert not all(_front_clear(places, e, u.move, t, room + 0.001)
                       for t in np.linspace(t_up, u.move.duration_s, 41))
    assert [round(1000 * rooms[k], 1) for k in ((0, "pinky", 4), (0, "ring", 4),
                                                 (0, "middle", 0), (1, "pinky", 4))] \
        == [41.2, 20.9, 9.0, 16.9]
    assert all(not np.isfinite(v) for k, v in rooms.items() if k[2] in (1, 6))


def test_the_reach_bound_holds_every_move_of_the_arm(places):
    """``HighClear.reach_bound_m``: the reach axis's bound from rest (acceleration 40 m/s^2
    reached over its 5 ms jerk ramp: 0.17 mm in 5 ms, 6.2 mm in 20 ms), the double
    integral of ``min(J t, A)`` worked out here step by step; every move of the arm
    between the postures (with rail steps of 0-0.3 m) moves the reach no further from its
    start, nor within its last moments, than the bound of that time."""
    hc, h = places.high, places.hand
    j = h.index["reach"]
    a, jerk = places.moves[0].acceleration[j], places.moves[0].jerk[j]
    assert (a, jerk) == (40.0, 8000.0)
    dt = 1e-6
    t = np.arange(0.0, 0.04, dt)
    v = np.cumsum(np.minimum(jerk * t, a)) * dt
    x = np.cumsum(v) * dt
    for ts in (0.002, 0.005, 0.01, 0.02, 0.035):
        assert hc.reach_bound_m(ts) == pytest.approx(x[round(ts / dt) - 1], rel=1e-3)
    assert hc.reach_bound_m(0.005) == pytest.approx(1.667e-4, rel=1e-3)
    assert hc.reach_bound_m(0.02) == pytest.approx(6.167e-3, rel=1e-3)
    r = [places.reach_m(i) for i in range(places.postures)]
    for p0 in range(3):
        for p1 in range(3):
            for rail_m in (0.0, 0.042, 0.3):
                if p0 == p1:
                    continue
                move = places.arm_move((0.0, r[p0]), (rail_m, r[p1]))
                ts = np.linspace(0.0, move.duration_s, 201)
                reach = np.array([move.at(t_s)[0][1] for t_s in ts])
                gone = np.abs(reach - reach[0])
                left = np.abs(reach[-1] - reach)
                assert all(gone[k] <= hc.reach_bound_m(ts[k]) + 1e-12 for k in range(201))
                assert all(left[k] <= hc.reach_bound_m(ts[-1] - ts[k]) + 1e-12
                           for k in range(201))


def test_the_entrys_rule_for_a_move_of_the_arm(places):
    """``lift_front``: the front rule where the reach stays and before a move out of the
    keyboard; before a move in where the entry's room holds the move's length, or the
    reach axis's reach (``reach_bound_m``) in the time from the lift's front moment to
    its black one (the later of its lift from the press and its rise from hover). On the
    first posture at rail 0: the pinky on E4 (room 41.2 mm, 35.1 ms: 21.3 mm) and the
    ring (20.9 mm, 26.6 ms: 11.7 mm) keep it into either other posture, 25 or 75 mm in;
    the middle on C4 (9.0 mm, 27.6 ms: 12.7 mm) keeps the black rule."""
    hc = places.high
    r0, r1, r2 = (places.reach_m(i) for i in range(3))
    got = {}
    for e in _entries(places):
        if e.posture != 0:
            continue
        m = places.moves[0]
        gap = max(hc.rise_clear_s(e, up, False) - hc.rise_clear_s(e, up)
                  for up in (m.lift(e, "high").move, m.rise(e).move))
        got[e.finger] = (round(1000 * hc.front_room_m(e), 1), round(1000 * gap, 1),
                         round(1000 * hc.reach_bound_m(gap), 1),
                         hc.lift_front(e, r0, r1), hc.lift_front(e, r0, r2))
        assert hc.lift_front(e, r0, r0) and hc.lift_front(e, r1, r0) and hc.lift_front(e, r2, r0)
    assert got == {"pinky": (41.2, 35.1, 21.3, True, True), "ring": (20.9, 26.6, 11.7, True, True),
                   "middle": (9.0, 27.6, 12.7, False, False)}
    assert not hc.lift_front(None, r0, r1) and hc.lift_front(None, r1, r0)


def _ends_clear(places: Places, e, reach_from_m: float, rail_from_m: float, sigma: float,
                front: bool) -> bool:
    """Entry ``e``'s descent from crossing height, ``sigma`` times slower, with the arm's
    move from (``rail_from_m``, ``reach_from_m``) to (0, ``e``'s posture's reach) ending
    at the descent's moment by the front rule (``front``) or the black rule: clear by the
    front rule, the hand where the arm is, at 61 moments from its start to the arm's end
    (finer than the search's 33 points; before the arm starts, where it started)."""
    hc = places.high
    d = slowed(places.descend(e, "high").move, sigma)
    t_end = hc.descent_clear_s(e, d, front)
    reach_to = places.reach_m(e.posture)
    arm = places.arm_move((rail_from_m, reach_from_m), (0.0, reach_to))
    t0 = t_end - arm.duration_s
    for t in np.linspace(0.0, t_end, 61):
        reach = reach_from_m if t < t0 else float(arm.at(t - t0)[0][1])
        if not _front_clear(places, e, d, t, reach - reach_to):
            return False
    return True


def test_a_descent_after_a_move_out_keeps_the_front_rule_where_its_bodies_stayed_in_front(
        places):
    """``descent_front``: after a move of the arm out of the keyboard (the second or third
    posture to the first, the third to the second) a descent is timed by the front rule
    where its room holds the move's length or the reach axis's travel to rest over the
    descent's time from its black moment to its front one at the motors' slowest (x1.5):
    with the arm ending at that moment, every point of the descent is clear by the front
    rule with the hand where the arm then is (at x1 and x1.5, rail steps of 0 and 42 mm).
    At rail 0: the first posture's ring and pinky on E4 keep it after either move (their
    rooms 20.9 and 41.2 mm against 15.7 and 13.4 mm of travel), the second posture's pinky
    on E4 (16.9 against 15.0 mm); the middle on C4 (9.0 mm against 17.0) keeps the black
    rule, and ended at its front moment at the slowest descent it is not clear. Moves into
    the keyboard keep the black rule; the same posture the front rule."""
    hc = places.high
    r = [places.reach_m(i) for i in range(places.postures)]
    kept = set()
    for e in _entries(places):
        p = e.posture
        assert hc.descent_front(e, r[p], r[p])
        for q in range(places.postures):
            if q < p:
                assert not hc.descent_front(e, r[q], r[p])  # (a move in)
            if q <= p:
                continue
            rule = hc.descent_front(e, r[q], r[p])
            for rail_m in (0.0, 0.042):
                for sigma in (1.0, 1.5):
                    assert _ends_clear(places, e, r[q], rail_m, sigma, rule)
            d = places.descend(e, "high").move
            if rule and hc.descent_clear_s(e, d) > hc.descent_clear_s(e, d, False) + 0.010:
                kept.add((p, q, e.finger, e.pitch_class))
    assert kept == {(0, 1, "ring", 4), (0, 2, "ring", 4), (0, 1, "pinky", 4),
                    (0, 2, "pinky", 4), (1, 2, "pinky", 4)}
    mid = places.atlases[0].entry("middle", 60, 0.0)
    assert not hc.descent_front(mid, r[1], r[0])
    assert not _ends_clear(places, mid, r[1], 0.0, 1.5, True)
    assert not hc.descent_front(None, r[1], r[0]) and hc.descent_front(None, r[0], r[0])


def _searched(places: Places) -> HighClear:
    """The same hand's moments with no table: every one searched by forward kinematics."""
    return HighClear(places.hand, places.atlases)


def test_the_shipped_moments_are_those_searched(places):
    """Every posture's table ships the moments (``MoveTable.clear_s``); on 30 entries of
    each they are, bit for bit, what the search finds on the entry's own moves (the
    planner reads them there: ``HighClear._shipped``)."""
    searched = _searched(places)
    rng = np.random.default_rng(7)
    for moves in places.moves:
        assert len(moves.table.clears) == len(moves.table.crossings) > 1000
        entries = [e for e in moves.atlas._entries.values() if e is not None]
        for i in rng.choice(len(entries), 30, replace=False):
            e = entries[i]
            row = [moves.table.clear_s(e, c, params())
                   for c in range(len(CLEAR_MOVES) * len(CLEAR_RULES) + 1)]
            assert None not in row
            assert row == searched.clear_row(e, moves)
            assert row == places.high.clear_row(e, moves)
            assert places.high.rise_clear_s(e, moves.lift(e, "high").move) == row[0]
            assert places.high.rise_clear_s(e, moves.lift(e, "high").move, False) == row[3]
            # (the front room, read: what forward kinematics finds on the entry's moves)
            assert places.high.front_room_m(e) == row[ROOM_COLUMN] == searched.room_of(e, moves)


def test_a_move_not_the_entrys_own_is_searched(places):
    """A move the table does not hold (another pose's lift, here one slowed to twice
    its time) is searched, not read: its moment is its own."""
    searched = _searched(places)
    e = next(_entries(places))
    u = places.lift(e, "high").move
    slow = slowed(u, 2.0)
    got = places.high.rise_clear_s(e, slow)
    assert got == searched.rise_clear_s(e, slow)
    assert got != places.high.rise_clear_s(e, u)


def test_moments_of_other_parameters_are_not_read(places):
    moves = places.moves[0]
    e = next(_entries(places))
    assert moves.table.clear_s(e, 0, params()) is not None
    assert moves.table.clear_s(e, 0, params().replace("samples", "points")) is None

"""Fingering by optimisation: a finger for every note, by dynamic programming
(Viterbi) over a song (or a part of one: play.py fingers a long song in parts).

Notes that start together (within ``CHORD_WINDOW_S``) form a group. For a
group of m notes, each candidate assigns m distinct fingers in the order of
the keys (thumb lowest, pinky highest: the hand does not cross over). A
candidate implies a rail position: the least-squares fit of the fingers'
natural lateral offsets (from the hand's rest posture, ``HandReach``) to
the keys. Its cost is

- stretch: squared distance of every finger from its natural place at that
  rail position, infinite beyond the finger's reach, or where two of its keys
  are a shape the hand cannot take (``pair_ok``: the planner's whole-hand IK;
  the lateral model alone misses, e.g., a finger between two pressing ones that
  has no room to clear the keys);
- the thumb (and, less, the pinky) on a black key;
and the cost of going from one candidate to the next is

- rail travel, and travel faster than the rail can comfortably go in the
  time between the groups (effectively infinite above its top speed);
- a change of hand position (no rail position serves both groups, a finger
  passes another or takes over its key, or a finger goes to a key further from
  the others it played since the hand last moved than it reaches with the arm
  still, ``HandReach.range_m``): ``MOVE_COST`` plus the music
  lost while the hand lifts, travels and lands (``reposition_s``) beyond the
  time every key is up anyway;
- a finger struck again sooner than it can come up and down (same key:
  ``HandReach.repeat_s``; another key: ``move_s``, both measured on the
  hand's own motions), as music lost;
- a key still held (from any earlier group, along the best path into each
  candidate) whose finger is wanted again, or that the new rail position
  leaves out of its finger's reach: it is let go ``CUT_LEAD_S`` before the new
  notes (``Assignment.release_s``) and the rest of it is music lost, so the
  fingering weighs cutting a held note short against the other ways on.

Music lost is weighed at ``LOST_S_COST`` per second.

No human annotation is used: all numbers come from the hand's kinematics.
A group the five fingers cannot hold whole (a chord wider than the hand, more
than five notes at once) is played in part: its largest subsets that they can
hold are the candidates, each left-out note costing its length as music lost
(the top note, often the melody, a little more); the notes left out, and notes
no candidate can play, are returned as infeasible with the reason.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.music import keyboard as kb

CHORD_WINDOW_S = 0.030
REUSE_S = 0.30  # time a finger needs to strike another key when the hand gives no measured move_s
# lift before and landing after the rail's move, beyond the rail's own time; a short move
# in a fast passage costs the notes after it more than its own time, while the fingers
# overlap most of a long one (measured: 0.00-0.04 s after moves of 0.15-0.25 m). So:
# the rail's time and REPOSITION_OVERHEAD_S, but no more than REPOSITION_CAP_S in all
# unless the rail itself takes longer, then its time and REPOSITION_OVERHEAD_MIN_S
REPOSITION_OVERHEAD_S = 0.15
REPOSITION_OVERHEAD_MIN_S = 0.03
REPOSITION_CAP_S = 0.25
MOVE_COST = 1.0  # any change of hand position (all fingers must be up)
LOST_S_COST = 50.0  # per second of a note the hand is still travelling in (or leaves out)
TOP_NOTE_COST = 1.0  # leaving out a chord's top note (often the melody) costs this much more
# a key held while later notes need its finger, or the hand where its finger cannot
# reach it, is let go this long before them (the rest of it is music lost)
CUT_LEAD_S = 0.060
MAX_GROUP = 10  # notes struck together beyond this many (the lowest) are not even tried  # a finger moved to another key sooner than this after its release is penalised
FINGER_ORDER = ("thumb", "index", "middle", "ring", "pinky")
# (finger 1, pitch 1, finger 2, pitch 2) -> whether both can be down at once
PairCheck = Callable[[str, int, str, int], bool]


@dataclass(frozen=True)
class HandReach:
    """Lateral reach of each finger relative to the rail (m), from the hand's rest posture.

    ``offset_m[f]``: x of finger f's tip minus the rail position, at rest.
    ``reach_m[f]``: how far (either way) the tip can move sideways from
    there without moving the rail (abduction and wrist deviation).
    ``spread_m[f]``: the same with the wrist still too: two fingers of one
    chord can be at most ``spread_m`` of each further apart than at rest.
    ``rail_speed_m_s``, ``rail_accel_m_s2``: the rail's top speed and acceleration;
    ``rail_range_m``: its travel. ``repeat_s[f]``, ``move_s[f]``: the shortest time from
    finger f letting a key up to striking it again, or striking the next white key
    (measured on the hand's own motions).
    """

    offset_m: dict[str, float]
    reach_m: dict[str, float]
    rail_speed_m_s: float
    rail_range_m: tuple[float, float]
    rail_accel_m_s2: float
    spread_m: dict[str, float] | None = None  # sideways reach with the wrist still too
    repeat_s: dict[str, float] | None = None  # key up to key down again, same key (s)
    move_s: dict[str, float] | None = None  # key up to key down on the next white key (s)
    # how far apart (m) two keys one finger plays from one hand position (rail and wrist
    # still) may be: its sideways reach from its key both ways together, from the hand on
    # white keys (see ``Planner._finger_ranges``). None: no limit beyond ``reach_m``
    range_m: dict[str, float] | None = None


@dataclass(frozen=True)
class Assignment:
    """A note and the finger that plays it; ``rail_m`` is the planned rail position."""

    note_index: int
    finger: str
    rail_m: float
    release_s: float | None = None  # let go by then, before its offset (a later note needs it)


@dataclass(frozen=True)
class Infeasible:
    note_index: int
    reason: str


def _groups(onsets: list[float]) -> list[list[int]]:
    groups: list[list[int]] = []
    for i, t in enumerate(onsets):
        if groups and t - onsets[groups[-1][0]] <= CHORD_WINDOW_S:
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def assign_fingers(notes, reach: HandReach, pair_ok: PairCheck | None = None
                   ) -> tuple[list[Assignment], list[Infeasible]]:
    """Choose a finger for every note of ``notes`` (sorted by onset, then pitch).

    ``pair_ok(f1, p1, f2, p2)``: whether finger f1 on pitch p1 and f2 on p2 can be
    down at once (the planner's whole-hand IK); every two keys of a chord must pass
    it. None: the lateral reach model alone."""
    order = sorted(range(len(notes)), key=lambda i: (notes[i].onset_s, notes[i].pitch))
    groups_local = _groups([notes[i].onset_s for i in order])
    groups = [[order[k] for k in g] for g in groups_local]
    infeasible: list[Infeasible] = []

    # candidates per group
    cands: list[list[tuple]] = []  # (fingers, rail, static cost, (rail lo, rail hi))
    kept_groups: list[list[int]] = []
    for g in groups:
        g = sorted(g, key=lambda i: notes[i].pitch)
        if len(g) > MAX_GROUP:  # (a cluster: its highest notes are tried)
            for i in g[:-MAX_GROUP]:
                infeasible.append(Infeasible(i, f"more than {MAX_GROUP} notes at once"))
            g = g[-MAX_GROUP:]
        cs = _candidates(notes, g, reach, pair_ok)
        if not cs:
            xs = [kb.key(notes[i].pitch).center_x_m for i in g]
            why = (f"chord wider than the hand ({(max(xs) - min(xs)) * 1000:.0f} mm)" if len(g) > 1
                   else "out of the rail's reach")
            for i in g:
                infeasible.append(Infeasible(i, why))
            continue
        cands.append(cs)
        kept_groups.append(g)

    if not kept_groups:
        return [], infeasible

    # Viterbi. Each group has one more state than its candidates: the group left out
    # (its notes as music lost), so that a note whose playing would cost more (keys held
    # before it let go early, a change of hand position) than it is worth is not played.
    n = len(kept_groups)
    onsets = [notes[g[0]].onset_s for g in kept_groups]
    skip_cost = [LOST_S_COST * sum(notes[i].offset_s - notes[i].onset_s for i in g) + TOP_NOTE_COST
                 for g in kept_groups]
    cost = [np.array([c[2] for c in cands[0]] + [skip_cost[0]])]
    back: list[np.ndarray] = [np.zeros(len(cands[0]) + 1, dtype=int)]
    # per state, along the best path into it: the notes (and fingers) sounding from its
    # group on (a key held over several later groups keeps its finger and its reach; a
    # group left out keeps those of the state before it, whose key-up time still counts),
    # the last state that plays (group, candidate; None before any), and the held notes
    # its transition lets go early
    sounding = [[tuple((i, f) for i, f in zip(kept_groups[0], c[0]) if f is not None) for c in cands[0]] + [()]]
    last = [[(0, a) for a in range(len(cands[0]))] + [None]]
    cuts: list[list[tuple[int, ...]]] = [[() for _ in range(len(cands[0]) + 1)]]
    # per state, along the best path into it: each finger's keys (lowest and highest x)
    # since the hand last moved
    spans = [[_key_spans(notes, kept_groups[0], c[0], {}) for c in cands[0]] + [{}]]
    for k in range(1, n):
        g, onset = kept_groups[k], onsets[k]
        held = [tuple((i, f) for i, f in snd if notes[i].offset_s > onset + 1e-6) for snd in sounding[k - 1]]
        free = [onset - max(notes[i].offset_s for i, _ in snd) if snd else math.inf for snd in sounding[k - 1]]
        m = len(cands[k])
        ck = np.empty(m + 1)
        bk = np.empty(m + 1, dtype=int)
        cuts_k: list[tuple[int, ...]] = []
        spans_k: list[dict] = []
        for b, (fb, rb, sb, span_b) in enumerate(cands[k]):
            best, arg, best_cut, best_move = math.inf, 0, (), False
            for a, e in enumerate(last[k - 1]):
                c, cut, move = 0.0, (), False
                if e is not None:
                    fa, ra, _, span_a = cands[e[0]][e[1]]
                    c, cut, move = _transition(notes, kept_groups[e[0]], fa, ra, span_a, g, fb, rb, span_b,
                                               max(onset - onsets[e[0]], 1e-3), free[a], held[a], reach,
                                               pair_ok, spans[k - 1][a])
                if cost[k - 1][a] + c < best:
                    best, arg, best_cut, best_move = cost[k - 1][a] + c, a, cut, move
            ck[b] = best + sb
            bk[b] = arg
            cuts_k.append(best_cut)
            spans_k.append(_key_spans(notes, g, fb, {} if best_move else spans[k - 1][arg]))
        a_best = int(np.argmin(cost[k - 1]))  # (left out: the best way here so far goes on)
        ck[m], bk[m] = cost[k - 1][a_best] + skip_cost[k], a_best
        cuts_k.append(())
        spans_k.append(spans[k - 1][a_best])
        spans.append(spans_k)
        cost.append(ck)
        back.append(bk)
        cuts.append(cuts_k)
        sounding.append([tuple((i, f) for i, f in held[int(bk[b])] if i not in cuts_k[b])
                         + tuple((i, f) for i, f in zip(g, c[0]) if f is not None)
                         for b, c in enumerate(cands[k])] + [sounding[k - 1][a_best]])
        last.append([(k, b) for b in range(m)] + [last[k - 1][a_best]])
    # backtrack (ties broken by the lowest index: deterministic)
    choice = [0] * n
    choice[-1] = int(np.argmin(cost[-1]))
    for k in range(n - 1, 0, -1):
        choice[k - 1] = int(back[k][choice[k]])
    # Rails: the chosen fingers leave each group an interval of rail positions
    # that reach all its keys; keep the rail still while the interval allows,
    # else move it a quarter of the interval inside the nearer end, so that the
    # hand only travels when it must.
    # (A change of hand position that the rail's interval alone does not ask for, a
    # finger beyond its range, keeps the rail: the planner finds the new position there.)
    rails: list[float] = []
    prev = None
    for k, g in enumerate(kept_groups):
        if choice[k] == len(cands[k]):  # left out
            rails.append(math.nan)
            continue
        fingers, rail, _, _ = cands[k][choice[k]]
        lo, hi = cands[k][choice[k]][3]
        if prev is None or not lo <= hi:
            r = rail
        elif lo <= prev <= hi:
            r = prev
        else:
            m = 0.25 * (hi - lo)
            r = min(max(prev, lo + m), hi - m)
        rails.append(r)
        prev = r
    release: dict[int, float] = {}  # held notes let go early (by that time)
    for k, g in enumerate(kept_groups):
        for i in cuts[k][choice[k]]:
            release[i] = notes[g[0]].onset_s - CUT_LEAD_S
    out: list[Assignment] = []
    for k, g in enumerate(kept_groups):
        if choice[k] == len(cands[k]):
            for i in g:
                infeasible.append(Infeasible(i, "left out: playing it would cost more music than it is "
                                                "(held keys let go early, the hand's way there)"))
            continue
        fingers, _, _, _ = cands[k][choice[k]]
        if not math.isfinite(cost[k][choice[k]]):
            for i in g:
                infeasible.append(Infeasible(i, "no fingering reaches it in time"))
            continue
        xs = [kb.key(notes[i].pitch).center_x_m for i in g]
        why = ("more than five notes at once" if len(g) > len(FINGER_ORDER)
               else f"chord wider than the hand ({(max(xs) - min(xs)) * 1000:.0f} mm)")
        for i, f in zip(g, fingers):
            if f is None:
                infeasible.append(Infeasible(i, f"{why}: left out"))
            elif i in release and release[i] < notes[i].onset_s + CUT_LEAD_S:
                infeasible.append(Infeasible(i, "left out: its finger, or the hand, is needed elsewhere "
                                                "at once"))
            else:
                out.append(Assignment(i, f, rails[k], release.get(i)))
    out.sort(key=lambda a: a.note_index)
    infeasible.sort(key=lambda x: x.note_index)
    return out, infeasible


def reposition_s(d_m: float, reach: HandReach) -> float:
    """Time (s) a change of hand position over ``d_m`` of rail takes: fingers up, the
    rail's minimum-jerk move (within its speed and acceleration), fingers down."""
    if d_m <= 0.0:
        return 0.0
    t_rail = max(1.875 * d_m / reach.rail_speed_m_s, math.sqrt(5.7735 * d_m / reach.rail_accel_m_s2))
    return max(t_rail + REPOSITION_OVERHEAD_MIN_S, min(t_rail + REPOSITION_OVERHEAD_S, REPOSITION_CAP_S))


def fit_rail(fingers, xs_m: np.ndarray, reach: HandReach) -> tuple[float, np.ndarray]:
    """The rail position (m) that puts ``fingers`` nearest, by their reach, to keys at
    ``xs_m`` (least squares of each finger's sideways stretch from its natural place
    over its reach), clipped to the rail's travel; and each finger's stretch there (m)."""
    offs = np.array([reach.offset_m[f] for f in fingers])
    w = 1.0 / np.array([reach.reach_m[f] for f in fingers]) ** 2
    rail = float(np.sum(w * (xs_m - offs)) / np.sum(w))
    rail = min(max(rail, reach.rail_range_m[0]), reach.rail_range_m[1])
    return rail, xs_m - offs - rail


def _candidates(notes, g: list[int], reach: HandReach, pair_ok: PairCheck | None = None) -> list[tuple]:
    """Fingerings of the group ``g`` (note indices by pitch) as (fingers, rail, static
    cost, rail span): ``fingers`` has one entry per note, None for a note left out. All
    of the group if five fingers can hold it, else its largest subsets that they can
    (each left-out note costs its length as music lost; the top note, often the melody,
    a little more)."""
    xs_all = np.array([kb.key(notes[i].pitch).center_x_m for i in g])
    for size in range(min(len(g), len(FINGER_ORDER)), 0, -1):
        cs = []
        for keep in itertools.combinations(range(len(g)), size):
            xs = xs_all[list(keep)]
            black = [kb.is_black(notes[g[k]].pitch) for k in keep]
            dropped = [g[k] for k in range(len(g)) if k not in keep]
            lost = LOST_S_COST * sum(notes[i].offset_s - notes[i].onset_s for i in dropped)
            lost += TOP_NOTE_COST if (len(g) - 1) not in keep else 0.0
            for fingers in itertools.combinations(FINGER_ORDER, size):
                offs = np.array([reach.offset_m[f] for f in fingers])
                lim = np.array([reach.reach_m[f] for f in fingers])
                rail, dev = fit_rail(fingers, xs, reach)
                if np.any(np.abs(dev) > lim):
                    continue
                if pair_ok is not None and not all(
                        pair_ok(fingers[a], notes[g[keep[a]]].pitch, fingers[b], notes[g[keep[b]]].pitch)
                        for a, b in itertools.combinations(range(size), 2)):
                    continue
                if reach.spread_m is not None and len(fingers) > 1:
                    sp = np.array([reach.spread_m[f] for f in fingers])
                    d0 = xs - offs
                    if np.any(np.abs(d0[:, None] - d0[None, :]) > sp[:, None] + sp[None, :] + 1e-12):
                        continue
                cost = float(np.sum((dev / lim) ** 2)) + lost
                # the rail positions from which these fingers reach these keys
                span = (float(np.max(xs - offs - lim)), float(np.min(xs - offs + lim)))
                for f, b in zip(fingers, black):
                    if b and f == "thumb":
                        cost += 2.0
                    elif b and f == "pinky":
                        cost += 0.5
                full = [None] * len(g)
                for k, f in zip(keep, fingers):
                    full[k] = f
                cs.append((tuple(full), rail, cost, span))
        if cs:
            return cs
    return []


def _crosses(notes, prev_g, fa, g, fb) -> bool:
    """True if some finger of the new group plays a key on the wrong side of (or the
    same key as) a key another finger played in the previous group."""
    a = [(FINGER_ORDER.index(f), notes[i].pitch)
         for i, f in zip(sorted(prev_g, key=lambda i: notes[i].pitch), fa) if f is not None]
    b = [(FINGER_ORDER.index(f), notes[i].pitch)
         for i, f in zip(sorted(g, key=lambda i: notes[i].pitch), fb) if f is not None]
    return any(f1 != f2 and (f1 - f2) * (p1 - p2) <= 0 for f1, p1 in a for f2, p2 in b)


def _key_spans(notes, g, fingers, before: dict) -> dict:
    """``before`` (finger -> (lowest, highest) x of its keys, m) with the keys of
    ``fingers`` on the group ``g`` added."""
    out = dict(before)
    for i, f in zip(sorted(g, key=lambda i: notes[i].pitch), fingers):
        if f is not None:
            x = kb.key(notes[i].pitch).center_x_m
            lo, hi = out.get(f, (x, x))
            out[f] = (min(lo, x), max(hi, x))
    return out


def _range_excess(notes, g, fb, spans: dict, reach: HandReach) -> float:
    """How far (m) the keys of ``fb`` on ``g`` take a finger beyond ``reach.range_m``
    from the keys it played since the hand last moved (``spans``)."""
    if reach.range_m is None:
        return 0.0
    worst = 0.0
    for f, (lo, hi) in _key_spans(notes, g, fb, spans).items():
        worst = max(worst, hi - lo - reach.range_m[f])
    return worst


def _transition(notes, prev_g, fa, ra, span_a, g, fb, rb, span_b, dt, free_s, held,
                reach: HandReach, pair_ok: PairCheck | None = None,
                spans: dict | None = None) -> tuple[float, tuple[int, ...], bool]:
    """The cost of going from candidate (fa, ra) of group ``prev_g`` to (fb, rb) of ``g``
    with the keys ``held`` ((note, finger) still down at ``g``'s onset), the held notes
    that must then be let go early (see ``CUT_LEAD_S``), and whether the hand changes
    position. ``spans``: each finger's keys since the hand last moved (``_key_spans``)."""
    d = abs(rb - ra)
    v = d / dt
    if v > reach.rail_speed_m_s:
        return 1e6 * (1.0 + v), (), True  # effectively infeasible, but keeps a path
    c = 10.0 * d + 20.0 * max(0.0, v - 0.5 * reach.rail_speed_m_s) ** 2
    # a rail position serving both groups: the hand stays; else it must lift, travel
    # and land between them, and every frame that takes is a frame of music lost
    gap = max(span_b[0] - span_a[1], span_a[0] - span_b[1], 0.0)
    if gap == 0.0 and (_crosses(notes, prev_g, fa, g, fb) or (pair_ok is not None and not all(
            pair_ok(f1, notes[i1].pitch, f2, notes[i2].pitch)
            for i1, f1 in zip(prev_g, fa) if f1 is not None
            for i2, f2 in zip(g, fb) if f2 is not None and f2 != f1))):
        # a finger passing another (or taking over its key) needs the hand moved too, and
        # so do two keys no one hand shape reaches
        gap = kb.WHITE_PITCH_M
    if gap == 0.0 and spans:
        # a finger sent further from its earlier keys here than it reaches with the arm still
        excess = _range_excess(notes, g, fb, spans, reach)
        if excess > 1e-9:
            gap = max(excess, kb.WHITE_PITCH_M)
    prev_finger = {i: f for i, f in zip(sorted(prev_g, key=lambda i: notes[i].pitch), fa) if f is not None}
    new_finger = {i: f for i, f in zip(sorted(g, key=lambda i: notes[i].pitch), fb) if f is not None}
    used_now = {f: notes[i].pitch for i, f in new_finger.items()}
    onset = notes[g[0]].onset_s
    cut = []
    for i, f in held:
        dev = kb.key(notes[i].pitch).center_x_m - reach.offset_m[f] - rb
        if f in used_now or abs(dev) > reach.reach_m[f] or (pair_ok is not None and not all(
                pair_ok(f, notes[i].pitch, f2, notes[j].pitch) for j, f2 in new_finger.items())):
            # its finger is wanted again, or the hand must leave it behind: the key is
            # let go CUT_LEAD_S before the new notes, and the rest of it is music lost
            cut.append(i)
            c += LOST_S_COST * (notes[i].offset_s - (onset - CUT_LEAD_S))
            continue
        c += 5.0 * d
    if cut:
        free_s = max(free_s, CUT_LEAD_S) if len(cut) == len(held) else free_s
    if gap > 0.0:
        c += MOVE_COST + LOST_S_COST * max(0.0, reposition_s(gap, reach) - max(free_s, 0.0))
    for i, f in prev_finger.items():
        # a finger struck again must first come up (and, for another key, lift, cross
        # and come down): the time it needs beyond its free time is music lost
        if f not in used_now:
            continue
        free = max(onset - notes[i].offset_s, 0.0)
        if used_now[f] == notes[i].pitch:
            need = reach.repeat_s[f] if reach.repeat_s else 0.0
        else:
            need = reach.move_s[f] if reach.move_s else REUSE_S
        c += LOST_S_COST * max(0.0, need - free)
    return c, tuple(cut), gap > 0.0

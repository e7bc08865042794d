"""Play: song -> fingering -> key states -> IK keyframes -> timed trajectory -> file.

Orchestration only: each stage lives in its own module. Rows are written
and flushed chunk by chunk while the song is planned.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from planner.errors import InputError
from planner.fingering import FINGER_ORDER, HandReach, assign_fingers
from planner.hand.model import HandModel, load_hand
from planner.ik import HandIK, PressTarget, press_target, surface_near
from planner.music import keyboard as kb
from planner.music.midi import Song, load_song, pitch_name
from planner.targets import KeyState, build_states, descent_time_s, press_intervals
from planner.trajectory import Phase, build_timing, min_jerk_inverse, phase_duration, sample, solve_timing
from planner.trajfile import TrajectoryWriter

TRAVEL_Z_M = kb.BLACK_TOP_Z_M + 0.010  # lifted fingertips clear every key by 10 mm
DIRECT_MOVE_M = 0.006  # moving tips that shift less than this sideways go straight
LATE_S = 0.020  # a note whose key goes down later than this is reported
CHUNK_STATES = 12
REST_HOVER_Z_M = 0.020


@dataclass(frozen=True)
class NoteReport:
    index: int
    pitch: int
    onset_s: float
    finger: str | None
    reason: str | None  # None: played as written


@dataclass
class PlayResult:
    rows: int
    duration_s: float
    notes: list[NoteReport]
    planning_s: float
    first_row_s: float
    ik_solves: int
    late: list[tuple[int, float]] = field(default_factory=list)

    @property
    def infeasible(self) -> list[NoteReport]:
        return [n for n in self.notes if n.reason is not None]


class Planner:
    """Everything built once per hand: IK solver, rest posture, reach table."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        self.ik = HandIK(hand)
        self.rail = hand.index.get("rail")
        self.rest = self._rest_posture()
        tips = hand.tip_positions(self.rest)
        rail0 = self.rest[self.rail] if self.rail is not None else 0.0
        offsets = {f: float(tips[i, 0] - rail0) for i, f in enumerate(hand.fingers)}
        reach = {f: self._probe_reach(f, tips[i]) for i, f in enumerate(hand.fingers)}
        lo = hand.lower[self.rail] if self.rail is not None else 0.0
        hi = hand.upper[self.rail] if self.rail is not None else 0.0
        vmax = hand.velocity[self.rail] if self.rail is not None else 1e-9
        self.reach = HandReach(offsets, reach, float(vmax), (float(lo), float(hi)))

    def _rest_posture(self) -> np.ndarray:
        """The natural hovering hand at rail 0: fingertips over their knuckles, 20 mm above
        the keys, the thumb in front of the index (computed by IK, not typed)."""
        h = self.hand
        q0 = h.q_neutral.copy()
        for f in h.fingers:  # a curled start
            idx = h.joint_slice(f)
            for j in idx[1:]:
                q0[j] = 0.5 * (h.lower[j] + h.upper[j]) * 0.6
        q0 = h.apply_couplings(np.clip(q0, h.lower, h.upper))
        targets = []
        for f in h.fingers:
            j = h.spec.joint(h.spec.joints_of(f)[0])
            x = j.xyz_m[0] if f != "thumb" else h.spec.joint("index_mcp_abd").xyz_m[0] - 0.035
            y = 0.095 if f != "thumb" else 0.030
            targets.append(PressTarget(f, 0, (x, y, REST_HOVER_Z_M), (y, y)))
        r = self.ik.solve(targets, q0, q0, hover=())
        return r.q

    def _probe_reach(self, finger: str, tip: np.ndarray) -> float:
        """How far (m) a fingertip can move sideways from rest, rail and wrist locked.

        Found by IK: the largest d in 2.5 mm steps for which the tip reaches
        rest +/- d at hover height (the smaller of the two sides)."""
        ik = self.ik
        locked = [n for n in ("rail", "wrist_flex", "wrist_dev") if n in self.hand.index]
        for n in locked:
            ik.solver.mask_dof(n)
        try:
            best = []
            for sign in (-1.0, 1.0):
                d_ok = 0.0
                for step in range(1, 25):
                    d = 0.0025 * step
                    y = float(tip[1])
                    t = PressTarget(finger, 0, (float(tip[0]) + sign * d, y, float(tip[2])), (y - 0.03, y + 0.03))
                    r = ik.solve([t], self.rest, self.rest, hover=())
                    if not r.converged:
                        break
                    d_ok = d
                best.append(d_ok)
        finally:
            for n in locked:
                ik.solver.unmask_dof(n)
        return min(best)

    def posture_at(self, rail_m: float) -> np.ndarray:
        q = self.rest.copy()
        if self.rail is not None:
            q[self.rail] = min(max(rail_m, self.hand.lower[self.rail]), self.hand.upper[self.rail])
        return q

    # ------------------------------------------------------------ helpers
    def lift(self, q: np.ndarray, fingers) -> np.ndarray:
        """``q`` with the named fingertips raised to travel height by their own flexion joints."""
        h = self.hand
        q = q.copy()
        for _ in range(4):
            tips = h.tip_positions(q)
            J = h.tip_jacobians(q)
            S = h.dq_dindependent(q)
            moved = False
            for f in fingers:
                k = h.fingers.index(f)
                dz = TRAVEL_Z_M - tips[k, 2]
                if dz <= 1e-4:
                    continue
                cols = [c for c in h.joint_slice(f)[1:] if c in set(h.independent.tolist())]
                ci = [int(np.where(h.independent == c)[0][0]) for c in cols]
                Jz = (J[k, 2] @ S)[ci]
                dq = Jz * dz / (Jz @ Jz + 1e-6)
                q[cols] += dq
                moved = True
            q = h.apply_couplings(np.clip(q, h.lower, h.upper))
            if not moved:
                break
        return q


def _moving_shift(hand: HandModel, qa: np.ndarray, qb: np.ndarray, fingers) -> float:
    if not fingers:
        return 0.0
    ta, tb = hand.tip_positions(qa), hand.tip_positions(qb)
    return max(float(np.linalg.norm((tb - ta)[hand.fingers.index(f), :2])) for f in fingers)


def _crossing_fraction(z_from: float, z_to: float, z_cross: float) -> float:
    s = (z_cross - z_from) / (z_to - z_from) if z_to != z_from else 0.5
    return min_jerk_inverse(min(max(s, 0.0), 1.0))


def plan_song(song: Song, hand: HandModel, out_path: str, rate_hz: float = 100.0,
              song_name: str = "", progress: bool = False, planner: Planner | None = None) -> PlayResult:
    """Plan ``song`` on ``hand`` and stream the trajectory to ``out_path`` ('-' = stdout)."""
    if not (math.isfinite(rate_hz) and 1.0 <= rate_hz <= 10000.0):
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate_hz}")
    t_start = time.perf_counter()
    pl = planner or Planner(hand)
    notes = list(song.notes)
    assignments, infeasible = assign_fingers(notes, pl.reach)
    reasons: dict[int, str] = {x.note_index: x.reason for x in infeasible}
    finger_of = {a.note_index: a.finger for a in assignments}
    rail_of = {a.note_index: a.rail_m for a in assignments}
    intervals = press_intervals(notes, assignments)
    states = build_states(intervals, rail_of, float(pl.rest[pl.rail]) if pl.rail is not None else 0.0)
    if states and states[0].t_s > 0.0:
        pass

    meta = {"task": "play", "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
            "T_world_root": hand.T_world_root.tolist(), "rate_hz": rate_hz,
            "song": song_name, "notes": len(notes)}
    writer = TrajectoryWriter(out_path, meta, hand.joint_names, hand.motor_names)
    try:
        result = _run(pl, hand, notes, states, writer, rate_hz, reasons, progress, t_start)
    except BaseException:
        writer.abort()
        raise
    writer.close()
    result.planning_s = time.perf_counter() - t_start
    result.notes = [NoteReport(i, n.pitch, n.onset_s, finger_of.get(i), reasons.get(i))
                    for i, n in enumerate(notes)]
    return result


def _run(pl: Planner, hand: HandModel, notes, states: list[KeyState], writer: TrajectoryWriter,
         rate_hz: float, reasons: dict[int, str], progress: bool, t_start: float) -> PlayResult:
    dt = 1.0 / rate_hz
    end_song = max((n.offset_s for n in notes), default=0.0)
    q_prev = pl.posture_at(states[0].rail_hint_m if states else 0.0)

    def prepare_for(k: int) -> list[PressTarget]:
        """Fingers free in state k that press a new key in state k+1 wait above it."""
        if k + 1 >= len(states):
            return []
        now = {(p.finger, p.pitch) for p in states[k].presses} if k >= 0 else set()
        busy = {f for f, _ in now}
        return [press_target(p.finger, p.pitch) for p in states[k + 1].presses
                if (p.finger, p.pitch) not in now and p.finger not in busy
                and p.note_index not in dropped]

    # the start: the hand hovering where it will play first (brought there before t = 0)
    dropped: set[int] = set(reasons)
    first = pl.ik.solve([], q_prev, q_prev, prepare=prepare_for(-1))
    q_prev = first.q
    prev_state = KeyState(0.0, (), states[0].rail_hint_m if states else 0.0)
    next_row = 0
    t_committed = 0.0
    first_row_s = math.nan
    ik_solves = 1
    late: list[tuple[int, float]] = []
    pending: list[tuple[Phase, str, int | None]] = []
    total = len(states)

    def flush(phases_meta, hold_q, final_t=None):
        nonlocal next_row, t_committed, first_row_s
        phases = [p for p, _, _ in phases_meta]
        prob = build_timing(phases, t_committed)
        starts = solve_timing(prob)
        for (p, kind, note), s in zip(phases_meta, starts):
            if kind == "press" and note is not None:
                lateness = s + p.anchor * p.duration_s - p.ideal_s
                if lateness > LATE_S:
                    late.append((note, lateness))
        end_t = float(starts[-1] + phases[-1].duration_s) if phases else t_committed
        if final_t is not None:
            end_t = max(end_t, final_t)
        n_rows_end = int(math.floor(end_t * rate_hz + 1e-9)) + (1 if final_t is not None else 0)
        if n_rows_end > next_row:
            t = np.arange(next_row, n_rows_end) * dt
            q = sample(phases, starts, t, hold_q)
            q = hand.apply_couplings(q)
            writer.write_rows(t, q, hand.motor_angles(q))
            if math.isnan(first_row_s):
                first_row_s = time.perf_counter() - t_start
            next_row = n_rows_end
        t_committed = max(end_t, next_row * dt - dt)

    hold = q_prev
    for k, st in enumerate(states):
        presses = [p for p in st.presses if p.note_index not in dropped]
        # the rail stays where it is unless a key needs it elsewhere (the IK's
        # rail task is soft): the hand travels only when it must
        posture = pl.posture_at(q_prev[pl.rail] if pl.rail is not None else 0.0)
        targets = [press_target(p.finger, p.pitch) for p in presses]
        prep = prepare_for(k)
        r = pl.ik.solve(targets, q_prev, posture, prepare=prep)
        ik_solves += 1
        if not r.converged:
            r = pl.ik.solve(targets, posture, posture, prepare=prep)
            ik_solves += 1
        while not r.converged and presses:
            # drop the press that is new in this state and farthest from the rest of the chord
            held = {(p.finger, p.pitch) for p in prev_state.presses}
            cand = [p for p in presses if (p.finger, p.pitch) not in held] or presses
            worst = cand[-1]
            reasons[worst.note_index] = f"out of reach (IK error {r.press_error_m * 1000:.1f} mm)"
            dropped.add(worst.note_index)
            presses = [p for p in presses if p is not worst]
            targets = [press_target(p.finger, p.pitch) for p in presses]
            r = pl.ik.solve(targets, posture, posture, prepare=prep)
            ik_solves += 1
        q_next = r.q
        # torque bound for the press forces
        if presses:
            tau = hand.press_torques(q_next, {p.finger: p.force_n for p in presses})
            over = np.abs(tau) > hand.motor_peak_torque
            if np.any(over):
                m = int(np.argmax(np.abs(tau) / hand.motor_peak_torque))
                for p in presses:
                    reasons.setdefault(p.note_index, f"torque above bound (motor.{hand.motor_names[m]} "
                                       f"{abs(tau[m]):.2f} > {hand.motor_peak_torque[m]:.2f} N m)")
        cur = KeyState(st.t_s, tuple(presses), st.rail_hint_m)
        pending += _transition(pl, hand, prev_state, q_prev, cur, q_next)
        prev_state, q_prev = cur, q_next
        if len(pending) >= CHUNK_STATES * 3 or k == total - 1:
            flush(pending, hold)
            hold = q_prev
            pending = []
        if progress and total > 200 and k % 50 == 0:
            sys.stderr.write(f"\rplanning {k}/{total} states ({100 * k // total}%)")
            sys.stderr.flush()
    if progress and total > 200:
        sys.stderr.write(f"\rplanning {total}/{total} states (100%)\n")
    # settle and finish
    flush(pending, hold, final_t=max(end_song + 0.25, t_committed + 0.25))
    return PlayResult(writer.rows, writer.rows * dt, [], 0.0, first_row_s, ik_solves, late)


def _transition(pl: Planner, hand: HandModel, a: KeyState, qa: np.ndarray, b: KeyState,
                qb: np.ndarray) -> list[tuple[Phase, str, int | None]]:
    """Phases taking the hand from state ``a`` (at ``qa``) to state ``b`` (at ``qb``) at b.t_s."""
    pa = {(p.finger, p.pitch) for p in a.presses}
    pb = {(p.finger, p.pitch) for p in b.presses}
    releasing = sorted({f for f, k in pa - pb}, key=FINGER_ORDER.index)
    new = [p for p in b.presses if (p.finger, p.pitch) not in pa]
    pressing = [p.finger for p in new]
    v, acc = hand.velocity, hand.acceleration
    e = b.t_s
    note = new[0].note_index if new else None
    vel = max((p.velocity for p in new), default=64)
    if np.allclose(qa, qb, atol=1e-9):
        return []
    low = kb.DOWN_DEPTH_M
    if _moving_shift(hand, qa, qb, releasing + pressing) <= DIRECT_MOVE_M:
        T = phase_duration(qb - qa, v, acc)
        if pressing:
            T = max(T, 0.5 * descent_time_s(vel))
        anchor = 0.5
        return [(Phase(qa, qb, T, anchor, e, 1.0), "press" if pressing else "move", note)]
    out: list[tuple[Phase, str, int | None]] = []
    q_up = pl.lift(qa, releasing) if releasing else qa
    q_over = pl.lift(qb, pressing) if pressing else qb
    if releasing:
        z0 = -kb.KEY_DIP_M
        frac = _crossing_fraction(z0, TRAVEL_Z_M, z0 + low)
        out.append((Phase(qa, q_up, phase_duration(q_up - qa, v, acc), frac, e, 0.5), "release", None))
    out.append((Phase(q_up, q_over, phase_duration(q_over - q_up, v, acc), 0.5, e, 0.01), "move", None))
    if pressing:
        z1 = -kb.KEY_DIP_M
        frac = _crossing_fraction(TRAVEL_Z_M, z1, z1 + low)
        T = max(phase_duration(qb - q_over, v, acc), descent_time_s(vel))
        out.append((Phase(q_over, qb, T, frac, e, 1.0), "press", note))
    return out


# ---------------------------------------------------------------- CLI glue


def format_summary(song_name: str, res: PlayResult, song_s: float, out: str) -> str:
    n = len(res.notes)
    bad = res.infeasible
    rtf = song_s / res.planning_s if res.planning_s > 0 else math.inf
    lines = [f"{song_name}: {n} notes, {n - len(bad)} played, {len(bad)} infeasible; "
             f"{res.rows} rows ({res.duration_s:.2f} s) -> {out}",
             f"planning {res.planning_s * 1000:.0f} ms for {song_s:.2f} s of music "
             f"(real-time factor {rtf:.0f}x), first row after {res.first_row_s * 1000:.0f} ms, "
             f"{res.ik_solves} IK solves"]
    for nr in bad:
        lines.append(f"  infeasible: t={nr.onset_s:.3f} s {pitch_name(nr.pitch)} (MIDI {nr.pitch}): {nr.reason}")
    for i, lt in res.late:
        nt = res.notes[i]
        lines.append(f"  late: t={nt.onset_s:.3f} s {pitch_name(nt.pitch)} key down {lt * 1000:.0f} ms late "
                     "(too fast for the motors)")
    return "\n".join(lines)


def play_cli(a) -> int:
    song = load_song(a.song, track=a.track, channel=a.channel, transpose=a.transpose)
    hand = load_hand(a.hand)
    out = a.output if a.output is not None else os.path.splitext(a.song)[0] + ".csv"
    name = os.path.basename(a.song)
    res = plan_song(song, hand, out, a.rate, song_name=name,
                    progress=sys.stderr.isatty())
    sys.stderr.write(format_summary(name, res, max((n.offset_s for n in song.notes), default=0.0),
                                    out) + "\n")
    if a.report or a.html:
        from planner import report

        if a.report:
            report.write_play_report(a.report, out, a.song)
        if a.html:
            report.write_html(a.html, out)
    if a.strict and (res.infeasible or res.late):
        return 1
    return 0

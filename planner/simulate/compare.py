"""Physics against the kinematic check, note by note: where the two F1s differ and why.

The frame F1 is a mean over the song's frames of each frame's F1, so the difference
``kinematic F1 - physics F1`` is a sum over frames. A frame's difference is shared
equally among the keys whose state differs in it (down in one replay, up in the other),
and each such (frame, key) goes to the note of that key it belongs to: the note sounding
then, or the nearest note of that key within ``NEAR_NOTE_S`` (a key still rising after
its note, down a frame early); what is left is a wrong key of its own. The shares add up
to the whole difference (tested).

For each note or wrong key the physics' own account: the frames it lost at the onset
(the key went down later than the kinematic rule says), in the middle, at the release
(kept down after the note: the key returning), the finger on it and how far that
finger's pad was from its planned place (simulated minus planned, mm, the largest over
the frames concerned).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.check.bodykeys import body_keys
from planner.check.criteria import (
    expected_keys,
    frame_scores,
    key_contacts,
    pitch_name,
    song_frames,
)
from planner.check.kinematics import Kinematics
from planner.hand.bodies import collision_bodies
from planner.music.keyboard import LOWEST_PITCH, WHITE_WIDTH_M
from planner.simulate.planbody import plan_body_keys
from planner.simulate.scores import key_down

NEAR_NOTE_S = 0.1  # a key state this close to a note of its key belongs to that note
WIDE_MM = 1000.0 * WHITE_WIDTH_M - 1e-6  # narrower (mm) than a white key's front: named
LIFTED_MM = 2.0  # a pad this far above its plan is held up by more than its servo's give


def _width_mm(pitch: int, y_m: float) -> float:
    """The width of a key's footprint at ``y_m`` (its box there), mm."""
    from planner.simulate.keyboard import key_body

    for b in key_body(pitch).boxes:
        if abs(y_m - b.center_m[1]) <= b.half_m[1]:
            return 2000.0 * b.half_m[0]
    return float("nan")


@dataclass(frozen=True)
class NoteDifference:
    """One note (``onset_s`` >= 0 and its index) or a wrong key (``note`` = -1)."""

    note: int
    name: str
    pitch: int
    onset_s: float
    lost_f1: float  # its share of kinematic F1 - physics F1
    onset_frames: int  # down in the kinematic replay, not yet in physics, at the start
    middle_frames: int  # down in the kinematic replay, up in physics, within the note
    release_frames: int  # down in physics after the kinematic release (or the note's end)
    extra_frames: int  # down in physics where the kinematic replay is up (wrong key)
    fingers: tuple[str, ...]  # fingers touching the key in physics over those frames
    pad_error_mm: float  # largest |simulated - planned| pad point of those fingers
    pad_dz_mm: float  # its height error there (simulated - planned: > 0 above the plan)
    plan_y_mm: float = float("nan")  # the planned pressing pad's y on the key (mm back)
    key_width_mm: float = float("nan")  # the key's footprint width at that y
    touched: tuple[str, ...] = ()  # other keys the planned finger touches in physics then
    plan_finger: str = ""  # the finger the plan presses the note with
    finger_width_mm: float = 0.0  # that finger's end in the scene (its width across)
    plan_frames: int = 0  # of its frames, those where the plan's own finger bodies reach
    # the key (``planner.simulate.planbody``; full contact only): a wrong key the plan puts
    # a finger's body on, before any dynamics

    @property
    def kind(self) -> str:
        """One cause per difference: ``wrong`` (a key down outside its notes), ``narrow``
        (pressed where the key is narrower than the finger's end), ``lifted`` (the pad
        held over ``LIFTED_MM`` above its plan: a finger's end or segment on a key bed),
        ``timing`` (the key's own onset and return)."""
        if self.note < 0:
            return "wrong"
        if self.key_width_mm < self.finger_width_mm:
            return "narrow"
        return "lifted" if self.pad_dz_mm > LIFTED_MM else "timing"

    @property
    def cause(self) -> str:
        parts = []
        if self.onset_frames:
            parts.append(f"down {self.onset_frames} frames late")
        if self.middle_frames:
            parts.append(f"up {self.middle_frames} frames within the note")
        if self.release_frames:
            parts.append(f"still down {self.release_frames} frames after its release")
        if self.extra_frames:
            parts.append(f"down {self.extra_frames} frames outside any note")
        if self.touched:
            parts.append(f"the finger on {'+'.join(self.touched)}")
        if self.plan_frames:
            parts.append(f"the plan's finger body on it in {self.plan_frames} of them")
        if math.isfinite(self.key_width_mm) and self.key_width_mm < WIDE_MM:
            parts.append(f"pressed {self.plan_y_mm:.0f} mm back, where the key is "
                         f"{self.key_width_mm:.1f} mm wide (the {self.plan_finger}'s end "
                         f"{self.finger_width_mm:.1f} mm)")
        return ", ".join(parts) or "physics down where the kinematic replay is not"


def _owner(notes_of_key: list[tuple[int, float, float]], t: float) -> int:
    """Index of the note of a key that frame time ``t`` belongs to, -1 for none."""
    best, gap = -1, NEAR_NOTE_S
    for i, on, off in notes_of_key:
        if on <= t < off:
            return i
        d = on - t if t < on else t - off
        if d <= gap:
            best, gap = i, d
    return best


def note_differences(replay, rate_hz: float | None = None) -> tuple[NoteDifference, ...]:
    """The notes and wrong keys behind the F1 difference of a play ``run_replay``
    (largest share first)."""
    rec, notes = replay.record, replay.notes
    if notes is None:
        return ()
    rate = rate_hz or float(replay.trajectory.metadata["rate_hz"])
    frames = song_frames(notes, rate)
    n = min(len(frames), len(rec.t_s))
    planned = np.array([replay.hand.tip_positions(q) for q in rec.q_ref[:n]])
    kin = np.zeros((len(frames), 88), dtype=bool)
    phys = np.zeros_like(kin)
    kc = key_contacts(planned)
    # (the plan's keys by check's rule, the hand's bodies: what ``kinematic_f1`` scores)
    kin[:n] = body_keys(Kinematics(replay.hand, np.asarray(
        replay.trajectory.metadata["T_world_root"], dtype=float)), rec.q_ref[:n],
        collision_bodies(replay.hand.spec)).down
    phys[:n] = key_down(rec)[:n]
    expected = expected_keys(notes, frames)
    f1k = frame_scores(expected, kin)[2]
    f1p = frame_scores(expected, phys)[2]
    loss = (f1k - f1p) / len(frames)
    by_key: dict[int, list] = {}
    for i, nt in enumerate(notes):
        by_key.setdefault(nt.pitch - LOWEST_PITCH, []).append((i, nt.onset_s, nt.offset_s))
    acc: dict[tuple, dict] = {}
    pad_err = np.linalg.norm(rec.tips_m[:n] - planned, axis=2) * 1000.0  # (n, 5) mm
    press = _plan_presses(notes, frames[:n], kc, planned)
    fingers = replay.hand.fingers
    widths = _finger_widths_mm(replay.scene, fingers)
    in_plan = (plan_body_keys(replay.hand, rec.q_ref[:n], kc)
               if replay.report.contact == "full" else np.zeros((n, 88), dtype=bool))
    for t, k in zip(*np.nonzero(kin != phys)):
        share = loss[t] / np.count_nonzero(kin[t] != phys[t])
        i = _owner(by_key.get(int(k), []), float(frames[t]))
        key = ("note", i) if i >= 0 else ("wrong", int(k))
        a = acc.setdefault(key, {"lost": 0.0, "onset": 0, "middle": 0, "release": 0,
                                 "extra": 0, "fingers": set(), "err": 0.0, "dz": 0.0,
                                 "k": int(k), "touched": set(), "t0": float(frames[t]),
                                 "plan": 0})
        if t < n and in_plan[t, k]:
            a["plan"] += 1
        if t < n and i >= 0 and kin[t, k]:
            f = press.get(i, (-1, 0.0))[0]
            a["touched"].update(int(q) + LOWEST_PITCH for q in np.flatnonzero(
                rec.key_finger[t] == f) if f >= 0 and q != k)
        a["lost"] += share
        if i >= 0:
            on, off = notes[i].onset_s, notes[i].offset_s
            inside = on <= frames[t] < off
            if kin[t, k] and inside:
                first = not phys[int(np.searchsorted(frames, on)):t + 1, k].any()
                a["onset" if first else "middle"] += 1
            elif phys[t, k]:
                a["release" if frames[t] >= on else "onset"] += 1
            else:
                a["middle"] += 1
        else:
            a["extra"] += 1
        if t < n:
            f = int(rec.key_finger[t, k])
            if f >= 0:
                a["fingers"].add(fingers[f])
                if pad_err[t, f] > a["err"]:
                    a["err"] = float(pad_err[t, f])
                    a["dz"] = float(rec.tips_m[t, f, 2] - planned[t, f, 2]) * 1000.0
    out = []
    for (kind, i), a in acc.items():
        p = a["k"] + LOWEST_PITCH
        f, y = press.get(i, (-1, float("nan"))) if kind == "note" else (-1, float("nan"))
        out.append(NoteDifference(
            i if kind == "note" else -1, pitch_name(p), p,
            float(notes[i].onset_s) if kind == "note" else a["t0"], float(a["lost"]),
            a["onset"], a["middle"], a["release"], a["extra"],
            tuple(sorted(a["fingers"], key=fingers.index)), a["err"], a["dz"], y * 1000.0,
            _width_mm(p, y) if math.isfinite(y) else float("nan"),
            tuple(pitch_name(q) for q in sorted(a["touched"])),
            fingers[f] if f >= 0 else "", widths[f] if f >= 0 else 0.0, a["plan"]))
    out.sort(key=lambda d: -d.lost_f1)
    return tuple(out)


def _plan_presses(notes, frames: np.ndarray, kc, planned: np.ndarray) -> dict:
    """Note index -> (finger, pad y) where the plan first presses it (key down by a pad
    on it), for the notes the plan presses."""
    out = {}
    for i, nt in enumerate(notes):
        k = nt.pitch - LOWEST_PITCH
        a, b = np.searchsorted(frames, [nt.onset_s, nt.offset_s])
        for t in range(int(a), int(b)):
            on = np.flatnonzero(kc.tip_key[t] == k)
            if kc.down[t, k] and len(on):
                f = int(on[np.argmax(np.nan_to_num(kc.tip_depth[t, on]))])
                out[i] = (f, float(planned[t, f, 1]))
                break
    return out


def _finger_widths_mm(scene, fingers: tuple[str, ...]) -> list[float]:
    """Each finger's end in the scene: the width across it (its link's x) of the colliding
    geoms of its pad's link, the pad sphere and the distal segment's capsules (mm; 2 with
    pads only, the pad point's sphere)."""
    if scene is None:
        return [0.0] * len(fingers)
    m = scene.model
    out = []
    for f in fingers:
        body = m.geom_bodyid[m.geom(f"{f}_pad").id]
        gs = [g for g in range(m.ngeom) if m.geom_bodyid[g] == body and m.geom_contype[g]]
        lo = min(m.geom_pos[g][0] - m.geom_size[g][0] for g in gs)
        hi = max(m.geom_pos[g][0] + m.geom_size[g][0] for g in gs)
        out.append(1000.0 * float(hi - lo))
    return out

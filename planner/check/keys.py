"""The keys of a play replay: key-down episodes, key-bed hits, and against a song the
frame scores over the song's frames, note hits, lateness and wrong presses."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.check.criteria import (
    KEY_BED_DEPTH_M,
    LOWEST_PITCH,
    NOTE_HIT_FRACTION,
    KeyContacts,
    expected_keys,
    frame_scores,
    key_contacts,
    note_outcomes,
    pitch_name,
    song_frames,
)
from planner.check.results import KeyBedHit, KeyEpisode, LateNote, MissedNote, PlayResult
from planner.hand.spec import FINGERS
from planner.trajfile import Trajectory

KEY_BED_TOL_M = 2e-6  # fingertip rounding (1e-6 rad over a ~0.4 m chain)


def _frame_period(t_s: np.ndarray) -> float:
    return float(np.median(np.diff(t_s))) if len(t_s) > 1 else 0.01


def key_episodes(mask: np.ndarray, t_s: np.ndarray, finger: np.ndarray | None = None,
                 names: tuple[str, ...] = FINGERS) -> list[KeyEpisode]:
    """Contiguous runs of True in each key column of ``mask`` (T, 88), sorted by start;
    ``finger`` (T, 88): who holds each key down, an index into ``names`` (-1 none).

    An episode lasts from its first frame's time to the next frame's time
    (one median period past the last row at the end of the file).
    """
    t_s = np.asarray(t_s, dtype=float)
    T = len(t_s)
    t_end = np.append(t_s[1:], t_s[-1] + _frame_period(t_s)) if T else t_s
    m = np.asarray(mask, dtype=bool)
    pad = np.zeros((1, m.shape[1]), dtype=bool)
    edges = np.diff(np.vstack([pad, m, pad]).astype(np.int8), axis=0)
    out = []
    for k in np.flatnonzero(m.any(axis=0)):
        starts = np.flatnonzero(edges[:, k] == 1)
        stops = np.flatnonzero(edges[:, k] == -1)  # exclusive
        for a, b in zip(starts, stops):
            fingers: tuple[str, ...] = ()
            if finger is not None:
                fs = finger[a:b, k]
                fingers = tuple(names[i] for i in sorted(set(fs[fs >= 0].tolist())))
            p = int(k) + LOWEST_PITCH
            out.append(KeyEpisode(p, pitch_name(p), float(t_s[a]), float(t_end[b - 1]), fingers))
    out.sort(key=lambda e: (e.start_s, e.pitch))
    return out


def play_replay(tr: Trajectory, tips: np.ndarray, notes
                ) -> tuple[PlayResult, KeyContacts, np.ndarray | None]:
    """Keys of every row; with ``notes``, the scores over the song's frames (criteria)."""
    t = tr.t_s
    kc = key_contacts(tips)
    played = key_episodes(kc.down, t, kc.finger)
    deep = np.nan_to_num(kc.tip_depth, nan=-1.0) > KEY_BED_DEPTH_M + KEY_BED_TOL_M
    hits = []
    for r, f in zip(*np.nonzero(deep)):
        p = int(kc.tip_key[r, f]) + LOWEST_PITCH
        hits.append(KeyBedHit(float(t[r]), FINGERS[f], p, pitch_name(p),
                              float(kc.tip_depth[r, f])))
    if notes is None:
        return PlayResult(len(t), tuple(played), tuple(hits)), kc, None
    score = score_song(t, kc.down, kc.finger, notes, float(tr.metadata["rate_hz"]))
    res = PlayResult(len(t), tuple(played), tuple(hits), f1=score.f1,
                     precision=score.precision, recall=score.recall, notes=len(notes),
                     notes_hit=len(notes) - len(score.missed), missed=score.missed,
                     wrong_presses=score.wrong_presses, late=score.late,
                     song_frames=score.song_frames)
    return res, kc, expected_keys(notes, t)


@dataclass(frozen=True)
class SongScore:
    """A replay's keys scored against a song (criteria): frame scores over the song's
    frames, the notes missed and late, and the keys pressed where no note sounds."""

    f1: float
    precision: float
    recall: float
    song_frames: int
    missed: tuple[MissedNote, ...]
    late: tuple[LateNote, ...]
    wrong_presses: tuple[KeyEpisode, ...]


def score_song(t: np.ndarray, down_rows: np.ndarray, finger_rows: np.ndarray | None, notes,
               rate_hz: float, names: tuple[str, ...] = FINGERS) -> SongScore:
    """Score key states ``down_rows`` (T, 88) at row times ``t`` against ``notes``; the
    planner's self-check calls this too, so its claims are the check's findings.
    ``finger_rows`` index into ``names`` (the fingers; the links for the body rule)."""
    frames = song_frames(notes, rate_hz)
    n = min(len(frames), len(t))
    frames = np.concatenate([t[:n], frames[n:]])  # the rows' own clock where they exist
    down = np.zeros((len(frames), down_rows.shape[1]), dtype=bool)
    down[:n] = down_rows[:n]  # frames without a row: nothing pressed
    prec, rec, f1 = frame_scores(expected_keys(notes, frames), down)
    wrong = key_episodes(down_rows & ~expected_keys(notes, t), t, finger_rows, names)
    missed, late = [], []
    for i, (note, o) in enumerate(zip(notes, note_outcomes(notes, frames, down))):
        if o.hit:
            if o.late:
                late.append(LateNote(float(note.onset_s), int(note.pitch),
                                     pitch_name(note.pitch), o.late_s, i))
            continue
        missed.append(MissedNote(float(note.onset_s), float(note.offset_s), int(note.pitch),
                                 pitch_name(note.pitch), o.fraction_down,
                                 _miss_reason(o, note.onset_s, float(t[-1])), i))
    return SongScore(float(f1.mean()), float(prec.mean()), float(rec.mean()), len(frames),
                     tuple(missed), tuple(late), tuple(wrong))


def _miss_reason(o, onset_s: float, t_last: float) -> str:
    if onset_s > t_last:
        return "after the trajectory's end"
    if not o.frames:
        return "no frame inside the note"
    if o.fraction_down == 0:
        return "key never down"
    return f"key down in {o.fraction_down:.0%} of its frames (< {NOTE_HIT_FRACTION:.0%})"

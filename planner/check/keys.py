"""The keys of a play replay: key-down episodes, key-bed hits, and against a song the
frame scores over the song's frames, note hits, lateness and wrong presses; judged block
by block (``PlayJudge``, ``SongScorer``: a file or a plan being written is judged as it
streams), or whole as one block (``play_replay``, ``score_song``, ``key_episodes``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.check.bodykeys import BodyKeys, bed_hits, body_names
from planner.check.criteria import (
    BODY_BED_DEPTH_M,
    KEY_BED_DEPTH_M,
    LOWEST_PITCH,
    N_KEYS,
    NOTE_HIT_FRACTION,
    KeyContacts,
    expected_keys,
    frame_scores,
    key_contacts,
    note_outcomes,
    pitch_name,
    song_frames,
)
from planner.check.episodes import EpisodeStream, PackedRows, Run
from planner.check.results import KeyBedHit, KeyEpisode, LateNote, MissedNote, PlayResult
from planner.hand.bodies import Body
from planner.hand.spec import FINGERS
from planner.trajfile import Trajectory

KEY_BED_TOL_M = 2e-6  # fingertip rounding (1e-6 rad over a ~0.4 m chain)


def frame_period(t_s: np.ndarray) -> float:
    """The rows' period: the median of their spacings (0.01 s for one row)."""
    return float(np.median(np.diff(t_s))) if len(t_s) > 1 else 0.01


def key_episodes(mask: np.ndarray, t_s: np.ndarray, finger: np.ndarray | None = None,
                 names: tuple[str, ...] = FINGERS) -> list[KeyEpisode]:
    """Contiguous runs of True in each key column of ``mask`` (T, 88), sorted by start;
    ``finger`` (T, 88): who holds each key down, an index into ``names`` (-1 none).

    An episode lasts from its first frame's time to the next frame's time
    (one median period past the last row at the end of the file). (``EpisodeStream``
    with one block.)
    """
    t_s = np.asarray(t_s, dtype=float)
    stream = EpisodeStream(np.shape(mask)[1])
    stream.add(mask, t_s, finger)
    return episodes_of(stream.finish(frame_period(t_s)), names)


def episodes_of(runs: list[Run], names: tuple[str, ...] = FINGERS) -> list[KeyEpisode]:
    """Runs of key columns as key episodes, their tags named by ``names``."""
    out = []
    for r in runs:
        p = r.key + LOWEST_PITCH
        out.append(KeyEpisode(p, pitch_name(p), r.start_s, r.end_s,
                              tuple(names[i] for i in r.tags)))
    return out


class PlayJudge:
    """The keys of a play's rows given block by block (``add``: the rows' times,
    fingertip points and ``BodyKeys``), then ``finish``: key-down episodes by the body
    rule (spec section 2: any body 5 mm below a key's top in its footprint; the point
    rule is its special case), the points' and the bodies' key-bed hits and, with
    ``notes``, the song's scores (``SongScorer``). ``play_replay`` is one block."""

    def __init__(self, notes, rate_hz: float, bodies: tuple[Body, ...]) -> None:
        self._bodies = bodies
        self._names, self._of_body = body_names(bodies)
        self._played = EpisodeStream(N_KEYS)
        self._bed = EpisodeStream(N_KEYS)
        self._hits: list[KeyBedHit] = []
        self._score = None if notes is None else SongScorer(notes, rate_hz, self._names)
        self._notes = notes
        self._rows = 0

    @property
    def names(self) -> tuple[str, ...]:
        """Who holds a key (``finger`` of ``add``'s result indexes it): ``body_names``."""
        return self._names

    def add(self, t: np.ndarray, tips: np.ndarray, bk: BodyKeys) -> KeyRows:
        """A block of rows; returns their keys down and fingertip contacts."""
        kc = key_contacts(tips)
        holder = np.where(bk.down, self._of_body[bk.body], -1).astype(np.int16)
        self._played.add(bk.down, t, holder)
        self._bed.add(bk.depth_m > BODY_BED_DEPTH_M, t, bk.body, bk.depth_m)
        deep = np.nan_to_num(kc.tip_depth, nan=-1.0) > KEY_BED_DEPTH_M + KEY_BED_TOL_M
        for r, f in zip(*np.nonzero(deep)):
            p = int(kc.tip_key[r, f]) + LOWEST_PITCH
            self._hits.append(KeyBedHit(float(t[r]), FINGERS[f], p, pitch_name(p),
                                        float(kc.tip_depth[r, f])))
        if self._score is not None:
            self._score.add(t, bk.down, holder)
        self._rows += len(t)
        return KeyRows(bk.down, holder, kc)

    def finish(self, t_s: np.ndarray) -> PlayResult:
        """The result; ``t_s``: every row's time."""
        period = frame_period(t_s)
        played = episodes_of(self._played.finish(period), self._names)
        body_bed = bed_hits(self._bed.finish(period), self._bodies)
        if self._score is None:
            return PlayResult(self._rows, tuple(played), tuple(self._hits),
                              body_bed_hits=body_bed)
        score, notes = self._score.finish(t_s), self._notes
        return PlayResult(self._rows, tuple(played), tuple(self._hits), f1=score.f1,
                          precision=score.precision, recall=score.recall, notes=len(notes),
                          notes_hit=len(notes) - len(score.missed), missed=score.missed,
                          wrong_presses=score.wrong_presses, late=score.late,
                          song_frames=score.song_frames, body_bed_hits=body_bed)


@dataclass(frozen=True)
class KeyRows:
    """A block's keys: ``down`` (T, 88) by the body rule, ``holder`` (T, 88) who holds
    each (an index into ``PlayJudge.names``, -1 none), and the fingertip points' contacts
    (``kc``: their depths load the fingers in the limit audit)."""

    down: np.ndarray
    holder: np.ndarray
    kc: KeyContacts


def play_replay(tr: Trajectory, tips: np.ndarray, bk: BodyKeys, bodies: tuple[Body, ...],
                notes) -> tuple[PlayResult, KeyRows, np.ndarray | None]:
    """Keys of every row; with ``notes``, the scores over the song's frames (criteria)."""
    judge = PlayJudge(notes, float(tr.metadata["rate_hz"]), bodies)
    rows = judge.add(tr.t_s, tips, bk)
    return (judge.finish(tr.t_s), rows,
            None if notes is None else expected_keys(notes, tr.t_s))


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
    planner's self-check scores so too, so its claims are the check's findings.
    ``finger_rows`` index into ``names`` (the fingers; the links for the body rule).
    (``SongScorer`` with one block.)"""
    scorer = SongScorer(notes, rate_hz, names)
    scorer.add(t, down_rows, finger_rows)
    return scorer.finish(t)


class SongScorer:
    """``score_song`` of rows given block by block (``add``, in order), then ``finish``:
    each block's frames scored as they come (the song's frames are the rows' clock), the
    wrong presses' episodes carried across blocks, the keys down kept as bits for the
    notes' outcomes (11 bytes a row)."""

    def __init__(self, notes, rate_hz: float, names: tuple[str, ...] = FINGERS) -> None:
        expected_keys(notes, np.zeros(0))  # (every pitch on the keyboard, or bad input)
        self._notes, self._names = notes, names
        self._onset = np.array([n.onset_s for n in notes], dtype=float)
        self._offset = np.array([n.offset_s for n in notes], dtype=float)
        self._frames = song_frames(notes, rate_hz)
        self._scores: list[tuple[np.ndarray, ...]] = []
        self._down = PackedRows(N_KEYS, len(self._frames))
        self._wrong = EpisodeStream(N_KEYS)
        self._rows = 0

    def _expected(self, t: np.ndarray) -> np.ndarray:
        """``expected_keys`` of rows ``t`` from the notes sounding within them."""
        near = np.flatnonzero((self._onset <= t[-1]) & (self._offset > t[0]))
        return expected_keys([self._notes[i] for i in near.tolist()], t)

    def add(self, t: np.ndarray, down: np.ndarray, finger: np.ndarray | None) -> None:
        if len(t) == 0:
            return
        exp = self._expected(t)
        n = max(0, min(len(t), len(self._frames) - self._rows))  # rows that are frames
        if n:
            self._scores.append(frame_scores(exp[:n], down[:n]))
            self._down.add(down[:n])
        self._wrong.add(down & ~exp, t, finger)
        self._rows += len(t)

    def finish(self, t: np.ndarray) -> SongScore:
        """The score; ``t``: every row's time (the notes' frames, the last row)."""
        notes, n = self._notes, min(len(self._frames), self._rows)
        frames = np.concatenate([t[:n], self._frames[n:]])  # the rows' own clock where they exist
        if len(frames) > n:  # frames without a row: nothing pressed
            rest = frames[n:]
            self._scores.append(frame_scores(expected_keys(notes, rest),
                                             np.zeros((len(rest), N_KEYS), dtype=bool)))
        prec, rec, f1 = (np.concatenate(s) for s in zip(*self._scores))
        wrong = episodes_of(self._wrong.finish(frame_period(t)), self._names)
        missed, late = [], []
        for i, (note, o) in enumerate(zip(notes, note_outcomes(notes, frames, self._down))):
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

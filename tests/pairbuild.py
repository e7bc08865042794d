"""Two-hand (version 3) files for the tests, made before a two-hand planner: each hand's
part planned alone by the one-hand planner, and the two plans written together by the one
two-hand writer (``planner.pairfile.PairWriter``) on a common clock (no test here).

A song of two parts (the left hand's notes, the right hand's) is written as one MIDI file
(every note in track 1: ``track`` 1 reads them all, with no part chosen), and each part as
a file of its own that its hand plans, from a rest pose of its own on the rail
(``REST_RAIL_M``: the one-hand planner's rest is at middle C, where two hands would
overlap; a test helper's choice, not the planner's). The plan that starts later (its ``song_start_s``:
the way in from rest) sets the common clock; the other hand waits at its first row (its
rest pose) before it, and the shorter plan holds its last row (rest) to the end.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from planner.hand.model import load_hand
from planner.music.midi import Note, load_song, write_notes_midi
from planner.pairfile import PairWriter
from planner.trajfile import song_start_s

RATE = 100.0
REST_RAIL_M = {"left": -0.35, "right": 0.35}  # each hand's rest on the rail (m), apart
SONG_TRACK = 1  # write_notes_midi's track of notes


def notes_of(pitches, start_s=0.5, step_s=0.4, length_s=0.3, channel=0) -> list[Note]:
    """One note per pitch, ``step_s`` apart from ``start_s``."""
    return [Note(int(p), start_s + i * step_s, start_s + i * step_s + length_s, 80, channel)
            for i, p in enumerate(pitches)]


@dataclass(frozen=True)
class PairFile:
    """A two-hand file written: its path, the song of both parts, and per prefix the
    song's indices of that hand's notes (the plan's ``by_hand`` claim)."""

    path: Path
    song: Path
    by_hand: dict[str, list[int]]
    t_s: np.ndarray
    q: tuple[np.ndarray, np.ndarray]


def _aligned(tr, start_s: float, n_rows: int) -> np.ndarray:
    """A plan's rows on the common clock: its first row held until its own start."""
    lead = round((start_s - song_start_s(tr.metadata)) * RATE)
    q = np.concatenate([np.repeat(tr.q[:1], lead, axis=0), tr.q])
    return np.concatenate([q, np.repeat(q[-1:], n_rows - len(q), axis=0)])


def plan_pair(tmp: Path, left: list[Note], right: list[Note], name: str = "pair",
              hands=("default-left", "default"), heard_left: list[Note] | None = None
              ) -> PairFile:
    """Plan ``left`` on the left hand and ``right`` on the right one, and write both as
    one two-hand file ``tmp/NAME.csv`` (the song: ``tmp/NAME.mid``, with ``heard_left``
    in place of the left part when given: a song other than the one planned)."""
    from planner.play.stream import Planner, plan_song

    models = tuple(load_hand(h) for h in hands)
    song_path = tmp / f"{name}.mid"
    write_notes_midi([*(heard_left or left), *right], song_path)
    song = load_song(song_path, track=SONG_TRACK)
    trs, index = [], {}
    for part, hand, side in ((left, models[0], "l"), (right, models[1], "r")):
        part_path = tmp / f"{name}-{side}.mid"
        write_notes_midi(part, part_path)
        part_song = load_song(part_path, track=SONG_TRACK)
        planner = Planner(hand)
        planner.rest_q = planner.rest_q.copy()
        planner.rest_q[hand.joint_names.index("rail")] = REST_RAIL_M[hand.side]
        trs.append(plan_song(part_song, hand, planner=planner).trajectory)
        heard = part_song.notes  # (in the song: the notes heard, in the part's order)
        if side == "l" and heard_left:
            heard = sorted(heard_left, key=lambda n: (n.onset_s, n.pitch))
        index[side] = [_song_index(song, n) for n in heard]
    start = max(song_start_s(tr.metadata) for tr in trs)
    n_rows = max(len(tr.t_s) + round((start - song_start_s(tr.metadata)) * RATE)
                 for tr in trs)
    q = tuple(_aligned(tr, start, n_rows) for tr in trs)
    t_s = np.arange(n_rows) / RATE
    left_out = sorted((index[s][x["note"]], x) for s, tr in zip("lr", trs)
                      for x in tr.end.get("left_out", []))
    by_hand = {p: sorted(set(index[s]) - {i for i, _ in left_out})
               for p, s in (("left.", "l"), ("right.", "r"))}
    path = tmp / f"{name}.csv"
    w = PairWriter(str(path), models, {
        "task": "play", "rate_hz": RATE, "song": song_path.name, "notes": len(song.notes),
        "track": SONG_TRACK, "channel": None, "transpose": False, "song_start_s": start})
    w.write_rows(t_s, q[0], q[1])
    w.close({"notes": len(song.notes), "played": len(song.notes) - len(left_out),
             "left_out": [{**x, "note": i} for i, x in left_out]}, by_hand)
    return PairFile(path, song_path, by_hand, t_s, q)


def _song_index(song, note: Note) -> int:
    """The index in ``song`` of a note of one part (its pitch and onset)."""
    for i, n in enumerate(song.notes):
        if n.pitch == note.pitch and abs(n.onset_s - note.onset_s) < 1e-3:  # (MIDI ticks)
            return i
    raise AssertionError(f"note {note} not in the song")


def write_unguarded(path: Path, pair_file: PairFile, q_left: np.ndarray, q_right: np.ndarray,
                    end: dict | None = None) -> Path:
    """``pair_file`` with other rows, written without the writer's guard (a file no
    planner may write: rows beyond a limit, hands that collide), its metadata and end
    marker as they were (``end``: keys changed in the end marker)."""
    from planner.trajfile import end_line, format_rows, header_line, parse_trajectory

    text = pair_file.path.read_text()
    tr = parse_trajectory(text)
    hands = tuple(load_hand(e["hand"]) for e in tr.metadata["hands"])
    q = np.concatenate([q_left, q_right], axis=1)
    qm = np.concatenate([h.motor_angles(x) for h, x in zip(hands, (q_left, q_right))], axis=1)
    rows = format_rows(pair_file.t_s, q, qm)
    info = {k: v for k, v in tr.end.items() if k not in ("end", "rows")} | (end or {})
    path.write_text(text.split("\n")[0] + "\n"
                    + header_line(tr.joint_names, tr.motor_names)
                    + rows.text + end_line(len(pair_file.t_s), info))
    return path

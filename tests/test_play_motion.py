"""The motion's tracks (planner/play/motion.py): a joint group's segments sampled at the
rows' times."""

from __future__ import annotations

import numpy as np

from planner.play.motion import _Track
from planner.play.profile import straight_move


def _reference(track: _Track, t_s: np.ndarray, q_start: np.ndarray) -> np.ndarray:
    """Row by row: before every segment, where the track starts; in a segment, its move;
    after it (until the next), where it ended."""
    out = []
    for t in t_s:
        running = [s for s in track.segments if s.t0_s <= t]
        if not running:
            out.append(q_start)
            continue
        s = running[-1]
        out.append(s.move.at(t - s.t0_s)[0] if t < s.t1_s else s.move.q_a + s.move.dq)
    return np.array(out).reshape(len(t_s), len(q_start))


def test_a_track_sampled_at_once_is_its_segments_row_by_row():
    rng = np.random.default_rng(1)
    for _ in range(200):
        q0 = rng.normal(size=3)
        track, t, q = _Track(q0.copy()), rng.uniform(0.0, 0.5), q0
        for _ in range(rng.integers(0, 8)):
            qb = q + 0.3 * rng.normal(size=3)
            t = track.add(t + rng.uniform(0.0, 0.3),
                          straight_move(q, qb, np.full(3, 3.0), np.full(3, 50.0),
                                        np.full(3, 2000.0)))
            q = qb
        t_s = np.sort(rng.uniform(0.0, 3.0, size=rng.integers(1, 300)))
        assert np.array_equal(track.at(t_s, q0), _reference(track, t_s, q0))
        # (and in pieces, as the rows are written: each piece from where the last ended)
        cut = len(t_s) // 2
        both = np.vstack([track.at(t_s[:cut], q0), track.at(t_s[cut:], q0)])
        assert np.array_equal(both, _reference(track, t_s, q0))

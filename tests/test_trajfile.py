"""Tests of planner.trajfile: the rows a writer hands its self-check are the file's."""

from __future__ import annotations

import numpy as np
import pytest

from planner.trajfile import TrajectoryWriter, read_trajectory


def test_values_as_written_are_the_files_bit_for_bit():
    """``as_written`` (the rows the writer hands its self-check) is what reading the
    file's 6-decimal text gives, bit for bit: on random values of every scale, halves
    and near-halves of the last decimal, negative zeros, and values a product's
    rounding could decide."""
    from planner.trajfile import as_written

    rng = np.random.default_rng(9)
    x = np.concatenate([rng.normal(0.0, 1.0, 20000), rng.uniform(-0.62, 0.7, 20000),
                        rng.uniform(-4000.0, 4000.0, 5000),
                        (np.arange(-3000, 3000) + 0.5) / 1e6,  # (exact halves)
                        (rng.integers(-10**7, 10**7, 5000) + 0.5) * 1e-6,  # (near halves)
                        [-4e-7, -0.0, 0.0, 4e-7, 1e12, -2.5e-6, np.inf, -np.inf]])
    got = as_written(x)
    want = np.array([float(f"{v:.6f}") for v in x.tolist()])
    assert np.array_equal(np.signbit(got), np.signbit(want))
    assert got.tobytes() == want.tobytes()


def test_the_rows_a_writer_returns_are_the_files(tmp_path, hand):
    """``write_rows`` hands back (to the self-check) the rows as the file holds them."""
    rng = np.random.default_rng(10)
    t = np.arange(300) * 10.0  # (rows 10 s apart: random ones within the speeds the
    # writer's guard holds)
    q = np.clip(hand.lower + (hand.upper - hand.lower) * rng.random((300, hand.n)),
                hand.lower, hand.upper)
    q[100:150] = q[99]  # (rows equal to the one before: formatted once)
    w = TrajectoryWriter(str(tmp_path / "r.csv"), {"task": "play", "hand": hand.name,
                         "urdf_sha256": hand.urdf_sha256,
                         "T_world_root": hand.T_world_root.tolist(), "rate_hz": 0.1},
                         hand)
    got = np.concatenate([w.write_rows(t[:120], q[:120], hand.motor_angles(q[:120])),
                          w.write_rows(t[120:], q[120:], hand.motor_angles(q[120:]))])
    w.close()
    tr = read_trajectory(str(tmp_path / "r.csv"))
    assert got.tobytes() == np.column_stack([tr.t_s, tr.q, tr.q_motor]).tobytes()


def test_rows_formatted_apart_and_appended_joined_are_the_same_file(hand):
    """``joined_rows``: rows formatted in parts (a live session's rows formatted ahead of
    its first plan, and that plan's own) and appended as one give the file, and the
    rows handed back, of the parts appended one by one; the guard judges the speed across
    a seam as it judges it between two appends (a jump there is refused either way)."""
    from planner.errors import SolverError
    from planner.trajfile import format_rows, joined_rows

    rng = np.random.default_rng(11)
    t = np.arange(40) * 10.0
    q = hand.lower + (hand.upper - hand.lower) * rng.random((40, hand.n))
    q[10:14] = q[9]  # (repeats: formatted once within a part)
    cuts = [(0, 1), (1, 2), (2, 12), (12, 13), (13, 40)]
    meta = {"task": "catch", "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
            "T_world_root": hand.T_world_root.tolist(), "rate_hz": 0.1}

    def parts(Q):
        return [format_rows(t[a:b], Q[a:b], hand.motor_angles(Q[a:b])) for a, b in cuts]

    apart, joined = TrajectoryWriter(None, meta, hand), TrajectoryWriter(None, meta, hand)
    got_apart = np.concatenate([apart.append(p) for p in parts(q)])
    got_joined = joined.append(joined_rows(parts(q)))
    apart.close()
    joined.close()
    assert joined.text == apart.text and got_joined.tobytes() == got_apart.tobytes()
    fast = np.tile(q[0], (40, 1))  # at rest but for one joint's jump across the seam
    j = int(np.argmax(hand.upper - hand.lower))  # between rows 11 and 12 (10 ms apart)
    fast[:12, j], fast[12:, j] = hand.lower[j], hand.upper[j]
    fast = hand.apply_couplings(fast)
    t = t / 1000.0
    for write, kept in ((lambda w: [w.append(p) for p in parts(fast)], 12),
                        (lambda w: w.append(joined_rows(parts(fast))), 0)):
        w = TrajectoryWriter(None, meta, hand)
        with pytest.raises(SolverError, match="speed"):
            write(w)
        assert w.rows == kept  # (the parts before the seam appended apart; none joined)

"""Tests of planner.trajfile: the rows a writer hands its self-check are the file's."""

from __future__ import annotations

import numpy as np

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

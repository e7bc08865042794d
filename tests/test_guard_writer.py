"""The hardware guard sits in the trajectory writer (issue 33, item 3): a row out of the
hand's joint limits is refused on every path a plan's rows take, and never reaches the
file, the pipe or the plan kept in memory.

The paths: ``plan_song`` into a file and in memory (``PlayPlan.text``, what
``PlayPlan.write`` writes: a refused plan has none), the one-shot catch
(``catch.plan.write_plan``), the live catch (``CatchSession``), and the writer itself
on a pipe and in memory. The bad row is put in by wrapping the stage that samples the
rows (``Motion.rows``, ``LiveMotion.rows``), as a planner bug would make it."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from planner.errors import SolverError
from planner.trajfile import TrajectoryWriter, read_trajectory

ROOT = Path(__file__).resolve().parents[1]
SONG = ROOT / "songs" / "twinkle.mid"
JOINT = "index_pip"  # the joint pushed past its upper limit


def _over(hand, q: np.ndarray, row: int = -1) -> np.ndarray:
    """``q`` with ``JOINT`` 1 mrad past its upper limit in ``row``."""
    q = np.array(q, dtype=float, copy=True)
    j = hand.index[JOINT]
    q[row, j] = hand.upper[j] + 1e-3
    return q


def _breaking(monkeypatch, cls, hand) -> None:
    """``cls.rows`` returning its last row out of the limits, from its second call on."""
    real = cls.rows
    calls = {"n": 0}

    def rows(self, *a, **k):
        q = real(self, *a, **k)
        calls["n"] += 1
        return _over(hand, q) if calls["n"] >= 2 and len(q) else q

    monkeypatch.setattr(cls, "rows", rows)


def _no_row_over(path: Path, hand) -> None:
    """What reached the file: no end marker, every row within the limits."""
    text = path.read_text(encoding="utf-8")
    assert '"end": true' not in text
    tr = read_trajectory(str(path), allow_incomplete=True) if text.count("\n") > 3 else None
    if tr is not None:
        assert (tr.q <= hand.upper + 1e-6).all() and (tr.q >= hand.lower - 1e-6).all()


def test_play_into_a_file_and_in_memory_refuses_the_row(hand, tmp_path, monkeypatch):
    import planner
    from planner.play.motion import Motion

    song = planner.load_song(str(SONG))
    pl = planner.Planner(hand)
    _breaking(monkeypatch, Motion, hand)
    out = tmp_path / "t.csv"
    with pytest.raises(SolverError, match=f"{JOINT} = .* outside"):
        planner.plan_song(song, hand, str(out), planner=pl)
    _no_row_over(out, hand)
    # in memory: no PlayPlan comes back, so there is no text to read or write
    _breaking(monkeypatch, Motion, hand)
    with pytest.raises(SolverError, match=f"{JOINT} = .* outside"):
        planner.plan_song(song, hand, None, planner=pl)


def test_the_one_shot_catch_refuses_the_row(tmp_path):
    from planner.catch import plan_catch, write_plan

    res = plan_catch(30.0, 1.5, 0.0, "default", str(tmp_path / "ok.csv"))
    plan = res.plan
    hand = plan.base_hand
    q = _over(hand, plan.rows.q, len(plan.rows.q) // 2)
    bad = dataclasses.replace(plan, rows=dataclasses.replace(plan.rows, q=q))
    out = tmp_path / "bad.csv"
    with pytest.raises(SolverError, match=f"{JOINT} = .* outside"):
        write_plan(bad, str(out))
    _no_row_over(out, hand)


def test_the_live_catch_refuses_the_row(tmp_path, monkeypatch):
    from planner.balls import get_ball
    from planner.catch import get_planner
    from planner.catch.flight.path import predict_throw
    from planner.catch.live.motion import LiveMotion
    from planner.catch.live.session import CatchSession

    pl = get_planner("default")
    ball = get_ball("tennis")
    fl = predict_throw(30.0, 1.5, 0.0, ball, False)
    _breaking(monkeypatch, LiveMotion, pl.base_hand)
    out = tmp_path / "live.csv"
    s = CatchSession(1.5, 0.0, ball=ball, planner=pl, out_path=str(out))
    with pytest.raises(SolverError, match=f"{JOINT} = .* outside"):
        for t in np.arange(1, 60) / 100.0:
            s.observe(float(t), fl.position(np.array([t]))[0])
        s.finish()
    s.abort()
    _no_row_over(out, pl.base_hand)


def _meta(hand) -> dict:
    return {"task": "play", "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
            "T_world_root": hand.T_world_root.tolist(), "rate_hz": 100.0}


def test_the_writer_refuses_the_row_on_a_pipe_and_in_memory(hand, capsys):
    t = np.arange(5) / 100.0
    q = np.tile(0.5 * (hand.lower + hand.upper), (5, 1))
    w = TrajectoryWriter("-", _meta(hand), hand)
    w.write_rows(t[:2], q[:2])
    with pytest.raises(SolverError, match=f"{JOINT} = .* outside"):
        w.write_rows(t[2:], _over(hand, q[2:]))
    w.abort()
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 4  # metadata, header and the two good rows: nothing after
    m = TrajectoryWriter(None, _meta(hand), hand)
    with pytest.raises(SolverError):
        m.write_rows(t, _over(hand, q, 0))
    assert m.rows == 0
    # a speed over the limit from the row written before is refused too
    m.write_rows(t[:1], q[:1])
    step = q[1].copy()
    j = hand.index[JOINT]
    step[j] += 1.5 * hand.velocity[j] * 0.01
    with pytest.raises(SolverError, match=f"{JOINT} speed"):
        m.write_rows(t[1:2], step[None])
    assert m.rows == 1

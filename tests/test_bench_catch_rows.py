"""bench/catch_rows.py: a catch's replay beside the check's ball-on-palm model, row by row
(the tool that found where the check's landing differs from the replay's: 2026-12-07
catch-drop history page)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from planner.catch.plan.api import plan_throw, write_plan
from planner.trajfile import read_trajectory

_PATH = Path(__file__).resolve().parents[1] / "bench" / "catch_rows.py"
_SPEC = importlib.util.spec_from_file_location("catch_rows", _PATH)
cr = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(cr)


def _cols(line: str) -> list[float]:
    """A table row's numbers: t, the replay's x y z, the model's x y z (mm)."""
    t, sim, mod = line.split("|")[:3]
    return [float(t)] + [float(x) for x in sim.split()] + [float(x) for x in mod.split()]


def test_a_held_throw_rows_start_at_the_landing_where_replay_and_model_agree(pl, tmp_path):
    """30 deg / 1.5 m (held in the replay, its ball barely leaves the palm: 1.0 mm): one
    table row per file row from the landing on; on the first row after the landing the
    replay's ball and the model's are within 2 mm of each other in the palm's plane
    (measured 0.3 mm) and the replay's ball is in the palm's pad, within its give (the
    model has no pad: measured 2.2 mm deep; on the rigid palm before the pad, 0.3 mm in
    all three), and the fingertips are listed by name."""
    pytest.importorskip("mujoco")
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    assert p.feasible, p.reasons
    out = tmp_path / "c.json"
    write_plan(p, str(out))
    lines = cr.rows_table(str(out), None)
    rows = [ln for ln in lines if ln[:1].isdigit()]
    first = _cols(rows[0])
    t_land = float(lines[0].split("landing ")[1].split(" s")[0])
    assert 0.0 < first[0] - t_land <= 0.01 + 1e-9
    t_s = read_trajectory(str(out)).t_s
    assert len(rows) == int((t_s > t_land).sum())
    assert max(abs(a - b) for a, b in zip(first[1:3], first[4:6])) <= 2.0
    assert 0.0 < -first[3] <= 1000 * pl.hand.pad_give_m and abs(first[6]) <= 2.0
    assert sum(ln.lstrip().startswith("thumb") for ln in lines) == 2


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert cr.main([str(tmp_path / "none.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("catch_rows: ")

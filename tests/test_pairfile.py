"""The two-hand file (version 3, ``planner.pairfile``): written by the one trajectory
writer, read back by ``read_plan`` as a typed pair plan, every mismatch one stderr line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from planner.errors import InputError, SolverError
from planner.hand.model import load_hand
from planner.hand.pair import HandPair, load_pair, pair_urdf_text
from planner.hand.urdf import urdf_sha256
from planner.pairfile import PairPlan, PairWriter, write_pair_file
from planner.planfile import PlanFile, read_plan
from planner.trajfile import TrajectoryWriter, read_trajectory
from tests.hardening import run_cli

RATE = 0.1  # (rows 10 s apart: random rows within the speeds the guard holds)


@pytest.fixture(scope="module")
def pair() -> HandPair:
    return load_pair("default-left,default")


def _rows(pair: HandPair, n: int, seed: int):
    rng = np.random.default_rng(seed)
    return tuple(h.apply_couplings(h.lower + (h.upper - h.lower) * rng.random((n, h.n)))
                 for h in pair.hands)


def _meta(**extra):
    return {"task": "play", "rate_hz": RATE, "song": "x.mid", "notes": 5, **extra}


def _write(path, pair, n=40, seed=1, by_hand=None, **meta):
    q = _rows(pair, n, seed)
    write_pair_file(str(path), pair, _meta(**meta), np.arange(n) / RATE, q,
                    end_info={"notes": 5, "played": 4},
                    by_hand=by_hand or {"left.": [0, 2], "right.": [1, 4]})
    return q


def test_a_pair_file_reads_back_as_each_hands_plan(tmp_path, pair) -> None:
    """Round trip: each hand's rows, motors, hash and mount come back as its own plan;
    the same rows written in two chunks, or in memory, are the same bytes."""
    n = 40
    q = _write(tmp_path / "a.csv", pair, n)
    plan = read_plan(str(tmp_path / "a.csv"))
    assert isinstance(plan, PairPlan)
    assert plan.pair.name == "default-left+default" and plan.task == "play"
    assert plan.metadata["version"] == 3 and plan.metadata["hand"] == plan.pair.name
    assert plan.metadata["urdf_sha256"] == urdf_sha256(pair_urdf_text(pair.hands))
    assert plan.by_hand == {"left.": (0, 2), "right.": (1, 4)}
    assert plan.trajectory.joint_names[0] == "left.rail"
    assert plan.trajectory.motor_names[-1].startswith("right.")
    for part, h, qh in zip(plan.hands, pair.hands, q):
        assert isinstance(part, PlanFile) and part.hand is h
        assert part.trajectory.joint_names == tuple(h.joint_names)
        assert np.abs(part.trajectory.q - qh).max() <= 5e-7
        assert np.abs(part.trajectory.q_motor - h.motor_angles(qh)).max() <= 5e-7
        assert np.array_equal(part.T_world_root, h.T_world_root)
        assert part.metadata["hand"] == h.name and part.metadata["urdf_sha256"] == h.urdf_sha256
        assert part.trajectory.complete and len(part.trajectory.t_s) == n
    text = (tmp_path / "a.csv").read_text()
    w = PairWriter(None, ("default-left", "default"), _meta())
    got = np.concatenate([w.write_rows(np.arange(15) / RATE, q[0][:15], q[1][:15]),
                          w.write_rows(np.arange(15, n) / RATE, q[0][15:], q[1][15:])])
    w.close({"notes": 5, "played": 4}, {"right.": [4, 1], "left.": [2, 0]})
    assert w.text == text
    tr = read_trajectory(str(tmp_path / "a.csv"))
    assert got.tobytes() == np.column_stack([tr.t_s, tr.q, tr.q_motor]).tobytes()
    # the metadata: a one-hand file's keys in its order, then the hands
    meta = json.loads(text.split("\n")[0][2:])
    assert list(meta)[:7] == ["format", "version", "task", "hand", "urdf_sha256",
                              "T_world_root", "rate_hz"]
    assert [e["prefix"] for e in meta["hands"]] == ["left.", "right."]
    assert [e["hand"] for e in meta["hands"]] == ["default-left", "default"]


def test_a_one_hand_file_stays_version_2(tmp_path, hand) -> None:
    """The one-hand writer and reader are untouched: version 2, no prefix, a PlanFile."""
    q = np.repeat(hand.apply_couplings(hand.lower + 0.5 * (hand.upper - hand.lower))[None],
                  3, axis=0)
    w = TrajectoryWriter(str(tmp_path / "one.csv"), {
        "task": "play", "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
        "T_world_root": hand.T_world_root.tolist(), "rate_hz": 100.0}, hand)
    w.write_rows(np.arange(3) / 100.0, q)
    w.close()
    text = (tmp_path / "one.csv").read_text()
    assert text.startswith('# {"format": "hand-trajectory", "version": 2,')
    assert text.split("\n")[1].startswith("t,rail,")
    assert isinstance(read_plan(str(tmp_path / "one.csv")), PlanFile)


def test_the_guard_judges_each_hand_by_its_own_limits(pair) -> None:
    """A row outside a hand's limits is refused, named by its prefixed joint."""
    q = _rows(pair, 2, 3)
    q[1][1, 0] = pair.hands[1].upper[0] + 0.01
    w = PairWriter(None, pair, _meta())
    with pytest.raises(SolverError, match=r"right\.rail = "):
        w.write_rows(np.arange(2) / RATE, q[0], q[1])
    with pytest.raises(InputError, match="a left hand then a right hand"):
        PairWriter(None, ("default", "default-left"), _meta())


def _edit(path, meta=None, header=None, end=None) -> str:
    """``path`` with its metadata, header or end marker changed by a function."""
    lines = path.read_text().split("\n")
    if meta is not None:
        m = json.loads(lines[0][2:])
        meta(m)
        lines[0] = "# " + json.dumps(m)
    if header is not None:
        lines[1] = header(lines[1])
    if end is not None:
        e = json.loads(lines[-2][2:])
        end(e)
        lines[-2] = "# " + json.dumps(e)
    out = path.with_name("edited.csv")
    out.write_text("\n".join(lines))
    return str(out)


def _set(entry: int, key: str, value):
    def f(m):
        m["hands"][entry][key] = value
    return f


BAD = {
    "missing hands": ({"meta": lambda m: m.pop("hands")}, "must have 'hands'"),
    "one hand": ({"meta": lambda m: m["hands"].pop()}, "must have 'hands'"),
    "a key missing": ({"meta": lambda m: m["hands"][0].pop("urdf_sha256")},
                      r"hands\[0\] lacks 'urdf_sha256'"),
    "wrong prefix": ({"meta": _set(0, "prefix", "l.")}, "has prefix 'l.'"),
    "hands swapped": ({"meta": lambda m: m["hands"].reverse()},
                      "a left hand then a right hand"),
    "unknown hand": ({"meta": _set(1, "hand", "no-such-hand")},
                     "cannot rebuild hand 'no-such-hand'"),
    "wrong hand hash": ({"meta": _set(1, "urdf_sha256", "0" * 64)},
                        "urdf_sha256 mismatch for 'right.'"),
    "wrong pair hash": ({"meta": lambda m: m.update(urdf_sha256="1" * 64)},
                        "urdf_sha256 mismatch: .* the pair"),
    "wrong pair name": ({"meta": lambda m: m.update(hand="default")}, "its hands make"),
    "a mount moved": ({"meta": _set(0, "T_world_root", [[1, 0, 0, 0.1], [0, 1, 0, -0.4],
                                                         [0, 0, 1, 0.05], [0, 0, 0, 1]])},
                      r"\(left\.\): T_world_root differs"),
    "pair not at the keyboard": ({"meta": lambda m: m["T_world_root"][0].__setitem__(3, 1)},
                                 "T_world_root differs"),
    "a catch": ({"meta": lambda m: m.update(task="catch")}, "is a play"),
    "columns unprefixed": ({"header": lambda h: h.replace("left.rail", "rail", 1)},
                           r"joint columns do not match .*missing left\.rail; extra rail"),
    "columns swapped": ({"header": lambda h: h.replace("left.reach", "X").replace(
        "left.rail", "left.reach").replace("X", "left.rail")}, "order differs"),
    "by_hand of one hand": ({"end": lambda e: e["by_hand"].pop("left.")},
                            "by_hand must name the notes of each hand"),
    "by_hand not indices": ({"end": lambda e: e["by_hand"].update({"left.": [0, "2"]})},
                            r"by_hand\['left.'\] must be a list"),
    "a note in both hands": ({"end": lambda e: e["by_hand"].update({"left.": [0, 1]})},
                             "gives note 1 twice"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_every_mismatch_is_one_line_and_exit_2(tmp_path, pair, capsys, case) -> None:
    """Each defect of a two-hand file is an InputError naming the file; at the command
    line one stderr line and exit 2."""
    _write(tmp_path / "a.csv", pair, 4)
    edit, message = BAD[case]
    path = _edit(tmp_path / "a.csv", **edit)
    with pytest.raises(InputError, match=message):
        read_plan(path)
    for cmd in ("check", "simulate"):
        rc, _out, err = run_cli(capsys, cmd, path)
        assert rc == 2 and err.count("\n") == 1 and path in err, (cmd, err)


def test_a_pair_file_names_its_hands_itself(tmp_path, pair) -> None:
    _write(tmp_path / "a.csv", pair, 4)
    with pytest.raises(InputError, match="names its hands itself"):
        read_plan(str(tmp_path / "a.csv"), hand_override="default")


def test_a_pair_of_other_hands(tmp_path) -> None:
    """Any left hand with any right hand: each rebuilt by its own name."""
    pair = HandPair((load_hand("default-left"), load_hand("mk5")))
    _write(tmp_path / "m.csv", pair, 4)
    plan = read_plan(str(tmp_path / "m.csv"))
    assert [p.hand.name for p in plan.hands] == ["default-left", "mk5"]
    assert plan.trajectory.joint_names[pair.hands[0].n] == "right.rail"

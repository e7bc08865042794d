"""Two hands as one robot (``planner.hand.pair``): the URDF a two-hand file will name,
its columns, and ``hand --hands LEFT,RIGHT --urdf``."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from planner.cli import main
from planner.errors import InputError
from planner.hand.model import load_hand
from planner.hand.pair import column_names, pair_urdf_text, rpy_of
from planner.hand.spec import rpy_matrix
from planner.hand.urdf import urdf_sha256


@pytest.fixture(scope="module")
def hands():
    return load_hand("default-left"), load_hand("default")


def test_the_pair_is_both_hands_each_as_it_is(hands) -> None:
    """Every frame of the pair's URDF (root: the keyboard frame) is its hand's own frame,
    prefixed, where that hand's model puts it: for random joints of both hands."""
    text = pair_urdf_text(hands)
    assert text == pair_urdf_text(hands)  # (the same bytes every time)
    m = pin.buildModelFromXML(text)
    d = m.createData()
    joints, motors = column_names(hands)
    assert m.nq == len(joints) == 2 * hands[0].n
    assert joints[0] == "left.rail" and joints[-1] == "right.pinky_dip"
    assert motors[0] == "left.rail" and len(motors) == 2 * hands[1].n_motor
    rng = np.random.default_rng(2)
    for _ in range(5):
        qs = [h.apply_couplings(rng.uniform(h.lower, h.upper)) for h in hands]
        qp = np.zeros(m.nq)
        for name, v in zip(joints, np.concatenate(qs)):
            qp[m.idx_qs[m.getJointId(name)]] = v
        pin.framesForwardKinematics(m, d, qp)
        for h, q in zip(hands, qs):
            for f in (*h.tip_frames, "palm_center", "carriage"):
                got = d.oMf[m.getFrameId(f"{h.side}.{f}")].homogeneous
                assert np.abs(got - h.frame_pose(q, f)).max() < 1e-12
    # couplings as mimics of the prefixed joints; every collision named by its hand
    assert '<mimic joint="left.index_pip" multiplier="0.667"' in text
    assert '<collision name="index_pad"' not in text
    assert text.count('<collision name="left.index_pad"') == 1


def test_rpy_of_inverts_rpy_matrix() -> None:
    rng = np.random.default_rng(4)
    for rpy in rng.uniform([-3, -1.5, -3], [3, 1.5, 3], (50, 3)):
        R = rpy_matrix(tuple(rpy))
        assert np.abs(rpy_matrix(rpy_of(R)) - R).max() < 1e-12


def test_a_pair_is_a_left_hand_then_a_right_hand(hands) -> None:
    with pytest.raises(InputError, match="a left hand then a right hand"):
        pair_urdf_text(hands[::-1])
    with pytest.raises(InputError, match="a left hand then a right hand"):
        column_names((hands[1], hands[1]))


def test_hand_hands_urdf(hands, tmp_path, capsys) -> None:
    out = tmp_path / "pair.urdf"
    assert main(["hand", "--hands", "default-left,default", "--urdf", str(out), "--json"]) == 0
    assert out.read_text() == pair_urdf_text(hands)
    assert urdf_sha256(out.read_text()) in capsys.readouterr().out
    assert main(["hand", "--hands", "default,default-left", "--urdf", str(tmp_path / "x")]) == 2
    assert not (tmp_path / "x").exists()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "left hand then a right hand" in err

"""Motor torques as a matrix of joint torques: ``hand.motor_torques(q, tau) == M @ tau``
(the hand's transmissions are linear in the joint torques at a given q). One definition,
used by ``check``'s ball loads and by the catch planner's QPs."""

from __future__ import annotations

import numpy as np

from planner.hand.model import HandModel

_LINEAR_M: dict[str, np.ndarray] = {}


def motor_torque_matrix(hand: HandModel, q: np.ndarray) -> np.ndarray:
    """(n_motor, n): ``hand.motor_torques(q, tau) == M @ tau``, built column by column
    from unit joint torques. When every coupling and transmission is linear the map
    does not depend on q and is built once per hand (cached by URDF hash)."""
    linear = (all(c.kind == "linear" for c in hand.couplings)
              and all(getattr(a, "mk5", None) is None for a in hand.actuators))
    if linear and hand.urdf_sha256 in _LINEAR_M:
        return _LINEAR_M[hand.urdf_sha256]
    M = np.stack([hand.motor_torques(q, e) for e in np.eye(hand.n)], axis=1)
    if linear:
        M.setflags(write=False)
        _LINEAR_M[hand.urdf_sha256] = M
    return M

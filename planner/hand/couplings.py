"""The hand's couplings in index form: which joints follow which, and the maps they make.

A coupling sets a dependent joint from its source, ``q[dep] = f(q[src])``: a linear law
(``LinearCoupling``: a ratio and an offset, also a URDF mimic) or the Mk5's four-bar
(``Mk5Coupling``: the seed's tables). ``HandModel`` builds one ``CouplingMap`` at set-up
and answers through it (``apply_couplings``, ``coupling_errors``, ``coupling_jacobian``,
``dq_dindependent``); the IK and the check read its laws (``HandModel.couplings``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.hand.spec import LinearCoupling, Mk5Coupling


@dataclass(frozen=True)
class CouplingLaw:
    """``q[dep] = f(q[src])`` with derivative ``df``; index form of a coupling."""

    dep: int
    src: int
    kind: str
    ratio: float = 0.0
    offset: float = 0.0
    mk5: object = None  # Mk5FingerParams for the nonlinear law

    def value(self, q_src):
        if self.kind == "linear":
            return self.ratio * q_src + self.offset
        from planner.hand import mk5

        return mk5.q2_of_q1(self.mk5, q_src) - q_src

    def slope(self, q_src):
        if self.kind == "linear":
            return self.ratio + 0.0 * q_src
        from planner.hand import mk5

        return mk5.dq2_dq1(self.mk5, q_src) - 1.0


class CouplingMap:
    """The coupling laws of a hand with ``n`` joints, and the joints they leave free.

    ``laws``: in the hand file's order; ``independent``: the joints no law drives (the
    hand's degrees of freedom), ``dependent``: the others, both sorted."""

    def __init__(self, spec_couplings, index: dict[str, int], n: int) -> None:
        laws = []
        for c in spec_couplings:
            if isinstance(c, LinearCoupling):
                laws.append(CouplingLaw(index[c.joint], index[c.source], "linear",
                                        c.ratio, c.offset))
            elif isinstance(c, Mk5Coupling):
                from planner.hand.mk5_tables import MK5_TABLES  # (an Mk5 hand's only: not
                # imported for the others)

                laws.append(CouplingLaw(index[c.joint], index[c.source], "mk5",
                                        mk5=MK5_TABLES[c.table][c.finger]))
        self.n = n
        self.laws: tuple[CouplingLaw, ...] = tuple(laws)
        dep = {c.dep for c in laws}
        # the linear laws at once (none of their sources is a dependent joint: no chain),
        # then the others in order
        lin = [c for c in laws if c.kind == "linear"]
        chained = any(c.src in dep for c in laws)
        self._lin = None if chained or not lin else (
            np.array([c.dep for c in lin]), np.array([c.src for c in lin]),
            np.array([c.ratio for c in lin]), np.array([c.offset for c in lin]))
        self._other_laws = tuple(c for c in laws if c.kind != "linear") if self._lin else laws
        self.independent = np.array([i for i in range(n) if i not in dep])
        self.dependent = np.array(sorted(dep), dtype=int)
        # every law linear: each one's slope is its ratio wherever its source is finite
        self.all_linear = all(c.kind == "linear" for c in laws)
        self.sources = np.array([c.src for c in laws], dtype=int)

    def apply(self, q: np.ndarray) -> np.ndarray:
        """A copy of ``q`` with every dependent joint set from its source."""
        q = np.array(q, dtype=float)
        if self._lin is not None:
            dep, src, ratio, offset = self._lin
            q[..., dep] = ratio * q[..., src] + offset
        for c in self._other_laws:
            q[..., c.dep] = c.value(q[..., c.src])
        return q

    def errors(self, q: np.ndarray) -> np.ndarray:
        """``q[dep] - f(q[src])`` for every law (rad); shape (..., n_laws)."""
        q = np.asarray(q, dtype=float)
        return np.stack([q[..., c.dep] - c.value(q[..., c.src]) for c in self.laws], axis=-1) \
            if self.laws else np.zeros(q.shape[:-1] + (0,))

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """d(errors)/dq, shape (n_laws, n)."""
        G = np.zeros((len(self.laws), self.n))
        for k, c in enumerate(self.laws):
            G[k, c.dep] = 1.0
            G[k, c.src] = -float(c.slope(q[c.src]))
        return G

    def dq_dindependent(self, q: np.ndarray) -> np.ndarray:
        """Map from independent joint velocities to all joint velocities, (n, n_independent)."""
        S = np.zeros((self.n, len(self.independent)))
        col = {int(j): k for k, j in enumerate(self.independent)}
        for j, k in col.items():
            S[j, k] = 1.0
        for c in self.laws:
            S[c.dep, col[c.src]] = float(c.slope(q[c.src]))
        return S

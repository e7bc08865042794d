"""A cheap sufficient test that a finger's move across keeps every tendon motor within
its share of capacity, so that ``TendonLoad.time_scale`` is exactly 1 without its samples.

``TendonLoad`` bounds a move's motor torques at each of its samples by
``|S| + |K| A + |C| W`` (``planner.play.tendonload``'s docstring: ``S`` the static torques,
``K = M H(q) q_s`` and ``C = M (H(q) q_ss + c(q, q_s))`` the inertial ones along the path,
``M`` the motor matrix, ``H`` the mass matrix, ``c`` the speeds' torques, ``A`` the
profile's peak acceleration, ``W <= V^2`` its peak speed squared); a move is slowed only
where that passes a motor's share. For a move of one finger's joints with no key pushing
back, this module bounds the same sum over a box of the finger's joints at once:

* the motor matrix is the same for every pose (linear couplings and transmissions:
  ``motor_torque_matrix``);
* a finger is a serial chain of revolute joints hanging from still links; the distance
  from joint ``k``'s origin (on its axis) to body ``b``'s centre of mass is at most
  ``d(k, b)``: the lengths of the joint offsets between them plus the body's lever
  (triangle inequality; each offset a constant length whatever the angles);
* gravity: ``|g_j| <= |g| sum_{b >= j} m_b d(j, b)`` on every joint of every finger,
  whatever the poses (``static_nm``, once per hand);
* ``|(M H)_mk|`` and the coefficients ``|(M c)_m,kl|`` of ``v_k v_l`` bounded over the
  box (``box_gain``): sampled on a grid, Taylor's theorem between the samples with the
  exact first derivatives there (Pinocchio's RNEA derivatives) and a bound on the
  second ones from the chain's constants (a vector turned by the joints has each
  derivative at most its length).

Then ``|S| + |K| A + |C| W <= static + G_H (|q_s| A + |q_ss| V^2) + G_c (|q_s| |q_s|) V^2``,
``q_s`` the couplings' tangent and ``q_ss`` zero but for the central differences'
rounding (both bounded with it). Where that is within every motor's share with
``PROOF_MARGIN`` to spare, every line of ``scale_for`` has room of at least 1: the move
is not slowed, the very answer of the full computation. Elsewhere the full computation
runs.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from planner.hand.model import HandModel

PROOF_MARGIN = 1e-6  # the share of a motor's capacity kept for the floats: the full
# computation's sums of a few dozen products of torques of at most a few N m, each rounded
# within 1e-16 relative, differ from the exact ones by far less than 1e-6 of the 0.1-1 N m
# capacities of the hands' tendon motors
GRID_POINTS = 4  # a box (a finger's high poses in one posture) sampled at 4 points a joint
# for the mass matrix's and speed torques' bounds, whose Taylor rest shrinks as the spacing
# squared: on 1,600 random moves across of the default hand, 3 points left one in eight of
# the middle and ring fingers' unproved, 4 and 5 only the moves of an ulp (identical high
# poses); 4^3 poses a finger, fifteen RNEA derivatives each, about 30 ms once per finger
# and posture, when first asked
ROUNDING_FACTOR = 64.0  # the central differences' rounding bound, in units of the largest
# joint value's ulp: each of the three points of a difference is rounded a few times (the
# path's point, the couplings' product and sum), 64 bounds their sum with room
BOX_ROOM_RAD = 1e-9  # a box is widened by this each side: a move's end worked out as the
# start plus the difference (``Moves.finger_scale``) may round an ulp or two past the pose
GRID_CELLS = 4  # a finger's hull of high poses over every posture (the box a move across
# from another posture's entry lies in) is cut into 4 cells a joint for its gains: over the
# whole hull the bound is 1.2-3.7 times a motor's share where the full computation finds
# 0.35-0.45 (two corpus pieces' 120 moves across postures, none proved); over 4^3 cells
# every one of them is proved. 64 cells at about 10 ms each: made by ``make_atlas`` only
CURVATURE = 64.0  # the second derivatives' bound of a term of the mass matrix or of the
# speed torques, in units of m d(j, b) d(k, b) (or of ||I_b||): products of at most five
# turned vectors whose r-th derivatives are at most 2^r times their length (32 the largest
# such sum, module docstring)


@dataclass(frozen=True)
class FingerChain:
    """The constants of one finger's serial chain of revolute joints (our joint order
    ``cols``; ``v_index`` Pinocchio's velocity indices): ``dist[k, b]`` bounds the
    distance from joint ``k``'s origin to body ``b``'s centre of mass; ``mass_kg``,
    ``inertia_norm`` (the rotational inertia's largest eigenvalue, kg m^2)."""

    cols: np.ndarray
    v_index: tuple[int, ...]
    dist: np.ndarray
    mass_kg: np.ndarray
    inertia_norm: np.ndarray

    def gravity_bound_nm(self, g: float) -> np.ndarray:
        """The largest gravity torque on each joint of the chain, any pose."""
        n = len(self.cols)
        return np.array([g * sum(self.mass_kg[b] * self.dist[j, b] for b in range(j, n))
                         for j in range(n)])

    def curvature(self, j: int, k: int) -> float:
        """A bound on the second derivatives of a term ``j, k`` of the chain's mass matrix
        or of its speed torques (``CURVATURE``)."""
        n = len(self.cols)
        return sum(CURVATURE * (self.mass_kg[b] * self.dist[j, b] * self.dist[k, b]
                                + self.inertia_norm[b]) for b in range(max(j, k), n))


def finger_chain(hand: HandModel, model, finger: str) -> FingerChain | None:
    """The finger's chain from the Pinocchio ``model`` (the hand's), or None when its
    joints are not a serial chain of one-coordinate revolute joints whose subtree is the
    finger alone."""
    ids = [model.getJointId(hand.joint_names[c]) for c in hand.joint_slice(finger)]
    if any(not model.joints[i].shortname().startswith("JointModelR") or model.joints[i].nq != 1
           for i in ids):
        return None
    if any(model.parents[ids[k]] != ids[k - 1] for k in range(1, len(ids))):
        return None
    if sorted(model.subtrees[ids[0]]) != sorted(ids):
        return None
    n = len(ids)
    offset = [float(np.linalg.norm(model.jointPlacements[i].translation)) for i in ids]
    lever = [float(np.linalg.norm(model.inertias[i].lever)) for i in ids]
    dist = np.zeros((n, n))
    for k in range(n):
        for b in range(k, n):
            dist[k, b] = sum(offset[k + 1:b + 1]) + lever[b]
    return FingerChain(
        np.asarray(hand.joint_slice(finger)), tuple(model.joints[i].idx_v for i in ids),
        dist, np.array([model.inertias[i].mass for i in ids]),
        np.array([float(np.max(np.abs(np.linalg.eigvalsh(model.inertias[i].inertia))))
                  for i in ids]))


@dataclass(frozen=True)
class BoxGain:
    """Bounds over a box of a finger's joints, each term as a centre and a radius
    (every value of the box within the radius of the centre): ``mass`` of ``(M H)_mk``,
    ``speed`` of ``(M c)_m,p``, the coefficient of ``v_k v_l`` for the pair ``pairs[p] =
    (k, l)``, ``k <= l``."""

    mass: np.ndarray
    mass_radius: np.ndarray
    speed: np.ndarray
    speed_radius: np.ndarray
    pairs: tuple[tuple[int, int], ...]


def box_gain(hand: HandModel, kin, chain: FingerChain, M: np.ndarray, lo: np.ndarray,
             hi: np.ndarray) -> BoxGain:
    """``BoxGain`` over the box ``lo``-``hi`` of the chain's joints (``M``: the motors'
    rows on them). ``H`` and ``c`` do not depend on the chain's first joint (the chain
    turned about its first axis, the links before it still: every term an inner product
    of vectors turned alike) nor on the joints before it; the others are sampled at
    ``GRID_POINTS`` each, a pose of the box within half a spacing ``h`` of a sample,
    where a term is within its first derivatives times ``h`` plus ``curvature`` times
    ``(sum h)^2 / 2`` of the sample's."""
    c, n = chain.cols, len(chain.cols)
    pairs = tuple((k, l) for k in range(n) for l in range(k, n))
    axes = [np.array([lo[0]])] + [np.linspace(lo[i], hi[i], GRID_POINTS) for i in range(1, n)]
    half = np.r_[0.0, (hi[1:] - lo[1:]) / (2.0 * (GRID_POINTS - 1))]
    rest = 0.5 * float(np.sum(half)) ** 2
    absM = np.abs(M)
    top = [np.full((len(M), n), -np.inf), np.full((len(M), len(pairs)), -np.inf)]
    low = [np.full((len(M), n), np.inf), np.full((len(M), len(pairs)), np.inf)]
    # (the chain's own model, every other joint locked: the same H and c, in a quarter of
    # the time a derivative)
    model = kin.model
    keep = {model.getJointId(hand.joint_names[j]) for j in c}
    chain_model = pin.buildReducedModel(
        model, [j for j in range(1, model.njoints) if j not in keep], kin.pin_q(np.zeros(hand.n)))
    chain_data = chain_model.createData()
    for point in itertools.product(*axes):
        H, dH, cv, dc = _terms_at(chain_model, chain_data, np.array(point), pairs)
        for i, (val, d) in enumerate(((H, dH), (cv, dc))):
            reach = absM @ (np.abs(d) @ half).T
            top[i] = np.maximum(top[i], M @ val + reach)
            low[i] = np.minimum(low[i], M @ val - reach)
    mass_rest = np.array([[chain.curvature(j, k) for k in range(n)] for j in range(n)])
    speed_rest = np.array([[chain.curvature(j, k) + (chain.curvature(j, l) if k != l else 0.0)
                            for k, l in pairs] for j in range(n)])
    return BoxGain(0.5 * (top[0] + low[0]), 0.5 * (top[0] - low[0]) + absM @ mass_rest * rest,
                   0.5 * (top[1] + low[1]), 0.5 * (top[1] - low[1]) + absM @ speed_rest * rest,
                   pairs)


@dataclass(frozen=True)
class BoxBound:
    """``TendonProof.bound_nm`` of every move of one finger between two poses of a box
    at once but for the move's own tangent ``t`` and profile (``A``, ``V``): the central
    differences' rounding (``e``, ``e2``) bounded over the box (``TendonProof.box_bound``),
    its terms summed ahead: ``static + (|mass t| + mass_radius |t| + e_mass) A +
    (|speed p| + speed_radius |p| + spread |t| + e_speed) V^2``, ``p`` the pairs'
    products ``t_k t_l``; each term at least the move's own in ``bound_nm``. The tangent
    is ``bound_nm``'s to the bit: each coupled joint's ``(ratio dq + offset) - offset``."""

    dep: np.ndarray  # (the finger's coupled joints, their sources, ratios and offsets)
    src: np.ndarray
    ratio: np.ndarray
    offset: np.ndarray
    mass: np.ndarray
    mass_radius: np.ndarray
    speed: np.ndarray
    speed_radius: np.ndarray
    K: np.ndarray
    L: np.ndarray
    e_mass: np.ndarray  # (|mass| + mass_radius) e per motor
    spread: np.ndarray  # (motors, joints): speed_all's slack |t_k| e_l + e_k |t_l| by joint
    e_speed: np.ndarray  # (|mass| + mass_radius) e2 + speed_all (e_k e_l) per motor
    static_nm: np.ndarray
    limit_nm: np.ndarray  # every motor's share less ``PROOF_MARGIN``

    def bound_nm(self, dq: np.ndarray, peak_acceleration: float, peak_speed: float
                 ) -> np.ndarray:
        """Each motor's bound on the move by ``dq`` (the finger's joints, before the
        couplings) of profile ``A``, ``V``, its ends in the box."""
        t = np.array(dq, dtype=float)
        t[self.dep] = (self.ratio * t[self.src] + self.offset) - self.offset
        at = np.abs(t)
        prod = t[self.K] * t[self.L]
        mass = (np.abs(self.mass @ t) + self.mass_radius @ at + self.e_mass) * peak_acceleration
        speed = (np.abs(self.speed @ prod) + self.speed_radius @ np.abs(prod)
                 + self.spread @ at + self.e_speed)
        return self.static_nm + mass + speed * (peak_speed * peak_speed)

    def proves(self, dq: np.ndarray, peak_acceleration: float, peak_speed: float) -> bool:
        """Whether ``bound_nm`` keeps every motor within ``limit_nm``: then so does the
        move's own bound (``TendonProof.proves``) and ``TendonLoad.time_scale`` is 1."""
        return bool((self.bound_nm(dq, peak_acceleration, peak_speed) <= self.limit_nm).all())


def _terms_at(model, data, q: np.ndarray, pairs
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """At configuration ``q`` of a chain's own ``model`` (its joints alone, in order):
    ``H`` (n, n), its derivatives ``dH[k, j, i] = d H_jk / d q_i``, the speed torques'
    coefficients ``cv`` (n, pairs) and their derivatives ``dc[p, j, i]``."""
    n = model.nv
    zero = np.zeros(n)

    def rnea_and_slope(vel: np.ndarray, acc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = pin.computeRNEADerivatives(model, data, q, vel, acc)[0].copy()
        return pin.rnea(model, data, q, vel, acc).copy(), d

    still, still_d = rnea_and_slope(zero, zero)
    units = list(np.eye(n))
    H = np.empty((n, n))
    dH = np.empty((n, n, n))
    for k, e in enumerate(units):
        tau, d = rnea_and_slope(zero, e)
        H[:, k], dH[k] = tau - still, d - still_d
    single = [rnea_and_slope(e, zero) for e in units]
    cv = np.empty((n, len(pairs)))
    dc = np.empty((len(pairs), n, n))
    for p, (k, l) in enumerate(pairs):
        if k == l:
            tau, d = single[k]
            cv[:, p], dc[p] = tau - still, d - still_d
        else:
            tau, d = rnea_and_slope(units[k] + units[l], zero)
            cv[:, p] = tau - single[k][0] - single[l][0] + still
            dc[p] = d - single[k][1] - single[l][1] + still_d
    return H, dH, cv, dc


class TendonProof:
    """The sufficient test of a hand's tendon motors (rows ``M`` of the motor matrix on
    every joint, ``capacity_nm`` their shares): ``proves`` for a move of one finger
    within one of its boxes (``add_box``), no key pushing back. Made only for a hand
    whose couplings and transmissions are linear; a finger whose joints are not a chain
    (``finger_chain``), or a motor pulling on a joint of no finger, proves nothing."""

    def __init__(self, hand: HandModel, kin, M: np.ndarray, capacity_nm: np.ndarray,
                 step: float) -> None:
        self.hand, self.kin, self.M, self.capacity_nm, self.step = hand, kin, M, capacity_nm, step
        self.chains = {f: finger_chain(hand, kin.model, f) for f in hand.fingers}
        # (each finger's boxes, ``add_box``, and their gains once asked)
        self.boxes: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {f: [] for f in hand.fingers}
        self.gains: dict[tuple[str, int], BoxGain] = {}
        g = float(np.linalg.norm(kin.model.gravity.linear))
        gravity = np.full(hand.n, np.inf)
        for chain in self.chains.values():
            if chain is not None:
                gravity[chain.cols] = chain.gravity_bound_nm(g)
        absM = np.abs(M)
        # (each motor's static bound; infinite when it pulls on a joint of no chain)
        self.static_nm = np.array([float(np.sum(absM[m, absM[m] > 0.0]
                                                * gravity[absM[m] > 0.0]))
                                   for m in range(len(M))])
        self._params = json.dumps({"grid_points": GRID_POINTS, "curvature": CURVATURE,
                                   "box_room_rad": BOX_ROOM_RAD,
                                   "motors": hashlib.sha256(np.ascontiguousarray(M).tobytes()
                                                            ).hexdigest()[:16]},
                                  sort_keys=True)
        # (what ``bound_nm`` reads: the couplings at zero, each finger's joints outside its
        # chain, each gain's derived arrays by the gain)
        self._coupled_zero = hand.apply_couplings(np.zeros(hand.n))
        self._outside = {}
        for f in hand.fingers:
            self._outside[f] = np.ones(hand.n, dtype=bool)
            self._outside[f][hand.joint_slice(f)] = False
        self._of_gain: dict[int, tuple] = {}
        # (each finger's grid of cells over its boxes' hull, ``add_cells``)
        self.cells: dict[str, tuple[np.ndarray, np.ndarray, tuple]] = {}
        self.finger_of = np.full(hand.n, -1)
        for i, f in enumerate(hand.fingers):
            self.finger_of[hand.joint_slice(f)] = i

    def params(self) -> str:
        """What a box's gain depends on besides the hand's chains and the box (a shipped
        gain made otherwise is not read: ``planner.play.movetable``): the grid, the
        curvature bound, the box's room and the motor rows (as a digest)."""
        return self._params

    def add_box(self, finger: str, lo: np.ndarray, hi: np.ndarray,
                gain: BoxGain | None = None) -> None:
        """A box of the finger's joints (its chain's, couplings applied) within which its
        moves are tested (a move with an end outside every box is not); the boxes are
        tried in the order they were added, a box's gain worked out when first needed
        (``gain``: its gain as shipped, ``box_gain``'s very floats). A box added again
        is kept once."""
        if self.chains[finger] is None or not np.all(lo <= hi):
            return
        box = _roomed(lo, hi)
        for i, (l0, h0) in enumerate(self.boxes[finger]):
            if np.array_equal(l0, box[0]) and np.array_equal(h0, box[1]):
                if gain is not None:
                    self.gains.setdefault((finger, i), gain)
                return
        if gain is not None:
            self.gains[(finger, len(self.boxes[finger]))] = gain
        self.boxes[finger].append(box)

    def gain(self, finger: str, points: np.ndarray) -> BoxGain | None:
        """The gain of the first of the finger's boxes holding every row of ``points``
        (its chain's joints), or None."""
        for i, (lo, hi) in enumerate(self.boxes[finger]):
            if np.all(points >= lo) and np.all(points <= hi):
                if (finger, i) not in self.gains:
                    chain = self.chains[finger]
                    self.gains[(finger, i)] = box_gain(self.hand, self.kin, chain,
                                                       self.M[:, chain.cols], lo, hi)
                return self.gains[(finger, i)]
        return None

    def box_gain(self, finger: str, lo: np.ndarray, hi: np.ndarray) -> BoxGain | None:
        """The gain ``gain`` works out for the box ``add_box(finger, lo, hi)`` adds (None:
        the finger proves nothing): what the move tables ship."""
        chain = self.chains[finger]
        if chain is None or not np.all(lo <= hi):
            return None
        return box_gain(self.hand, self.kin, chain, self.M[:, chain.cols], *_roomed(lo, hi))

    def bound_nm(self, q_a: np.ndarray, dq: np.ndarray, peak_acceleration: float,
                 peak_speed: float) -> np.ndarray | None:
        """Each motor's largest torque on the move from whole-hand ``q_a`` by ``dq``
        (couplings applied to its points), or None when the move is not one finger's
        within one of its boxes."""
        hand = self.hand
        fingers = set(self.finger_of[np.flatnonzero(dq)].tolist())
        if len(fingers) != 1 or -1 in fingers:
            return None
        finger = hand.fingers[fingers.pop()]
        chain = self.chains[finger]
        if chain is None:
            return None
        c = chain.cols
        tangent = hand.apply_couplings(dq) - self._coupled_zero
        if np.any(tangent[self._outside[finger]] != 0.0):
            return None  # (a coupling carries the move out of the finger)
        points = hand.apply_couplings(np.stack((q_a, q_a + dq)))
        terms = self._terms_over(finger, points[:, c])
        if terms is None:
            return None
        mass_c, mass_r, speed_c, speed_r, abs_mass, mass_all, speed_all, K, L = terms
        # (the tangent and curvature by central differences: the exact ones within their
        # rounding, a few ulps of the largest joint value over the step and its square)
        ulp = ROUNDING_FACTOR * np.spacing(np.max(np.abs(points), axis=0)[c]
                                           + np.abs(dq[c]) + 1.0)
        t = tangent[c]
        e, e2 = ulp / self.step, ulp / (self.step * self.step)
        mass = (np.abs(mass_c @ t) + abs_mass @ e
                + mass_r @ (np.abs(t) + e)) * peak_acceleration \
            + mass_all @ e2 * (peak_speed * peak_speed)
        prod = t[K] * t[L]  # (each pair's product, ``BoxGain.pairs``' order)
        slack = np.abs(t[K]) * e[L] + e[K] * np.abs(t[L]) + e[K] * e[L]
        speed = np.abs(speed_c @ prod) + speed_r @ np.abs(prod) + speed_all @ slack
        bound = self.static_nm + mass + speed * (peak_speed * peak_speed)
        # (over cells: each cell's bound holds where the move is in it, the largest holds)
        return bound if bound.ndim == 1 else np.max(bound, axis=0)

    def _terms_over(self, finger: str, points: np.ndarray) -> tuple | None:
        """What ``bound_nm`` reads of the gain over the move from ``points[0]`` to
        ``points[1]`` (its chain's joints): of the first box holding both (``gain``), else
        of every cell of the finger's grid (``add_cells``) that meets the box of the two
        points widened by ``BOX_ROOM_RAD`` (stacked: the move lies in those cells), when
        the grid holds that box; else None."""
        gain = self.gain(finger, points)
        if gain is not None:
            return (gain.mass, gain.mass_radius, gain.speed, gain.speed_radius,
                    *self._derived(gain))
        cells = self.cells.get(finger)
        if cells is None:
            return None
        lo, hi, terms = cells
        p_lo, p_hi = points.min(axis=0) - BOX_ROOM_RAD, points.max(axis=0) + BOX_ROOM_RAD
        if not (np.all(p_lo >= lo.min(axis=0)) and np.all(p_hi <= hi.max(axis=0))):
            return None
        meet = np.all(lo <= p_hi, axis=1) & np.all(hi >= p_lo, axis=1)
        return (*(a[meet] for a in terms[:7]), *terms[7:])

    def add_cells(self, finger: str, lo: np.ndarray, hi: np.ndarray, gain: BoxGain) -> None:
        """A grid of cells (``lo``, ``hi``: each cell's corners, rows; ``hull_cells``) that
        tiles a box of the finger's joints, with their gains stacked (each array's first
        axis the cell's): a move with an end outside every box (``add_box``) but within
        the grid is bounded over the cells it may pass through."""
        if self.chains[finger] is not None:
            self.cells[finger] = (lo, hi, (gain.mass, gain.mass_radius, gain.speed,
                                           gain.speed_radius, *self._derived(gain)))

    def hull_cells(self, finger: str, lo: np.ndarray, hi: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, BoxGain] | None:
        """The grid ``add_cells`` reads over the box ``lo``-``hi`` (widened by
        ``BOX_ROOM_RAD``): ``GRID_CELLS`` cells a joint but the chain's first (its gain
        does not depend on it), each cell's ``box_gain``, stacked; None for a finger that
        proves nothing."""
        chain = self.chains[finger]
        if chain is None or not np.all(lo <= hi):
            return None
        lo, hi = _roomed(lo, hi)
        edges = [np.array([lo[0], hi[0]])] + [np.linspace(lo[j], hi[j], GRID_CELLS + 1)
                                              for j in range(1, len(lo))]
        corners = [(np.array([e[k] for e, k in zip(edges, at)]),
                    np.array([e[k + 1] for e, k in zip(edges, at)]))
                   for at in itertools.product(*(range(len(e) - 1) for e in edges))]
        gains = [box_gain(self.hand, self.kin, chain, self.M[:, chain.cols], a, b)
                 for a, b in corners]
        return (np.array([a for a, _ in corners]), np.array([b for _, b in corners]),
                BoxGain(*(np.array([getattr(g, k) for g in gains])
                          for k in ("mass", "mass_radius", "speed", "speed_radius")),
                        gains[0].pairs))

    def box_bound(self, finger: str, lo: np.ndarray, hi: np.ndarray,
                  reach: np.ndarray) -> BoxBound | None:
        """``BoxBound`` of the finger's moves between poses of the box ``lo``-``hi`` (its
        chain's joints, couplings applied; widened by ``BOX_ROOM_RAD``) whose joints'
        own differences are at most ``reach``, over the gain of the first box holding it
        (``gain``), else over the cells it meets (``cells_gain``); None where neither
        holds it, or where a coupling joins the finger's joints to another's
        (``bound_nm``: such a move proves nothing)."""
        chain = self.chains[finger]
        if chain is None or not np.all(lo <= hi):
            return None
        c = chain.cols.tolist()
        laws = [w for w in self.hand.couplings if w.dep in c or w.src in c]
        deps = {w.dep for w in self.hand.couplings}
        if any(w.kind != "linear" or w.dep not in c or w.src not in c or w.src in deps
               for w in laws):
            return None
        lo, hi = _roomed(lo, hi)
        gain = self.gain(finger, np.stack((lo, hi)))
        if gain is None:
            gain = self.cells_gain(finger, lo, hi)
        if gain is None:
            return None
        # (``bound_nm``'s rounding bound, its largest over the box: ``np.spacing`` grows
        # with its argument)
        ulp = ROUNDING_FACTOR * np.spacing(np.maximum(np.abs(lo), np.abs(hi)) + reach + 1.0)
        e, e2 = ulp / self.step, ulp / (self.step * self.step)
        _, mass_all, speed_all, K, L = self._derived(gain)
        spread = np.zeros((len(self.M), len(c)))
        for p, (k, l) in enumerate(gain.pairs):
            spread[:, k] += speed_all[:, p] * e[l]
            spread[:, l] += speed_all[:, p] * e[k]
        at = (np.array([c.index(w.dep) for w in laws], dtype=int),
              np.array([c.index(w.src) for w in laws], dtype=int),
              np.array([w.ratio for w in laws], dtype=float),
              np.array([w.offset for w in laws], dtype=float))
        return BoxBound(*at, gain.mass, gain.mass_radius, gain.speed, gain.speed_radius,
                        K, L, mass_all @ e, spread, mass_all @ e2 + speed_all @ (e[K] * e[L]),
                        self.static_nm, self.capacity_nm * (1.0 - PROOF_MARGIN))

    def cells_gain(self, finger: str, lo: np.ndarray, hi: np.ndarray) -> BoxGain | None:
        """One gain over every cell of the finger's grid (``add_cells``) that meets the box
        ``lo``-``hi``: each term's interval the hull of theirs (so each cell's bound on a
        move is at most its own); None when the grid does not hold the box."""
        cells = self.cells.get(finger)
        if cells is None:
            return None
        c_lo, c_hi, terms = cells
        if not (np.all(lo >= c_lo.min(axis=0)) and np.all(hi <= c_hi.max(axis=0))):
            return None
        meet = np.all(c_lo <= hi, axis=1) & np.all(c_hi >= lo, axis=1)
        out = []
        for centre, radius in ((terms[0][meet], terms[1][meet]), (terms[2][meet], terms[3][meet])):
            low, top = np.min(centre - radius, axis=0), np.max(centre + radius, axis=0)
            mid = 0.5 * (low + top)
            out += [mid, np.maximum(top - mid, mid - low)]
        return BoxGain(*out, tuple(zip(terms[7].tolist(), terms[8].tolist())))

    def _derived(self, gain: BoxGain) -> tuple:
        """What ``bound_nm`` reads of a gain besides its terms, once per gain: ``|mass|``,
        ``|mass| + mass_radius``, ``|speed| + speed_radius`` and the pairs' two indices."""
        got = self._of_gain.get(id(gain))
        if got is None or got[0] is not gain:
            K, L = (np.array([p[i] for p in gain.pairs], dtype=int) for i in (0, 1))
            got = self._of_gain[id(gain)] = (
                gain, (np.abs(gain.mass), np.abs(gain.mass) + gain.mass_radius,
                       np.abs(gain.speed) + gain.speed_radius, K, L))
        return got[1]

    def proves(self, q_a: np.ndarray, dq: np.ndarray, peak_acceleration: float,
               peak_speed: float) -> bool:
        """Whether the move (``bound_nm``) keeps every motor within its share with
        ``PROOF_MARGIN`` to spare: ``TendonLoad.time_scale`` is then exactly 1."""
        bound = self.bound_nm(q_a, dq, peak_acceleration, peak_speed)
        return bound is not None and bool(np.all(bound <= self.capacity_nm
                                                 * (1.0 - PROOF_MARGIN)))


def _roomed(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A box widened by ``BOX_ROOM_RAD`` each side."""
    return (np.asarray(lo, dtype=float) - BOX_ROOM_RAD,
            np.asarray(hi, dtype=float) + BOX_ROOM_RAD)

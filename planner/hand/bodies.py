"""The hand's collision bodies: one definition of the shapes that touch keys and balls.

Spec section 3: every link that can touch a key or a ball has collision shapes that
enclose its physical body, with the dimensions of the hand's source documents; section 2
judges keys by them. The URDF's ``<collision>`` elements (``planner.hand.urdf``), the
physics replay's MuJoCo geoms (``planner.simulate.hand_mjcf``), the planner's body
clearance (``planner.play.fingerbody``) and ``check``'s body rule
(``planner.check.bodykeys``) all read ``collision_bodies``; nothing else makes a shape.

Built from the ``HandSpec`` (never from parsing our own URDF text), link by link, for
every link with a physical body (mass > 0: the URDF's inertial box), in the link's frame:

* **A finger segment** (a link whose subtree holds some of the fingertips but not all,
  its box longest along its y, the finger's axis): a rounded slab as wide and as thick as
  its box (the hand file's width; thickness 0.8 x width, ``spec._seg_link``), two
  capsules of half the thickness as radius, side by side across the finger, their outer
  sides at the box's width. Default hand, index base: 23.8 mm wide (seed Table 2,
  upper-limit column, 0.9375 in), 19.1 mm thick. The physics replay's first rule was one
  capsule of the thickness (``hand_mjcf.segment_capsule`` until this module): 19.1 mm
  wide, 4.8 mm narrower than the seed's finger; the seed's width says otherwise, so the
  slab. Between the two capsules' axes the slab's top and bottom dip
  ``r - sqrt(r^2 - a^2)`` below the box's faces (a: half the axes' spacing; 0.30 mm on
  the index base, 0.27 mm on its distal segment).
  Each capsule runs along y from the segment's proximal end (its cap's tip at the
  box's end) to its distal end; on the distal segment, to the pad sphere's centre.
* **The pad** (the distal segment of each finger): a sphere whose bottom, with the
  segment level, is the pad point (the tip link's origin): its centre a pad radius above
  the point, its radius the point's depth below the segment's axis (0.4 x the distal
  width, ``spec._tip``: 8.6 mm on the default index). It is as thick as the distal
  segment, so the slab's capsules and the pad share their lowest line.
* **Every other link** (palm, knuckles, the thumb's CMC, wrist, forearm, rail carriage):
  its box, as the hand file gives it.

The hand's own bodies do not touch each other (the kinematic check does not test that;
the physics replay does not collide them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.hand.spec import HandSpec, Link

BOX, SPHERE, CAPSULE = "box", "sphere", "capsule"
MIN_AXIS_M = 1e-4  # a capsule's axis is at least this long (a degenerate one: a sphere)


@dataclass(frozen=True)
class Body:
    """One collision shape, in its link's frame (m).

    ``kind`` BOX: centred at ``p0_m`` (= ``p1_m``), ``half_m`` along the link's axes.
    SPHERE: centre ``p0_m`` (= ``p1_m``), ``radius_m``. CAPSULE: the segment ``p0_m`` to
    ``p1_m`` swept by a ball of ``radius_m``. ``finger``: the finger whose chain carries
    it (None: the palm and the arm). ``name``: unique in the hand (the MuJoCo geom's
    name and the URDF ``<collision>``'s)."""

    name: str
    link: str
    kind: str
    p0_m: tuple[float, float, float]
    p1_m: tuple[float, float, float]
    radius_m: float = 0.0
    half_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    finger: str | None = None

    @property
    def centre_m(self) -> tuple[float, float, float]:
        return tuple(0.5 * (a + b) for a, b in zip(self.p0_m, self.p1_m))

    @property
    def length_m(self) -> float:
        """A capsule's axis length (0 for a sphere or a box)."""
        return math.dist(self.p0_m, self.p1_m)


def _tips_below(spec: HandSpec) -> dict[str, set[str]]:
    """Each link's fingertip links in its subtree (each tip up its chain of parents: no
    recursion, so no reference cycle for the planner's paused collector)."""
    parent = {j.child: j.parent for j in spec.joints}
    out: dict[str, set[str]] = {link.name: set() for link in spec.links}
    for tip in spec.tip_frames:
        name: str | None = tip
        while name is not None:
            out.setdefault(name, set()).add(tip)
            name = parent.get(name)
    return out


def _pads(spec: HandSpec) -> dict[str, tuple[tuple[float, float, float], float, str]]:
    """The pad of each distal link: (sphere centre in that link's frame, radius, finger)."""
    out = {}
    for j in spec.joints:
        if j.child in spec.tip_frames:
            x, y, z = j.xyz_m
            r = abs(z)
            out[j.parent] = ((x, y, z + r), r, j.child.removesuffix("_tip"))
    return out


def segment_capsules(link: Link, end_y_m: float | None, finger: str | None
                     ) -> tuple[Body, ...]:
    """A finger segment's slab (see the module docstring): two capsules across its width
    (one when the box is as wide as it is thick), along y from the box's proximal end to
    its distal end, or to ``end_y_m`` (the pad's centre) on the distal segment."""
    sx, sy, sz = link.size_m
    cx, cy, cz = link.com_m
    r = 0.5 * min(sx, sz)
    y0 = cy - 0.5 * sy + r
    y1 = cy + 0.5 * sy - r if end_y_m is None else end_y_m
    y1 = max(y1, y0 + MIN_AXIS_M)
    across_x = sx >= sz  # the wide side: across the finger (x) or through it (z)
    a = 0.5 * max(sx, sz) - r
    offsets = (-a, a) if a > 1e-12 else (0.0,)
    out = []
    for i, d in enumerate(offsets):
        x, z = (cx + d, cz) if across_x else (cx, cz + d)
        name = f"{link.name}_capsule" + (str(i) if len(offsets) > 1 else "")
        out.append(Body(name, link.name, CAPSULE, (x, y0, z), (x, y1, z), r, finger=finger))
    return tuple(out)


def collision_bodies(spec: HandSpec) -> tuple[Body, ...]:
    """Every collision shape of the hand, link by link in the spec's order (see the
    module docstring)."""
    below = _tips_below(spec)
    pads = _pads(spec)
    n_tips = len(spec.tip_frames)
    out: list[Body] = []
    for link in spec.links:
        if link.mass_kg <= 0:
            continue
        tips = below.get(link.name, set())
        finger = next(iter(tips)).removesuffix("_tip") if len(tips) == 1 else None
        sx, sy, sz = link.size_m
        pad = pads.get(link.name)
        if 0 < len(tips) < n_tips and sy > sx and sy > sz:
            out.extend(segment_capsules(link, None if pad is None else pad[0][1], finger))
        else:
            c = tuple(float(v) for v in link.com_m)
            out.append(Body(f"{link.name}_box", link.name, BOX, c, c,
                            half_m=(0.5 * sx, 0.5 * sy, 0.5 * sz), finger=finger))
        if pad is not None:
            centre, r, f = pad
            out.append(Body(f"{f}_pad", link.name, SPHERE, centre, centre, r, finger=f))
    return tuple(out)


def body_links(bodies: tuple[Body, ...]) -> tuple[str, ...]:
    """The links that carry bodies, in first-seen order."""
    return tuple(dict.fromkeys(b.link for b in bodies))


@dataclass(frozen=True)
class PlacedBodies:
    """Bodies in the world at many configurations: the sphere-swept ones (capsules and
    spheres: ``a``, ``b`` axis ends (T, S, 3), ``radius_m`` (S,)) and the boxes
    (``centre`` (T, B, 3), ``axes`` (T, B, 3, 3): columns the box's x, y, z in the world,
    ``half_m`` (B, 3)); ``swept``/``boxes`` index into the bodies placed."""

    swept: tuple[int, ...]
    a: np.ndarray
    b: np.ndarray
    radius_m: np.ndarray
    boxes: tuple[int, ...]
    centre: np.ndarray
    axes: np.ndarray
    half_m: np.ndarray


def place(bodies: tuple[Body, ...], link_poses: dict[str, np.ndarray]) -> PlacedBodies:
    """The bodies in the world, each link's world pose (T, 4, 4) from ``link_poses``."""
    def carry(b: Body, p: tuple[float, float, float]) -> np.ndarray:
        T = link_poses[b.link]
        return T[:, :3, :3] @ np.asarray(p) + T[:, :3, 3]

    sw = tuple(i for i, b in enumerate(bodies) if b.kind != BOX)
    bx = tuple(i for i, b in enumerate(bodies) if b.kind == BOX)
    n = len(next(iter(link_poses.values()))) if link_poses else 0

    def stack(xs, shape):
        return np.stack(xs, axis=1) if xs else np.zeros(shape)

    a = stack([carry(bodies[i], bodies[i].p0_m) for i in sw], (n, 0, 3))
    b = stack([carry(bodies[i], bodies[i].p1_m) for i in sw], (n, 0, 3))
    c = stack([carry(bodies[i], bodies[i].p0_m) for i in bx], (n, 0, 3))
    R = stack([link_poses[bodies[i].link][:, :3, :3] for i in bx], (n, 0, 3, 3))
    return PlacedBodies(sw, a, b, np.array([bodies[i].radius_m for i in sw]), bx, c, R,
                        np.array([bodies[i].half_m for i in bx]).reshape(-1, 3))

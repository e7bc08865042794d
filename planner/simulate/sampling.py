"""What the replay reads at each row, and the record's arrays made from it after the run.

At a row only MuJoCo's state is copied out (the hand's joints and speeds, the keys'
travel, the pad points and the palm, the contacts' geom pairs; the ball's state and
contact force); everything derived from it -- each servo's demand, its clamped force,
which finger holds which key -- is computed once over all the rows at the end, by the
same elementwise arithmetic the replay did row by row (the same numbers to the bit:
tests/test_simulate_speed.py), so that the rows cost the simulation little beyond the
copies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

N_KEYS = 88


def _index(adr: np.ndarray):
    """A slice where the addresses are consecutive (a copy, not a gather), else them."""
    adr = np.asarray(adr, dtype=int)
    if len(adr) and np.array_equal(adr, np.arange(adr[0], adr[0] + len(adr))):
        return slice(int(adr[0]), int(adr[0]) + len(adr))
    return adr


@dataclass(frozen=True)
class Addr:
    """The scene's addresses the rows read (looked up once)."""

    hand_q: slice | np.ndarray  # into qpos: the hand's joints, the hand's order
    hand_v: slice | np.ndarray  # into qvel
    key_q: slice | np.ndarray | None  # into qpos: the 88 keys' travel (None: no keyboard)
    sites: np.ndarray  # the pad points' sites, then the palm's
    ball_body: int  # -1 without a ball
    ball_geom: int


def addr(scene) -> Addr:
    keys = _index(scene.key_qpos) if len(scene.key_qpos) else None
    return Addr(_index(scene.hand_qpos), _index(scene.hand_dof), keys,
                np.append(scene.tip_sites, scene.palm_site).astype(int), scene.ball_body,
                scene.ball_geom)


class Rows:
    """The raw samples, one per row."""

    def __init__(self, T: int, n: int, n_sites: int) -> None:
        self.q = np.empty((T, n))
        self.v = np.empty((T, n))
        self.key = np.zeros((T, N_KEYS))
        self.sites = np.empty((T, n_sites, 3))
        self.ball = np.full((T, 3), np.nan)
        self.ball_v = np.full(T, np.nan)
        self.ball_n = np.zeros(T)
        self.ball_f = np.zeros(T)
        self.contact_rows: list[int] = []
        self.contact_geoms: list[np.ndarray] = []

    def take(self, k: int, data, a: Addr) -> None:
        """Row ``k``'s state (the ball's: ``take_ball``)."""
        qpos = data.qpos
        self.q[k] = qpos[a.hand_q]
        self.v[k] = data.qvel[a.hand_v]
        if a.key_q is not None:
            self.key[k] = qpos[a.key_q]
        self.sites[k] = data.site_xpos[a.sites]
        n = data.ncon
        if n:
            self.contact_rows.append(k)
            self.contact_geoms.append(np.array(data.contact.geom[:n]))

    def take_ball(self, k: int, data, a: Addr, contacts: int, force_n: float) -> None:
        self.ball[k] = data.xpos[a.ball_body]
        self.ball_v[k] = float(np.linalg.norm(data.cvel[a.ball_body][3:]))
        self.ball_n[k], self.ball_f[k] = contacts, force_n


def touches(rows: Rows, key_geom_key: np.ndarray, geom_finger: np.ndarray, ball_geom: int,
            n_fingers: int) -> tuple[np.ndarray, np.ndarray]:
    """(T, 88) int8: the finger touching each key at each row (the hand's index; -1
    none: of two, the later contact's), and (T, fingers) bool: the fingers touching the
    ball."""
    T = len(rows.q)
    key_finger = np.full((T, N_KEYS), -1, dtype=np.int8)
    ball_fingers = np.zeros((T, n_fingers), dtype=bool)
    if not rows.contact_rows:
        return key_finger, ball_fingers
    geoms = np.concatenate(rows.contact_geoms)
    row = np.repeat(rows.contact_rows, [len(g) for g in rows.contact_geoms])
    g1, g2 = geoms[:, 0], geoms[:, 1]
    k1, k2 = key_geom_key[g1], key_geom_key[g2]
    f1, f2 = geom_finger[g1], geom_finger[g2]
    key = np.where(k1 >= 0, k1, k2)
    fin = np.where(k1 >= 0, f2, f1)
    sel = (key >= 0) & (fin >= 0)
    key_finger[row[sel], key[sel]] = fin[sel]
    if ball_geom >= 0:
        fb = np.where(g1 == ball_geom, f2, f1)
        on = ((g1 == ball_geom) | (g2 == ball_geom)) & (fb >= 0)
        ball_fingers[row[on], fb[on]] = True
    return key_finger, ball_fingers


def servo_rows(rows: Rows, drive: np.ndarray, ctrl: np.ndarray, kp: np.ndarray,
               kv: np.ndarray, limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(demand, force), each (T, n_motor): what each servo's control law asked for at
    each row from its state there (``kp (ctrl - q) - kv qd``: MuJoCo's position servo;
    from the state itself -- ``data.actuator_length`` and ``_velocity`` are the last
    step's start, 1 ms old, at 250 rad/s^2 a 0.3 N m error), and that clamped to the
    servo's range ``limit``."""
    demand = kp * (ctrl - rows.q[:, drive]) - kv * rows.v[:, drive]
    return demand, np.clip(demand, -limit, limit)

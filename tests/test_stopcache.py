"""planner.catch.live.stopcache: the live stop table kept between runs only where
HAND_PLANNER_CACHE names a directory; read back, the same table to the bit (every field,
every type) without making it again; a key per catch point, ball and drag; a file that
cannot be read is made again."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from planner.catch.flight.path import get_ball
from planner.catch.live import stopcache
from planner.catch.live.stop import StopTable
from planner.catch.plan.api import get_planner

BALL = get_ball("tennis")
C = np.array([1.63, 0.0, 0.07])  # (a catch point no other test's table is made for)
ROW_S = 0.01


def _same(a: StopTable, b: StopTable) -> None:
    assert np.array_equal(a.angles_deg, b.angles_deg)
    assert np.array_equal(a.tilts_rad, b.tilts_rad)
    assert np.array_equal(a.prior, b.prior)
    assert len(a.stops) == len(b.stops) > 0
    for s, u in zip(a.stops, b.stops):
        for f in dataclasses.fields(s):
            x, y = getattr(s, f.name), getattr(u, f.name)
            assert type(x) is type(y), f.name
            assert np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y, f.name


def test_nothing_kept_without_the_variable(monkeypatch, tmp_path):
    monkeypatch.delenv(stopcache.CACHE_ENV, raising=False)
    monkeypatch.chdir(tmp_path)
    assert stopcache.cache_dir() is None
    StopTable.kept(get_planner("default"), C, BALL, True, ROW_S)
    assert list(tmp_path.iterdir()) == []


def test_a_kept_table_is_read_back_the_same(monkeypatch, tmp_path):
    pl = get_planner("default")
    monkeypatch.setenv(stopcache.CACHE_ENV, str(tmp_path))
    made = StopTable.kept(pl, C, BALL, True, ROW_S)
    files = list(tmp_path.iterdir())
    assert len(files) == 1
    make = StopTable.make

    def not_again(*a, **k):
        raise AssertionError("made again, not read")

    monkeypatch.setattr(StopTable, "make", not_again)
    read = StopTable.kept(pl, C, BALL, True, ROW_S)
    _same(read, made)
    _same(read, make(pl, C, BALL, True, ROW_S))  # (and the table made without the cache)


def test_a_key_per_catch_point_ball_and_drag():
    pl = get_planner("default")
    keys = {stopcache.table_key(pl, c, b, d, ROW_S)
            for c in (C, C + [0.01, 0.0, 0.0]) for b in (BALL, get_ball("golf"))
            for d in (True, False)}
    assert len(keys) == 8
    assert stopcache.table_key(pl, C.copy(), BALL, True, ROW_S) in keys


@pytest.mark.parametrize("content", [b"", b"not an npz"])
def test_a_file_that_cannot_be_read_is_made_again(monkeypatch, tmp_path, content):
    pl = get_planner("default")
    monkeypatch.setenv(stopcache.CACHE_ENV, str(tmp_path))
    path = stopcache.table_path(tmp_path, stopcache.table_key(pl, C, BALL, False, ROW_S))
    path.write_bytes(content)
    table = StopTable.kept(pl, C, BALL, False, ROW_S)
    _same(table, StopTable.make(pl, C, BALL, False, ROW_S))
    _same(StopTable.kept(pl, C, BALL, False, ROW_S), table)  # (written again, then read)


def test_a_file_whose_arrays_do_not_match_is_made_again(monkeypatch, tmp_path):
    """A kept file with a field missing or one stop short (written by hand, or by a
    version whose table had another shape) is not read: the table is made again."""
    pl = get_planner("default")
    monkeypatch.setenv(stopcache.CACHE_ENV, str(tmp_path))
    made = StopTable.kept(pl, C, BALL, False, ROW_S)
    path = stopcache.table_path(tmp_path, stopcache.table_key(pl, C, BALL, False, ROW_S))
    with np.load(path) as z:
        arrays = {n: z[n] for n in z.files}
    field = min(set(arrays) - {"arm", "angles_deg", "tilts_rad", "prior"})
    for broken in ({n: a for n, a in arrays.items() if n != field},
                   dict(arrays, **{field: arrays[field][:-1]})):
        with open(path, "wb") as fh:
            np.savez(fh, **broken)
        assert stopcache.load(path) is None
        _same(StopTable.kept(pl, C, BALL, False, ROW_S), made)

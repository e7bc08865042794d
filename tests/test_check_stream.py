"""``check`` reads a play file as a stream (issue 32, item 5): the report judged block by
block equals the report of the file read whole, whatever the blocks; a file it cannot
stream (damaged, a catch) is read whole, its defect named as before."""

from __future__ import annotations

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.errors import InputError
from planner.trajfile import NotStreamable, stream_trajectory
from tests.hardening import SCALE


def _same(path, song, monkeypatch, rows, **kw):
    whole = check_trajectory(str(path), song, **kw)
    monkeypatch.setattr("planner.trajfile.STREAM_ROWS", rows)
    streamed = check_trajectory(str(path), song, replay=False, **kw)
    assert streamed.replay is None and whole.replay is not None
    assert streamed.to_dict() == whole.to_dict()
    assert streamed.summary() == whole.summary()
    return streamed


@pytest.mark.parametrize("rows", [2, 7, 64, 4096])
def test_a_streamed_check_is_the_whole_check(planned, monkeypatch, rows):
    _same(planned, str(SCALE), monkeypatch, rows)
    _same(planned, None, monkeypatch, rows)


def test_the_stream_is_taken(planned, monkeypatch):
    seen = []
    real = stream_trajectory

    def spy(*a, **k):
        s = real(*a, **k)
        seen.append(s.rows)
        return s

    monkeypatch.setattr("planner.check.trajcheck.stream_trajectory", spy)
    check_trajectory(str(planned), str(SCALE), replay=False)
    assert seen and seen[0] > 100


def _edited(planned, tmp_path, edit):
    lines = planned.read_text().split("\n")
    edit(lines)
    out = tmp_path / "edited.csv"
    out.write_text("\n".join(lines))
    return out


def test_wrong_presses_and_limits_stream_alike(planned, tmp_path, monkeypatch):
    """Rows moved: a jump of the rail (speed, acceleration, jerk, wrong keys)."""
    def edit(lines):
        for i in range(300, 420):
            v = lines[i].split(",")
            v[1] = f"{float(v[1]) + 0.05:.6f}"
            lines[i] = ",".join(v)

    bad = _edited(planned, tmp_path, edit)
    rep = _same(bad, str(SCALE), monkeypatch, 50)
    assert not rep.ok


@pytest.mark.parametrize("edit", [
    lambda ls: ls.__setitem__(200, ls[200].replace(",", ";", 1)),
    lambda ls: ls.__setitem__(250, ls[250].replace("0.", "nan", 1)),
    lambda ls: ls.__setitem__(5, ls[6]),
    lambda ls: ls.pop(-2),
    lambda ls: ls.__setitem__(0, ls[0].replace('"default"', '"nohand"')),
])
def test_a_damaged_file_is_named_as_read_whole(planned, tmp_path, edit):
    bad = _edited(planned, tmp_path, edit)
    with pytest.raises(InputError) as whole:
        check_trajectory(str(bad), str(SCALE))
    with pytest.raises(InputError) as streamed:
        check_trajectory(str(bad), str(SCALE), replay=False)
    assert str(streamed.value) == str(whole.value)


def test_what_cannot_stream(planned, tmp_path):
    cut = _edited(planned, tmp_path, lambda ls: ls.pop(-2))
    with pytest.raises(NotStreamable):
        stream_trajectory(str(cut))
    s = stream_trajectory(str(planned))
    t = np.concatenate([b[0] for b in s.blocks(100)])
    assert len(t) == s.rows and t[0] == 0.0


def test_the_self_check_judges_alike_in_any_batch(hand, monkeypatch):
    """``play``'s self-check streams the same rules: its claims (the end marker) do not
    depend on how many rows it judges at once."""
    from planner.music.midi import load_song
    from planner.play import plan_song

    song = load_song(str(SCALE))
    whole = plan_song(song, hand).text
    monkeypatch.setattr("planner.selfcheck.BATCH_ROWS", 7)
    assert plan_song(song, hand).text == whole
    assert '"played": ' in whole.rsplit("\n", 2)[-2]

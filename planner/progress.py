"""A progress bar for long work (planning a song, drawing its report, a batch), on a
terminal only: its rate and the time left, on stderr, cleared when the work is done.

``progress_bar(unit)`` is a context manager giving a ``Progress``: ``update(done,
total)`` is the callback the planner's stages take (``plan_song(on_progress=...)``,
``write_check_report(on_progress=...)``, ``batch_plan(on_progress=...)``); ``write(line)``
prints a line above the bar. When stderr is not a terminal (a pipe, a log file, CI) or
``enabled`` is False (``--json``), nothing is drawn and ``write`` goes to stderr as is.
tqdm is imported only when a bar is drawn.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator


class Progress:
    """One bar, created when the first ``update`` says how much work there is."""

    def __init__(self, unit: str, enabled: bool) -> None:
        self.unit = unit
        self.enabled = enabled
        self._bar = None

    def update(self, done: int, total: int) -> None:
        if not self.enabled or total <= 0:
            return
        if self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(total=total, unit=self.unit, file=sys.stderr, leave=False,
                             mininterval=0.2)
        elif self._bar.total != total:
            self._bar.total = total
        self._bar.update(done - self._bar.n)

    def write(self, line: str) -> None:
        """``line`` on stderr, above the bar when there is one."""
        if self._bar is None:
            sys.stderr.write(line + "\n")
        else:
            self._bar.write(line, file=sys.stderr)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


@contextlib.contextmanager
def progress_bar(unit: str, enabled: bool = True) -> Iterator[Progress]:
    """A ``Progress`` drawn on stderr if it is a terminal and ``enabled``."""
    bar = Progress(unit, enabled and sys.stderr.isatty())
    try:
        yield bar
    finally:
        bar.close()

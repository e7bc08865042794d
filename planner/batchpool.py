"""The local worker processes of ``batch``: a pool that a signal can stop at once.

``WorkerPool(fn, workers)`` starts ``workers`` processes; ``run(tasks)`` yields
``(task, result)`` as each finishes. ``fn(task)`` runs in a worker; an exception it
raises, or the worker dying under it (killed, out of memory), comes back as the
result ``Failed(reason)`` (one line) and the others go on. Leaving the pool (its
``with`` block: done, an exception, ``KeyboardInterrupt`` from SIGINT, SIGTERM or
SIGHUP) terminates every worker and waits for it (SIGKILL after ``STOP_S``): none
outlives the main process, not even one killed with SIGKILL (each worker watches its
parent, and on Linux asks the kernel for SIGKILL when the parent dies).

Workers ignore SIGINT (a terminal's Ctrl-C reaches the whole process group: the main
process stops them) and take SIGTERM and SIGHUP by their default action (they die;
a trajectory they were writing stays without its end marker: visibly incomplete).
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from multiprocessing.connection import wait
from typing import Any

STOP_S = 1.0  # a worker has this long to die of SIGTERM before SIGKILL
WATCH_S = 0.2  # a worker looks at its parent this often
POLL_S = 0.2  # the main process looks for dead workers this often


@dataclass(frozen=True)
class Failed:
    """A task whose function raised, or whose worker died under it."""

    reason: str


def _die_with_parent(parent: int) -> None:
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(WATCH_S)
        os._exit(1)

    threading.Thread(target=watch, daemon=True).start()


def _worker(fn: Callable[[Any], Any], parent: int, tasks, conn) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
    _die_with_parent(parent)
    while True:
        item = tasks.get()
        if item is None:
            return
        i, task = item
        conn.send(("start", i))  # (sent at once, no buffer: a worker that dies loses nothing)
        try:
            out = fn(task)
        except Exception as e:  # noqa: BLE001 -- a task's failure is its result, one line
            first = (str(e).strip().splitlines() or [""])[0]
            out = Failed(f"{type(e).__name__}: {first}"[:500])
        conn.send(("done", i, out))


class WorkerPool:
    """See the module docstring."""

    def __init__(self, fn: Callable[[Any], Any], workers: int) -> None:
        ctx = mp.get_context("fork" if sys.platform.startswith("linux") else "spawn")
        self._tasks = ctx.Queue()
        self._procs, self._conns = [], []
        for _ in range(workers):
            recv, send = ctx.Pipe(duplex=False)
            p = ctx.Process(target=_worker, args=(fn, os.getpid(), self._tasks, send),
                            daemon=True)
            p.start()
            send.close()
            self._procs.append(p)
            self._conns.append(recv)

    def __enter__(self) -> WorkerPool:  # noqa: PYI034 (Python 3.10 has no typing.Self)
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    def run(self, tasks: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        todo = list(tasks)
        for i, t in enumerate(todo):
            self._tasks.put((i, t))
        for _ in self._procs:
            self._tasks.put(None)
        on: dict[int, int] = {}  # worker -> the task it is on
        left = set(range(len(todo)))
        live = dict(enumerate(self._conns))
        while left and live:
            for conn in wait(list(live.values()), timeout=POLL_S):
                w = self._conns.index(conn)
                try:
                    msg = conn.recv()
                except (EOFError, OSError):  # (the worker is gone)
                    del live[w]
                    i = on.pop(w, None)
                    if i is not None and i in left:
                        left.discard(i)
                        self._procs[w].join(STOP_S)
                        yield todo[i], Failed("its worker died (exit status "
                                              f"{self._procs[w].exitcode})")
                    continue
                if msg[0] == "start":
                    on[w] = msg[1]
                elif msg[1] in left:
                    on.pop(w, None)
                    left.discard(msg[1])
                    yield todo[msg[1]], msg[2]
        for i in sorted(left):  # (every worker gone: nothing will take these)
            yield todo[i], Failed("no worker left to plan it")

    def stop(self) -> None:
        """Terminate every worker (SIGTERM, then SIGKILL after ``STOP_S``) and reap it."""
        for p in self._procs:
            if p.is_alive():
                p.terminate()
        end = time.monotonic() + STOP_S
        for p in self._procs:
            p.join(max(0.0, end - time.monotonic()))
            if p.is_alive():
                p.kill()
                p.join()
        self._tasks.cancel_join_thread()
        self._tasks.close()
        for c in self._conns:
            c.close()

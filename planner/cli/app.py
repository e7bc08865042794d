"""The command line's shared machinery: the parser, one exit-code map, signals.

Exit status (spec section 1): 0 success; 2 bad input or usage (one line on
stderr); 1 anything else that failed, or an infeasible plan under --strict.
A reader that closes its end of the output pipe (``| head``) ends the run
quietly with 141 (128 + SIGPIPE, what a shell reports for a program killed by
it); SIGINT, SIGTERM and SIGHUP stop it cleanly with 128 + the signal's number.

Each command is a module of this package (``hand``, ``play``, ``catch``, ``batch``,
``check``, ``simulate``) with ``add_parser(sub)`` (its options) and ``run(args)`` (one
call of the typed API, its result as text or JSON, the exit status).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys

from planner.cli import batch, catch, check, hand, play, simulate
from planner.cli.options import check_artefacts, refuse_closed_stdout

EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE  # 141
EPILOG = """examples:
  hand-planner play songs/twinkle.mid -o twinkle.csv
  hand-planner check twinkle.csv songs/twinkle.mid --strict
  hand-planner catch --angle 30 --dist 1.5 -o catch.csv --json
  hand-planner hand --urdf hand.urdf
  hand-planner simulate twinkle.csv songs/twinkle.mid --json

exit status: 0 success; 2 bad input (one line on stderr); 1 anything else, or what
--strict rejects; 141 when the reader of the output goes away (| head); 128 + the
signal's number after SIGINT, SIGTERM or SIGHUP."""

# (the commands, in the order of the help; each a module with add_parser and run)
COMMANDS = {"hand": hand, "play": play, "catch": catch, "batch": batch, "check": check,
            "simulate": simulate}


class Interrupted(KeyboardInterrupt):
    """SIGTERM or SIGHUP, handled as SIGINT is: the run stops where it is."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


def _on_signal(signum, _frame) -> None:
    raise Interrupted(signum)


def _follow_signals() -> None:
    for sig in (signal.SIGTERM, signal.SIGHUP):
        try:
            signal.signal(sig, _on_signal)
        except (ValueError, OSError):  # not the main thread (an embedding program)
            pass


def _quiet_stdout() -> None:
    """After a closed pipe: stdout goes to /dev/null so that the interpreter's last
    flush at exit cannot fail again (and print 'Exception ignored ...')."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def one_line(text: object) -> str:
    """``text`` on one line: user input quoted in a message (a file name, an argument)
    may hold line breaks, which would break the one-line promise."""
    return str(text).replace("\r", "\\r").replace("\n", "\\n")


class Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line on stderr and exit 2."""

    def error(self, message: str) -> None:  # one line, exit 2
        sys.stderr.write(f"{self.prog}: error: {one_line(message)}\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    """The whole command line: every command's options (its module's ``add_parser``)."""
    prog = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "hand-planner"
    p = Parser(prog=prog if prog in ("cli.py", "hand-planner") else "hand-planner",
               description="Task planner for a tendon-driven robot hand",
               epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for command in COMMANDS.values():
        command.add_parser(sub)
    return p


# (the option naming where a command's artefact goes: '-' there is stdout)
_ARTEFACT = {"play": ("output", "trajectory"), "catch": ("output", "trajectory"),
             "hand": ("urdf", "URDF")}


def _refuse_json_with_stdout(a: argparse.Namespace) -> None:
    """``--json`` owns stdout: the command's trajectory or URDF then needs a path."""
    option, what = _ARTEFACT.get(a.command, (None, ""))
    if getattr(a, "json", False) and option and getattr(a, option) == "-":
        from planner.errors import InputError

        raise InputError(f"--json writes its object on stdout: the {what} needs a path")


# (below this address-space limit, ``ulimit -v``, the numerical libraries cannot start, and
# OpenBLAS may spin forever retrying its buffer (seen at 230 MB; twinkle plans at 250 MB);
# above it, a shortage ends in MemoryError or ImportError, one line)
MIN_ADDRESS_SPACE = 256 << 20


def _address_space_refused() -> str | None:
    """The one line when ``ulimit -v`` is too small to start; under any limit, OpenBLAS
    keeps to one thread (with a thread's buffers per core it spins forever retrying them
    when the limit cannot hold them all)."""
    import resource

    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return None
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    if soft >= MIN_ADDRESS_SPACE:
        return None
    return (f"the address-space limit (ulimit -v) is {soft >> 20} MiB; the planner needs at "
            f"least {MIN_ADDRESS_SPACE >> 20} MiB to start")


def _out_of_memory(e: BaseException) -> str:
    what = one_line(e)[:200]
    limit = _address_space_refused() or "is the address-space limit (ulimit -v) too small?"
    return f"out of memory ({type(e).__name__}{': ' + what if what else ''}); {limit}"


def main(argv: list[str] | None = None) -> int:
    from planner.output import reopen_closed_stdio

    closed = reopen_closed_stdio()  # (a stream the shell closed: /dev/null)
    refused = _address_space_refused()
    if refused:
        sys.stderr.write(f"error: {refused}\n")
        return 2
    args = build_parser().parse_args(argv)
    from planner.errors import InfeasibleError, InputError, PlannerError

    _follow_signals()
    try:
        _refuse_json_with_stdout(args)
        refuse_closed_stdout(args, closed)
        check_artefacts(args)  # (every output path, before any planning)
        rc = COMMANDS[args.command].run(args)
        sys.stdout.flush()
        return rc
    except BrokenPipeError:
        _quiet_stdout()
        return EXIT_BROKEN_PIPE
    except InputError as e:
        sys.stderr.write(f"error: {one_line(e)}\n")
        return 2
    except InfeasibleError as e:
        sys.stderr.write(f"infeasible: {one_line(e)}\n")
        return 1
    except PlannerError as e:
        sys.stderr.write(f"failed: {one_line(e)}\n")
        return 1
    except (MemoryError, ImportError) as e:  # (``ulimit -v``: an allocation or a library
        sys.stderr.write(f"error: {_out_of_memory(e)}\n")  # that cannot be mapped)
        return 2
    except KeyboardInterrupt as e:
        signum = e.signum if isinstance(e, Interrupted) else signal.SIGINT
        sys.stderr.write(f"interrupted ({signal.Signals(signum).name})\n")
        return 128 + signum


def run() -> None:
    """The console script's entry point."""
    sys.exit(main())

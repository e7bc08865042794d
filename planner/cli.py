"""Command line (``hand-planner``, or ``python cli.py`` in the repository): parse, call
one API function, map errors to exit codes.

Exit status (spec section 1): 0 success; 2 bad input or usage (one line on
stderr); 1 anything else that failed, or an infeasible plan under --strict.
A reader that closes its end of the output pipe (``| head``) ends the run
quietly with 141 (128 + SIGPIPE, what a shell reports for a program killed by
it); SIGINT, SIGTERM and SIGHUP stop it cleanly with 128 + the signal's number.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys

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


def _line(text: object) -> str:
    """``text`` on one line: user input quoted in a message (a file name, an argument)
    may hold line breaks, which would break the one-line promise."""
    return str(text).replace("\r", "\\r").replace("\n", "\\n")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2
        sys.stderr.write(f"{self.prog}: error: {_line(message)}\n")
        raise SystemExit(2)


def _build_parser() -> argparse.ArgumentParser:
    prog = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "hand-planner"
    p = _Parser(prog=prog if prog in ("cli.py", "hand-planner") else "hand-planner",
                description="Task planner for a tendon-driven robot hand",
                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in (_add_hand, _add_play, _add_catch, _add_batch, _add_check, _add_simulate):
        add(sub)
    return p


def _add_hand(sub) -> None:
    """``hand``: describe, list, URDF, strength."""
    h = sub.add_parser("hand", help="describe a hand, list hands, write its URDF")
    h.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    h.add_argument("--list", action="store_true", help="list the shipped hands")
    h.add_argument("--urdf", metavar="PATH", help="write the hand's URDF here ('-' for stdout)")
    h.add_argument("--strength", action="store_true",
                   help="the hand's strength from its model beside the seed's requirements")
    h.add_argument("--json", action="store_true", help="one JSON object on stdout")


def _add_play(sub) -> None:
    """``play``: plan a MIDI song."""
    pl = sub.add_parser("play", help="plan a MIDI song")
    pl.add_argument("song", help="MIDI file")
    pl.add_argument("-o", "--output", default=None,
                    help="trajectory CSV ('-' for stdout; default: SONG.csv in the current "
                         "directory)")
    pl.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    pl.add_argument("--rate", type=float, default=100.0, help="setpoint rate, Hz (default 100)")
    pl.add_argument("--track", type=int, default=None, help="only this track (0-based)")
    pl.add_argument("--channel", type=int, default=None, help="only this channel (0-15)")
    pl.add_argument("--transpose", action="store_true", help="move notes outside A0-C8 by octaves")
    pl.add_argument("--strict", action="store_true",
                    help="exit 1 if any note is not played, late, or a key is pressed wrongly")
    _pictures(pl)
    pl.add_argument("--json", action="store_true",
                    help="the summary as one JSON object on stdout (needs -o FILE)")


def _pictures(parser) -> None:
    """``--report DIR`` and ``--html FILE`` (play, catch, check: the checked plan drawn)."""
    parser.add_argument("--report", metavar="DIR", help="write PNG plots here")
    parser.add_argument("--html", metavar="FILE", help="write a 3D animation (HTML)")


def _add_catch(sub) -> None:
    """``catch``: plan a catch (once, or live from observations)."""
    c = sub.add_parser("catch", help="plan a catch of a thrown ball")
    c.add_argument("--angle", type=float, default=None,
                   help="launch angle above horizontal, deg (required unless --live)")
    c.add_argument("--dist", type=float, required=True, help="horizontal distance to the hand, m")
    c.add_argument("--height", type=float, default=0.0, help="hand height above the launch point, m")
    c.add_argument("--ball", default="tennis", help="ball: tennis, baseball, golf, seed")
    c.add_argument("--drag", action="store_true", help="model quadratic air drag")
    c.add_argument("--observations", metavar="CSV", help="fit the flight to t,x,y,z observations")
    c.add_argument("--live", action="store_true",
                   help="re-plan after each t,x,y,z observation read from stdin as it arrives")
    c.add_argument("-o", "--output", default="catch.csv",
                   help="trajectory CSV ('-' for stdout; default catch.csv)")
    c.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    c.add_argument("--rate", type=float, default=100.0, help="setpoint rate, Hz (default 100)")
    c.add_argument("--strict", action="store_true", help="exit 1 if the catch is infeasible")
    _pictures(c)
    c.add_argument("--json", action="store_true",
                   help="the summary as one JSON object on stdout (needs -o FILE)")


def _add_batch(sub) -> None:
    """``batch``: a folder of songs."""
    b = sub.add_parser("batch", help="plan and check every song of a folder (resumable)")
    b.add_argument("songs", help="folder of MIDI files (*.mid)")
    b.add_argument("out", help="folder for the trajectories, per-song records and summary")
    b.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    b.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    b.add_argument("--address", default=None,
                   help="run on a Ray cluster at this address ('local': a local Ray)")
    b.add_argument("--json", action="store_true", help="one JSON object on stdout")


def _replay_options(parser, what: str) -> None:
    """The options ``check`` and ``simulate`` share: how to read the file and the song,
    what fails, the output."""
    parser.add_argument("trajectory", help="hand-trajectory v1 file")
    parser.add_argument("song", nargs="?", default=None, help="the MIDI file it was planned from")
    parser.add_argument("--allow-incomplete", action="store_true",
                        help="replay a file without its end marker (still being written, or cut)")
    parser.add_argument("--min-f1", type=float, default=None, help=f"fail under this {what} F1")
    parser.add_argument("--strict", action="store_true",
                        help="fail on any missed or late note, not only wrong ones")
    parser.add_argument("--track", type=int, default=None,
                        help="read only this track of the song (default: as the plan was made)")
    parser.add_argument("--channel", type=int, default=None,
                        help="read only this channel (default: as the plan was made)")
    parser.add_argument("--transpose", action="store_true",
                        help="move notes outside A0-C8 by octaves (default: as the plan was made)")
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")
    parser.add_argument("--hand", default=None,
                        help="the hand name or hand file (.toml) the plan was made with "
                             "(default: the file's hand, by name)")


def _add_check(sub) -> None:
    """``check``: replay a trajectory by kinematics and verify it."""
    k = sub.add_parser("check", help="replay a trajectory and verify it")
    _replay_options(k, "frame")
    k.add_argument("--played", metavar="OUT.mid", help="write the keys pressed as a MIDI file")
    _pictures(k)


def _add_simulate(sub) -> None:
    """``simulate``: replay a trajectory in MuJoCo."""
    sm = sub.add_parser("simulate", help="replay a trajectory in MuJoCo physics and score it",
                        epilog="needs MuJoCo: pip install -e \".[physics]\"")
    _replay_options(sm, "physics")
    sm.add_argument("--contact", choices=("full", "pads"), default="full",
                    help="collision shapes: full (finger segments, palm, pads; default) or pads "
                         "(only the pad points, the kinematic check's contact model)")
    sm.add_argument("--video", metavar="FILE.mp4",
                    help="write an mp4 of the run: the plan beside the physics")
    sm.add_argument("--html", metavar="FILE",
                    help="write the run's frames as an offline HTML page (play, scrub)")


def _cmd_hand(a: argparse.Namespace) -> int:
    from planner.hand.model import load_hand
    from planner.hand.spec import list_hands

    if a.strength and (a.list or a.urdf):
        from planner.errors import InputError

        raise InputError("--strength cannot be combined with --list or --urdf")
    if a.list:
        from planner.hand.spec import load_hand_spec

        hands = {n: load_hand_spec(n).description for n in list_hands()}
        if a.json:
            print(json.dumps({"command": "hand", "hands": [
                {"name": n, "description": d} for n, d in hands.items()]}))
        else:
            for n, d in hands.items():
                print(f"{n:10s} {d}")
        return 0
    hand = load_hand(a.hand)
    if a.urdf:
        if a.urdf == "-":
            sys.stdout.write(hand.urdf)
        else:
            from planner.output import write_file

            write_file(a.urdf, hand.urdf)
        if a.json:
            print(json.dumps({"command": "hand", "name": hand.name, "urdf": a.urdf,
                              "urdf_sha256": hand.urdf_sha256}))
        return 0
    if a.strength:
        from planner.hand.strength import hand_strength

        st = hand_strength(hand)
        print(json.dumps(st.to_dict()) if a.json else st.summary())
        return 0
    print(json.dumps(hand.to_dict()) if a.json else hand.summary())
    return 0


def _cmd_play(a: argparse.Namespace) -> int:
    from planner.play import play_cli

    return play_cli(a)


def _cmd_catch(a: argparse.Namespace) -> int:
    from planner.catch.summary import catch_cli

    return catch_cli(a)


def _cmd_batch(a: argparse.Namespace) -> int:
    from planner.batch import batch_cli

    return batch_cli(a)


def _cmd_simulate(a: argparse.Namespace) -> int:
    from planner.simulate import simulate_cli

    return simulate_cli(a)


def _cmd_check(a: argparse.Namespace) -> int:
    from planner.check import check_cli

    return check_cli(a)


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
    what = _line(e)[:200]
    limit = _address_space_refused() or "is the address-space limit (ulimit -v) too small?"
    return f"out of memory ({type(e).__name__}{': ' + what if what else ''}); {limit}"


def main(argv: list[str] | None = None) -> int:
    from planner.output import reopen_closed_stdio

    closed = reopen_closed_stdio()  # (a stream the shell closed: /dev/null)
    refused = _address_space_refused()
    if refused:
        sys.stderr.write(f"error: {refused}\n")
        return 2
    args = _build_parser().parse_args(argv)
    from planner.errors import InfeasibleError, InputError, PlannerError

    _follow_signals()
    try:
        _refuse_json_with_stdout(args)
        from planner.output import check_artefacts, refuse_closed_stdout

        refuse_closed_stdout(args, closed)
        check_artefacts(args)  # (every output path, before any planning)
        rc = {"hand": _cmd_hand, "play": _cmd_play, "catch": _cmd_catch, "check": _cmd_check,
              "batch": _cmd_batch, "simulate": _cmd_simulate}[
            args.command
        ](args)
        sys.stdout.flush()
        return rc
    except BrokenPipeError:
        _quiet_stdout()
        return EXIT_BROKEN_PIPE
    except InputError as e:
        sys.stderr.write(f"error: {_line(e)}\n")
        return 2
    except InfeasibleError as e:
        sys.stderr.write(f"infeasible: {_line(e)}\n")
        return 1
    except PlannerError as e:
        sys.stderr.write(f"failed: {_line(e)}\n")
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


if __name__ == "__main__":
    run()

"""Command line (``hand-planner``, or ``python cli.py`` in the repository): parse, call
one API function, map errors to exit codes (``app``); one module a command."""

from planner.cli.app import build_parser, main, run

__all__ = ["build_parser", "main", "run"]

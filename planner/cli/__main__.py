"""``python -m planner.cli``: what the installed ``hand-planner`` runs."""

from planner.cli.app import run

run()

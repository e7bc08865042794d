#!/usr/bin/env python3
"""``python cli.py ...`` from the repository: the same command line as the installed
``hand-planner`` (``planner/cli.py``)."""

import sys

from planner.cli import main

if __name__ == "__main__":
    sys.exit(main())

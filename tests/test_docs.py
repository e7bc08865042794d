"""The user's documents: the README's quick start is what CI runs, every page they link
exists, and they speak to a user (no session logs, commit hashes, issue numbers, paths
outside the repository or people's first names: those are docs/history/'s)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
USER_DOCS = [ROOT / "README.md", ROOT / "docs" / "sources.md",
             *sorted((ROOT / "docs" / "user").glob("*.md")),
             *sorted((ROOT / "docs" / "design").glob("*.md"))]
FIRST_NAMES = ("Noah", "Justin", "David", "Joseph", "Markus", "Tyler", "Jim", "Alex")


def _quick_start() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Quick start\n+```bash\n(.*?)```", text, re.DOTALL).group(1)
    return [c.strip() for line in block.splitlines() for c in line.split("&&")]


def test_ci_runs_the_readme_quick_start():
    """Each of the quick start's commands is a line of .ci/run (which writes the plan
    into a temporary folder, and makes its own virtual environment)."""
    ci = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    commands = _quick_start()
    assert commands[0].startswith("python3 -m venv") and len(commands) == 6, commands
    for c in commands[2:]:
        assert c.replace("twinkle.csv", '"$out/twinkle.csv"') in ci, c


def test_the_readme_is_a_guide():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 150
    for heading in ("## Quick start", "## Commands", "## Python API", "## Read more",
                    "## Licence and citation"):
        assert heading in text
    assert (ROOT / "LICENSE").read_text().lstrip().startswith("Apache License")
    assert 'license = "Apache-2.0"' in (ROOT / "pyproject.toml").read_text()


def test_every_link_of_the_user_docs_exists():
    for page in USER_DOCS:
        for target in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", page.read_text()):
            if "://" not in target:
                assert (page.parent / target).exists(), (page.name, target)


def test_the_user_docs_speak_to_a_user():
    for page in USER_DOCS:
        text = page.read_text(encoding="utf-8")
        for pattern in (r"\.\./shared", r"\bseed 0\d\d\b", r"\bissue \d+", r"\bsession \d+",
                        r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,12}\b",
                        *(rf"\b{n}\b" for n in FIRST_NAMES)):
            found = re.search(pattern, text)
            assert found is None, (page.name, found and found.group(0))


def _help(*args: str) -> str:
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), *args, "--help"],
                       capture_output=True, text=True, check=True, timeout=120)
    return r.stdout


def test_every_command_and_option_is_in_commands_md():
    """What ``--help`` lists, commands.md describes (each option in backquotes)."""
    text = (ROOT / "docs" / "user" / "commands.md").read_text(encoding="utf-8")
    commands = re.search(r"\{([a-z,]+)\}", _help()).group(1).split(",")
    assert len(commands) >= 6
    for name in commands:
        assert f"## {name}" in text, name
        usage = _help(name).split("\n\n")[0]
        for option in set(re.findall(r"\[(--[a-z][a-z0-9-]*)", usage)) - {"--help"}:
            assert re.search(rf"`{option}\b", text), (name, option)

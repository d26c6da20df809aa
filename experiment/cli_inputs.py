"""What the command line's commands share: exit codes, and reading their inputs or exiting 2.

Each ``*_or_exit`` prints what was wrong, naming the file or option and what was expected, and
raises ``SystemExit(2)``: a bad input never ends in a traceback (``app.py``'s contract).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2


def out_folder_or_exit(out: Path) -> Path:
    """``--out`` as a folder this process can write into; exit 2 naming it otherwise."""
    if out.exists() and not out.is_dir():
        print(f"--out {out}: expected a folder, got a file", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        print(f"--out {out}: cannot make the folder: {err.strerror or err}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT) from None
    if not os.access(out, os.W_OK | os.X_OK):
        print(f"--out {out}: expected a folder this user can write into", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)
    return out


def register_leaves_or_none(args: argparse.Namespace) -> list[type] | None:
    """Register the shipped leaves, ``--leaves`` and the installed ``duet.leaves`` entry points;
    the user's leaf classes, or None (the problem on stderr) if one cannot be registered."""
    from planner.user_leaves import LeafSourceError, register_leaves

    try:
        return list(register_leaves(getattr(args, "leaves", None) or ()))
    except LeafSourceError as err:
        print(err, file=sys.stderr)
        return None


def preflight_or_exit(
    world: Any, world_file: str, tree: str | None, main_tree: str | None = None
) -> None:
    """Fail before simulating (exit 2) when the task cannot work: ``validate``'s checks."""
    from experiment.preflight import preflight_problems

    problems = preflight_problems(world, world_file, Path(tree) if tree else None, main_tree)
    if problems:
        print("\n".join(problems), file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def load_world_or_exit(path: str) -> Any:
    """Load a world file; on a bad file print the error and raise SystemExit(2)."""
    from worlds.world_file import WorldFileError, load_world

    try:
        return load_world(path)
    except WorldFileError as err:
        print(err, file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT) from None


__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_FAILURE",
    "EXIT_OK",
    "load_world_or_exit",
    "out_folder_or_exit",
    "preflight_or_exit",
    "register_leaves_or_none",
]

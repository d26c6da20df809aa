"""What a trial record says about the campaign it belongs to, so that results files merge.

A record names its world (``world``: name, ``world_sha256``: a hash of its content as read),
its tree (``tree``: the path relative to the project, or its file name outside it, "" for the
default; ``tree_sha256``: a hash of the file's bytes), its ``seed``, and where it ran
(``backend``, ``host``) and with which code (``code_sha256``: :func:`code_hash`).
:func:`campaign_key` is what changes a trial's outcome: a campaign
owns only the records whose key is its own; others in the same ``results.jsonl`` are kept,
untouched, and ignored. Records written before these fields have no key and are owned by no
campaign, but ``app.py report`` still reads them.
"""

from __future__ import annotations

import functools
import hashlib
import json
from pathlib import Path
from typing import Any

#: The project's folder: trees inside it are named relative to it.
PROJECT = Path(__file__).resolve().parents[1]

#: The fields of a record that say where, when and with which code it ran, not what happened.
RUN_FIELDS = (
    "wall_time_s",
    "physics_wall_s",
    "control_wall_s",
    "watch_wall_s",
    "host",
    "backend",
    "realtime_factor",
    "code_sha256",
)

#: The project's folders whose files make a trial's outcome (the code, the robots' models,
#: the default skills' demonstrations): :func:`code_hash` hashes them.
CODE_FOLDERS = ("affordances", "duet_robot", "experiment", "planner", "skills", "worlds")

#: The fields that make a campaign: records agreeing on all of them are the same campaign's.
KEY_FIELDS = ("world", "world_sha256", "tree", "tree_sha256", "seed", "settings")


def content_hash(data: Any) -> str:
    """SHA-256 of a JSON-ready value in canonical form (sorted keys, no spaces)."""
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def tree_name(tree: Path | None) -> str:
    """How records name a tree: relative to the project when inside it, else its file name
    (``tree_sha256`` tells two of one name apart): a tree given by another path, from
    another folder or another machine, is the same campaign's."""
    if tree is None:
        return ""
    try:
        return tree.resolve().relative_to(PROJECT).as_posix()
    except ValueError:
        return tree.name


def tree_hash(tree: Path | None) -> str:
    """SHA-256 of a tree file's bytes ("" for the default tree, built in code)."""
    return "" if tree is None else hashlib.sha256(tree.read_bytes()).hexdigest()


def campaign_key(
    world_name: str,
    world_data: dict[str, Any],
    tree: Path | None,
    seed: int,
    settings: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The fields every record of one campaign carries (:data:`KEY_FIELDS`).

    Parameters
    ----------
    world_name : str
    world_data : dict
        The world as read (``World.model_dump(mode="json")``); its hash names its content.
    tree : Path, optional
    seed : int
    settings : dict, optional
        Anything else that changes a trial's outcome (e.g. the tree's own leaves).
    """
    return {
        "world": world_name,
        "world_sha256": content_hash(world_data),
        "tree": tree_name(tree),
        "tree_sha256": tree_hash(tree),
        "seed": seed,
        "settings": settings or {},
    }


@functools.cache
def code_hash() -> str:
    """SHA-256 of the code that runs a trial: ``app.py`` and every file under
    :data:`CODE_FOLDERS` (compiled caches aside), each by its path in the project and its
    bytes. Records carry it as ``code_sha256``, so that a campaign resumed after an update
    says which of its records the other code made (it is not part of the campaign's key: a
    comment edited does not make every record to be run again)."""
    digest = hashlib.sha256()
    files = [PROJECT / "app.py"]
    for folder in CODE_FOLDERS:
        files.extend(p for p in (PROJECT / folder).rglob("*") if p.is_file())
    for path in sorted(f for f in files if "__pycache__" not in f.parts and f.exists()):
        digest.update(path.relative_to(PROJECT).as_posix().encode("utf-8") + b"\0")
        digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.hexdigest()


def owned_by(record: dict[str, Any], key: dict[str, Any]) -> bool:
    """Whether ``record`` belongs to the campaign of ``key``."""
    return all(record.get(field) == key[field] for field in KEY_FIELDS)


def group_of(record: dict[str, Any]) -> tuple[str, ...]:
    """A record's campaign for reports: its key where it has one, else what old records
    said (seed and tree)."""
    return tuple(str(record.get(f, "")) for f in KEY_FIELDS)


def outcome(record: dict[str, Any]) -> dict[str, Any]:
    """A record less the fields of where and when it ran (:data:`RUN_FIELDS`)."""
    return {k: v for k, v in record.items() if k not in RUN_FIELDS}

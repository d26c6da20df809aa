"""Enum names a tree's scripts and ``Switch`` cases may use: BT.CPP's ``registerScriptingEnums``.

BT.CPP's host registers them in C++ (``factory.registerScriptingEnums<Color>()``,
``factory.registerScriptingEnum("THE_ANSWER", 42)``); a tree file cannot declare them. In
Duet a ``--leaves`` module (or a ``duet.leaves`` entry point's module) declares them::

    SCRIPT_ENUMS = {"THE_ANSWER": 42}          # names -> integers
    SCRIPT_ENUMS = [Color, {"THE_ANSWER": 42}]  # or enum classes with integer values, or both

and :func:`planner.user_leaves.register_leaves` registers them. A script then reads ``RED``
as its integer (``color := RED``, ``color == BLUE``), an enum name winning over a key of the
same name, and ``Switch case_1="RED"`` matches a variable holding 1. As in BT.CPP, one name
registered twice with two values is an error. The registry is global to the process.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Iterable, Mapping
from typing import Any

__all__ = ["ScriptEnumError", "clear_script_enums", "register_script_enums", "script_enum"]

_ENUMS: dict[str, int] = {}
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class ScriptEnumError(ValueError):
    """Enum declarations that cannot be registered; says which and why."""


def enum_values(declared: Any, label: str) -> dict[str, int]:
    """The names and integers of ``SCRIPT_ENUMS``: a mapping of names to integers, an enum
    class whose members' values are integers, or a list or tuple of those.

    Raises
    ------
    ScriptEnumError
        Naming ``label`` and what was expected, for anything else.
    """
    parts = declared if isinstance(declared, list | tuple) else [declared]
    values: dict[str, int] = {}
    for part in parts:
        items: Iterable[tuple[Any, Any]]
        if isinstance(part, type) and issubclass(part, enum.Enum):
            items = ((m.name, m.value) for m in part)
        elif isinstance(part, Mapping):
            items = part.items()
        else:
            raise ScriptEnumError(
                f"{label}: SCRIPT_ENUMS: expected a dict of names to integers, an enum class "
                f"or a list of those, got {type(part).__name__}"
            )
        for name, value in items:
            if not isinstance(name, str) or _NAME.fullmatch(name) is None:
                raise ScriptEnumError(
                    f"{label}: SCRIPT_ENUMS: expected names a script can write (letters, "
                    f"digits, _), got {name!r}"
                )
            if isinstance(value, bool) or not isinstance(value, int):
                raise ScriptEnumError(
                    f"{label}: SCRIPT_ENUMS: {name}: expected an integer, got {value!r}"
                )
            _agree(values, name, int(value), label)
            values[name] = int(value)
    return values


def _agree(known: Mapping[str, int], name: str, value: int, label: str) -> None:
    if name in known and known[name] != value:
        raise ScriptEnumError(
            f"{label}: SCRIPT_ENUMS: {name}: expected one value, got {known[name]} and {value}"
        )


def register_script_enums(declared: Any, label: str = "SCRIPT_ENUMS") -> dict[str, int]:
    """Register enum names (see :func:`enum_values`) for every tree's scripts; return them.

    Nothing is registered if one of them clashes with a name registered with another value.

    Raises
    ------
    ScriptEnumError
        A declaration of the wrong form, or a clash (naming both values).
    """
    values = enum_values(declared, label)
    for name, value in values.items():
        _agree(_ENUMS, name, value, label)
    _ENUMS.update(values)
    return values


def script_enum(name: str) -> int | None:
    """The integer of a registered enum name, None for any other name."""
    return _ENUMS.get(name)


def clear_script_enums() -> None:
    """Forget every registered name (tests)."""
    _ENUMS.clear()

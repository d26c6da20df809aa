"""World file problems: what went wrong where, and pydantic's errors translated into them.

A :class:`WorldFileError` names the file, the field path, what was expected and what was
received. Validators raise :class:`FieldProblems` (built by :func:`field_problem`) to keep a
field path and that pair; :func:`problems_from` reads them back, with every other pydantic
error, from a ``ValidationError``.
"""

from __future__ import annotations

import types
import typing
from collections.abc import Mapping, Sequence, Sized
from dataclasses import dataclass
from enum import StrEnum
from typing import Annotated, Any

from pydantic import BaseModel, ValidationError
from pydantic.fields import FieldInfo

from affordances.safe_yaml import shown
from worlds.spec import Shape

_MAX_LISTED_PROBLEMS = 20
_MAX_SHOWN_CHARS = 80


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class WorldFileProblem:
    """One problem found in a world file.

    Attributes
    ----------
    field : str or None
        Path of the offending field, e.g. ``objects[0].mass``; None for whole-file problems.
    expected : str
        What the field (or file) should have been.
    received : str
        What was found instead, already formatted for display.
    line : int or None
        1-based line of a YAML/JSON syntax error, else None.
    column : int or None
        1-based column of a YAML/JSON syntax error, else None.
    """

    field: str | None
    expected: str
    received: str
    line: int | None = None
    column: int | None = None

    def format(self, file: str) -> str:
        """Render this problem as one line prefixed by ``file``."""
        if self.line is not None:
            where = f"{file}:{self.line}:{self.column}" if self.column else f"{file}:{self.line}"
            return f"{where}: {self.expected}: {self.received}"
        prefix = f"{file}: {self.field}" if self.field else file
        return f"{prefix}: expected {self.expected}, got {self.received}"


class WorldFileError(ValueError):
    """A world file could not be read or is not a valid world.

    ``str()`` gives one line per problem, each naming the file, the field path, what was
    expected and what was received, e.g.
    ``worlds/x.yaml: objects[0].mass: expected a number greater than 0, got -1.0``; YAML
    syntax errors read ``worlds/x.yaml:12:5: invalid YAML: <problem>``.

    Parameters
    ----------
    file : str
        The world file, as the caller named it.
    problems : sequence of WorldFileProblem
        At least one problem; the attributes below describe the first one.

    Attributes
    ----------
    file : str
        The world file, as the caller named it.
    field : str or None
        Path of the first offending field (``objects[0].mass``), None for whole-file problems.
    line : int or None
        1-based line of a syntax error, else None.
    expected : str
        What the first offending field (or the file) should have been.
    received : str
        What was found instead.
    problems : tuple of WorldFileProblem
        Every problem found (validation reports several at once).
    """

    def __init__(self, file: str, problems: Sequence[WorldFileProblem]) -> None:
        if not problems:
            raise ValueError("WorldFileError: expected at least one problem, got none")
        self.file = file
        self.problems = tuple(problems)
        first = self.problems[0]
        self.field = first.field
        self.line = first.line
        self.expected = first.expected
        self.received = first.received
        lines = [p.format(file) for p in self.problems[:_MAX_LISTED_PROBLEMS]]
        if len(self.problems) > _MAX_LISTED_PROBLEMS:
            lines.append(f"{file}: ... and {len(self.problems) - _MAX_LISTED_PROBLEMS} more")
        super().__init__("\n".join(lines))


@dataclass(frozen=True)
class Issue:
    """A problem found by a validator; ``path`` is relative to where it was raised."""

    path: tuple[str | int, ...]
    expected: str
    received: str


class FieldProblems(ValueError):
    """Raised inside validators so that the error keeps a field path and expected/received.

    pydantic wraps it in a ``value_error`` whose ``ctx["error"]`` is this exception; the
    conversion to :class:`WorldFileError` reads the issues back from there.
    """

    def __init__(self, issues: Sequence[Issue]) -> None:
        self.issues = tuple(issues)
        super().__init__(
            "; ".join(
                f"{format_path(i.path) or '<here>'}: expected {i.expected}, got {i.received}"
                for i in self.issues
            )
        )


def field_problem(expected: str, received: Any, *path: str | int) -> FieldProblems:
    return FieldProblems([Issue(tuple(path), expected, show_value(received))])


def show_value(value: Any) -> str:
    """Format a received value for an error message: a shortened repr, enums as values."""
    if isinstance(value, Shown):
        return value.text
    text = shown(_plain(value))
    if len(text) > _MAX_SHOWN_CHARS:
        text = text[: _MAX_SHOWN_CHARS - 3] + "..."
    if not isinstance(value, str | int | float | bool | type(None) | list | tuple | dict):
        text = f"{text} ({type(value).__name__})"
    return text


def _plain(value: Any, depth: int = 4) -> Any:
    """Enums as their values and tuples as lists, so messages look like the file; only as
    deep and as wide as a message shows (a value may share its parts many times over)."""
    if isinstance(value, StrEnum):
        return value.value
    if isinstance(value, list | tuple):
        if depth == 0:
            return [...]
        return [_plain(item, depth - 1) for item in value[:7]]
    return value


@dataclass(frozen=True)
class Shown:
    """A received value that is already formatted (e.g. a description, not a repr)."""

    text: str


def format_path(path: Sequence[str | int]) -> str:
    text = ""
    for item in path:
        if isinstance(item, int):
            text += f"[{item}]"
        else:
            text += f".{item}" if text else item
    return text


# --------------------------------------------------------------------------------------------
# pydantic errors -> WorldFileError
# --------------------------------------------------------------------------------------------


def _strip_annotated(annotation: Any) -> Any:
    while typing.get_origin(annotation) is Annotated:
        annotation = typing.get_args(annotation)[0]
    return annotation


def _is_model(annotation: Any) -> bool:
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


def _tagged_members(annotation: Any) -> dict[str, type[BaseModel]]:
    """Members of a discriminated union of models, keyed by their ``type`` tag."""
    if typing.get_origin(annotation) not in (typing.Union, types.UnionType):
        return {}
    members: dict[str, type[BaseModel]] = {}
    for arg in typing.get_args(annotation):
        arg = _strip_annotated(arg)
        if _is_model(arg) and "type" in arg.model_fields:
            tag = arg.model_fields["type"].default
            members[str(getattr(tag, "value", tag))] = arg
    return members


def _unwrap_optional(annotation: Any) -> Any:
    """The ``X`` of an optional ``X | None`` (so an unknown key in an optional section lists
    that section's keys); any other annotation as it is."""
    if typing.get_origin(annotation) not in (typing.Union, types.UnionType):
        return annotation
    present = [a for a in typing.get_args(annotation) if a is not type(None)]
    return _strip_annotated(present[0]) if len(present) == 1 else annotation


def _element_type(annotation: Any, index: int) -> Any:
    args = typing.get_args(annotation)
    if typing.get_origin(annotation) is tuple and args:
        if len(args) == 2 and args[1] is Ellipsis:
            return args[0]
        return args[index] if 0 <= index < len(args) else None
    if typing.get_origin(annotation) is list and args:
        return args[0]
    return None


@dataclass(frozen=True)
class _Located:
    path: tuple[str | int, ...]
    parent: type[BaseModel] | None
    field: FieldInfo | None


def _locate(loc: Sequence[str | int], root: type[BaseModel]) -> _Located:
    """Turn a pydantic ``loc`` into a user-facing path, dropping union tags.

    Also returns the model holding the last key and that key's field, if any, so messages
    can list the allowed keys or describe a missing field.
    """
    annotation: Any = root
    path: list[str | int] = []
    parent: type[BaseModel] | None = None
    field: FieldInfo | None = None
    for item in loc:
        annotation = _unwrap_optional(_strip_annotated(annotation))
        if isinstance(item, int):
            path.append(item)
            annotation = _element_type(annotation, item)
            parent, field = None, None
            continue
        members = _tagged_members(annotation)
        if item in members:
            annotation = members[item]
            continue
        path.append(item)
        if _is_model(annotation):
            parent = annotation
            field = annotation.model_fields.get(item)
            annotation = field.annotation if field is not None else None
        else:
            parent, field, annotation = None, None, None
    return _Located(tuple(path), parent, field)


_EXPECTED_BY_TYPE = {
    "float_type": "a number",
    "float_parsing": "a number",
    "int_type": "a whole number",
    "int_parsing": "a whole number",
    "int_from_float": "a whole number",
    "string_type": "text",
    "bool_type": "true or false",
    "tuple_type": "a list",
    "list_type": "a list",
    "dict_type": "a mapping of keys to values",
    "model_type": "a mapping of keys to values",
    "model_attributes_type": "a mapping of keys to values",
    "finite_number": "a finite number",
}


def problems_from(error: ValidationError, root: type[BaseModel]) -> list[WorldFileProblem]:
    """Translate every pydantic error of validating ``root`` into a :class:`WorldFileProblem`."""
    problems: list[WorldFileProblem] = []
    errors = error.errors()
    for err in errors:
        if err["type"] == "too_short" and any(
            len(other["loc"]) > len(err["loc"]) and other["loc"][: len(err["loc"])] == err["loc"]
            for other in errors
        ):
            continue  # pydantic also reports a tuple as too short when one of its items fails
        located = _locate(err["loc"], root)
        kind = err["type"]
        ctx = err.get("ctx") or {}
        value = err.get("input")
        cause = ctx.get("error")
        if isinstance(cause, FieldProblems):
            for issue in cause.issues:
                where = format_path(located.path + issue.path) or None
                problems.append(WorldFileProblem(where, issue.expected, issue.received))
            continue
        path = located.path
        if kind == "missing":
            what = located.field.description if located.field is not None else None
            expected = f"a value ({what})" if what else "a value"
            received = "nothing (the key is missing)"
        elif kind == "extra_forbidden":
            allowed = ", ".join(located.parent.model_fields) if located.parent else "none"
            expected = f"only the keys {allowed}"
            received = f"unknown key {path[-1]!r}" if path else show_value(value)
        elif kind in ("union_tag_invalid", "union_tag_not_found"):
            path = (*path, "type")
            tags = ", ".join(repr(t.value) for t in Shape)
            expected = f"a shape type, one of {tags}"
            received = show_value(ctx["tag"]) if "tag" in ctx else "nothing (the key is missing)"
        elif kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
            relation = {
                "greater_than": ("gt", "greater than"),
                "greater_than_equal": ("ge", "greater than or equal to"),
                "less_than": ("lt", "less than"),
                "less_than_equal": ("le", "less than or equal to"),
            }[kind]
            expected = f"a number {relation[1]} {_number(ctx.get(relation[0]))}"
            received = show_value(value)
        elif kind in ("too_short", "too_long", "string_too_short", "string_too_long"):
            expected, received = _length_problem(kind, ctx, value)
        elif kind == "invalid_key":
            path = path[:-1]
            expected = "text keys"
            received = f"key {show_value(err['loc'][-1])}"
        elif kind in ("enum", "literal_error"):
            expected = f"one of {ctx.get('expected')}"
            received = show_value(value)
        elif kind in _EXPECTED_BY_TYPE:
            expected = _EXPECTED_BY_TYPE[kind]
            received = show_value(value)
        else:
            message = str(err.get("msg", kind))
            expected = message.removeprefix("Input should be ").removeprefix("Value error, ")
            received = show_value(value)
        problems.append(WorldFileProblem(format_path(path) or None, expected, received))
    return problems


def _number(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _length_problem(kind: str, ctx: Mapping[str, Any], value: Any) -> tuple[str, str]:
    is_text = kind.startswith("string")
    if kind.endswith("short"):
        least = ctx.get("min_length")
        expected = f"non-empty text (at least {least} character)" if is_text else None
        expected = expected or f"a list with at least {least} item{'s' if least != 1 else ''}"
    else:
        most = ctx.get("max_length")
        expected = f"at most {most} {'characters' if is_text else 'items'}"
    if is_text:
        return expected, show_value(value)
    count = ctx.get("actual_length")
    count = len(value) if count is None and isinstance(value, Sized) else count
    return expected, f"{count} item{'s' if count != 1 else ''}"

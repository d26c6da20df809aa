"""What a tree file's tags and attributes may name: the registry of leaves, their constructor
parameters and ports, and whether an attribute's text is a blackboard key or a literal of the
port's type."""

from __future__ import annotations

import enum
import functools
import inspect
import math
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, get_args, get_origin

import py_trees
from py_trees.ports import PortsMixin, get_ports_registry
from py_trees.ports_utils import convert_str_to_type

from planner.bt_controls import BUILTIN_CONTROLS
from planner.bt_decorators import BUILTIN_DECORATORS
from planner.bt_leaves import BUILTIN_LEAVES
from planner.bt_loops import BUILTIN_LOOPS
from planner.bt_scripting import BUILTIN_SCRIPT_NODES
from planner.bt_switch import BUILTIN_SWITCHES
from planner.bt_updated import BUILTIN_UPDATED
from planner.decorators import SimTimeout

#: Registry entries: a :class:`~py_trees.ports.PortsMixin` class or a ``functools.partial`` of one.
Registry = Mapping[str, Any]
#: Constructor parameters the parser fills itself, never from an attribute.
IMPLICIT_PARAMS = frozenset({"self", "name", "child", "children", "behaviour_class_name"})


def effective_registry(registry: Registry | None = None) -> dict[str, Any]:
    """Return the tag -> class mapping the loader builds with.

    ``registry`` (default: py_trees' global ports registry, i.e. every imported concrete
    ports-enabled behaviour) plus ``Timeout`` -> :class:`~planner.decorators.SimTimeout`
    and BT.CPP's built-in nodes (:func:`builtin_nodes`), unless ``registry`` defines its own.
    """
    reg = dict(get_ports_registry() if registry is None else registry)
    reg.setdefault("Timeout", SimTimeout)
    for tag, cls in builtin_nodes().items():
        reg.setdefault(tag, cls)
    return reg


def builtin_nodes() -> dict[str, Any]:
    """BT.CPP's built-in nodes that py_trees lacks, by tag (:mod:`planner.bt_leaves`,
    :mod:`planner.bt_controls`, :mod:`planner.bt_decorators`, :mod:`planner.bt_switch`,
    :mod:`planner.bt_scripting`, :mod:`planner.bt_loops`, :mod:`planner.bt_updated`)."""
    return {
        **BUILTIN_LEAVES,
        **BUILTIN_CONTROLS,
        **BUILTIN_DECORATORS,
        **BUILTIN_SWITCHES,
        **BUILTIN_SCRIPT_NODES,
        **BUILTIN_LOOPS,
        **BUILTIN_UPDATED,
    }


def registry_class(entry: Any) -> type | None:
    """Return the class behind a registry entry (a class or a ``functools.partial`` of one)."""
    if isinstance(entry, functools.partial):
        entry = entry.func
    return entry if inspect.isclass(entry) else None


@dataclass(frozen=True)
class _Param:
    annotation: Any
    required: bool


def constructor_params(entry: Any) -> dict[str, _Param]:
    """Named constructor parameters an XML attribute may set, most-derived class first.

    Parameters the parser fills itself (``name``, ``child``...) and ``*args``/``**kwargs`` are
    left out; those bound by a ``functools.partial`` registry entry are not required.
    """
    bound = set(entry.keywords) if isinstance(entry, functools.partial) else set()
    cls = registry_class(entry)
    params: dict[str, _Param] = {}
    if cls is None:
        return params
    for klass in cls.__mro__:
        if klass in (py_trees.behaviour.Behaviour, PortsMixin, object):
            continue
        if "__init__" not in vars(klass):
            continue
        try:
            signature = inspect.signature(vars(klass)["__init__"])
        except (TypeError, ValueError):
            continue
        for pname, param in signature.parameters.items():
            if pname in IMPLICIT_PARAMS or pname in params:
                continue
            if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
                continue
            annotation = None if param.annotation is param.empty else param.annotation
            if isinstance(annotation, str):
                annotation = _resolve_annotation(klass, pname)
            required = param.default is param.empty and pname not in bound
            params[pname] = _Param(annotation, required)
    return params


def _resolve_annotation(klass: type, pname: str) -> Any:
    try:
        return typing.get_type_hints(vars(klass)["__init__"]).get(pname)
    except Exception:  # an unresolvable string annotation just means "no conversion check"
        return None


def type_name(tp: Any) -> str:
    """Short readable name of a port type: ``float``, ``list[float]``, ``numpy.ndarray``."""
    if get_origin(tp) is not None:
        return str(tp).replace("typing.", "")
    if inspect.isclass(tp):
        if tp.__module__ == "builtins":
            return tp.__name__
        return f"{tp.__module__}.{tp.__qualname__}"
    return str(tp)


#: Largest magnitude a number written in a tree may have: far beyond any port's meaning.
LIMIT = 1e6


def literal_problem(value: str, data_type: Any, port: str = "") -> str | None:
    """Return why ``value`` does not convert to ``data_type`` as the parser does, or None.

    Uses py_trees' own conversion (the one ``setup_ports`` applies), plus a length check for
    fixed-length tuples, which py_trees converts without checking. Numbers must be finite and
    within :data:`LIMIT`; by the project's naming, a port ending in ``_s`` (a duration) must be
    greater than 0 and one ending in ``_m`` or ``_n`` (a distance, a force) at least 0.
    """
    if data_type is None or data_type is str or data_type is Any or data_type is object:
        return None
    if data_type in (int, float):
        return _number_problem(value, data_type, port)
    expected = type_name(data_type)
    try:
        ok, converted = convert_str_to_type(value, data_type)
    except (ValueError, TypeError, KeyError):
        return f"cannot convert '{value}' to {expected}"
    if not ok:
        if not _literal_convertible(data_type):
            return (
                f"a {expected} cannot be written as a literal; pass it through a blackboard "
                "key such as {name}"
            )
        return f"cannot convert '{value}' to {expected}"
    if get_origin(data_type) is tuple:
        args = get_args(data_type)
        if args and Ellipsis not in args and len(converted) != len(args):
            return f"expected {len(args)} comma-separated values for {expected}, got '{value}'"
    return None


def _number_problem(value: str, data_type: type, port: str) -> str | None:
    text = value.strip()
    if len(text) > 40:
        return (
            f"expected a {data_type.__name__} within {LIMIT:g}, got a {len(text)}-character value"
        )
    try:
        number = data_type(text)
    except (ValueError, OverflowError):
        return f"cannot convert '{value}' to {data_type.__name__}"
    if not math.isfinite(number) or abs(number) > LIMIT:
        return f"expected a finite {data_type.__name__} within {LIMIT:g}, got '{value}'"
    if port.endswith("_s") and number <= 0:
        return f"expected a duration greater than 0 s, got '{value}'"
    if port.endswith(("_m", "_n")) and number < 0:
        return f"expected a value of at least 0, got '{value}'"
    return None


def _literal_convertible(tp: Any) -> bool:
    origin = get_origin(tp)
    if origin in (list, tuple):
        return all(_literal_convertible(a) for a in get_args(tp) if a is not Ellipsis)
    if origin is not None:
        return any(_literal_convertible(a) for a in get_args(tp) if a is not type(None))
    return tp in (str, int, float, bool) or (inspect.isclass(tp) and issubclass(tp, enum.Enum))


def key_problem(value: str) -> tuple[bool, str | None]:
    """Return (is_key, problem) for an attribute value; ``{name}`` is a blackboard key."""
    opens, closes = value.count("{"), value.count("}")
    if opens == 0 and closes == 0:
        return False, None
    if (
        opens == 1
        and closes == 1
        and value.startswith("{")
        and value.endswith("}")
        and len(value) > 2
    ):
        return True, None
    return True, f"malformed blackboard key '{value}'; expected {{name}} or a literal"


def one_of(names: list[str] | set[str]) -> str:
    """Sorted, comma-separated names for messages (``none`` when empty)."""
    return ", ".join(sorted(names)) if names else "none"

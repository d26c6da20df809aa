"""What a key name means inside one ``<SubTree>`` instance, as py_trees' XML parser resolves it.

Each instance has a namespace (``/first_object``) and a table of the ports its ``<SubTree>``
element (or its ``<BehaviorTree>``'s defaults) gives: ``port="{parent_key}"`` binds the
port to the caller's key, ``port="literal"`` to that constant; any other name is the
instance's own ``<namespace>/name``, and ``@name`` the root's ``/name``. The validator's
dataflow (:mod:`planner.tree_dataflow`) and the scripts at run time
(:mod:`planner.bt_scripting`) both resolve names with :func:`resolve`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass

__all__ = ["Binding", "bound_key", "resolve", "subtree_bindings"]


@dataclass(frozen=True)
class Binding:
    """What a key name means in one subtree instance: an absolute key or a constant."""

    key: str | None  # absolute blackboard key, e.g. "/first_object/state"
    literal: str | None  # the constant a <SubTree> port was given
    origin: ET.Element | None = None  # where the constant was written


def bound_key(value: str) -> str | None:
    """``name`` for an attribute value ``{name}``; None for a literal or a malformed key."""
    if (
        len(value) > 2
        and value.startswith("{")
        and value.endswith("}")
        and value.count("{") == 1
        and value.count("}") == 1
    ):
        return value[1:-1]
    return None


def resolve(name: str, namespace: str, remap: Mapping[str, Binding]) -> Binding:
    """The binding of ``name`` in the instance at ``namespace`` with the table ``remap``."""
    if name.startswith("@"):  # BT.CPP: the root blackboard
        return Binding("/" + name[1:], None)
    return remap.get(name) or Binding(namespace.rstrip("/") + "/" + name, None)


def subtree_bindings(
    call: ET.Element, tree: ET.Element, namespace: str, remap: Mapping[str, Binding]
) -> dict[str, Binding]:
    """The table of the instance a ``<SubTree>`` ``call`` makes of ``tree``, from a caller at
    ``namespace`` with the table ``remap``: the call's ports, else the tree's defaults."""
    inner: dict[str, Binding] = {}
    for port, value in {**tree.attrib, **call.attrib}.items():
        if port in ("ID", "name") or port.startswith("_"):
            continue
        name = bound_key(value)
        inner[port] = (
            resolve(name, namespace, remap) if name is not None else Binding(None, value, call)
        )
    return inner

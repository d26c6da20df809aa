"""Wire a ports-enabled behaviour in code the way the XML loader wires it from attributes.

``wire(leaf, object="parcel", from_state="{state}")``: a value in braces names a blackboard key
(relative to ``namespace``), anything else is a constant converted to the port's type, exactly
as an XML attribute would be.
"""

from __future__ import annotations

import numbers
from typing import Any

from py_trees.ports import CONST_PREFIX, DOT_REPLACEMENT, PortsMixin


def wire(behaviour: PortsMixin, namespace: str = "/", /, **ports: Any) -> PortsMixin:
    """Set up ``behaviour``'s ports; returns it for chaining.

    Raises
    ------
    KeyError
        For a port the behaviour does not declare, or a required input port (one without a
        default) left out: names the behaviour and the port.
    """
    known = set(behaviour.input_ports()) | set(behaviour.output_ports())
    missing = [
        f"'{port}'"
        for port, info in behaviour.input_ports().items()
        if info.required and not info.has_default and port not in ports
    ]
    if missing:
        # As a tree file's element without it is refused, not a NoDataAvailable at the first
        # tick naming a uuid-made key.
        raise KeyError(
            f"{type(behaviour).__name__} {behaviour.name!r}: missing required input port"
            f"{'s' if len(missing) > 1 else ''} {', '.join(missing)}"
        )
    remap: dict[str, str] = {}
    for port, value in ports.items():
        if port not in known:
            raise KeyError(
                f"{type(behaviour).__name__} {behaviour.name!r}: unknown port {port!r}; "
                f"expected one of {', '.join(sorted(known))}"
            )
        if not isinstance(value, str | numbers.Real):
            raise TypeError(
                f"{type(behaviour).__name__} {behaviour.name!r}: port {port!r}: expected a "
                f"constant as a tree's attribute writes it (text, a number or a bool) or a "
                f"blackboard key such as '{{{port}}}', got a {type(value).__name__}: put it on "
                "the blackboard and pass its key"
            )
        text = str(value)
        if text.startswith("{") and text.endswith("}"):
            remap[port] = text[1:-1]
        else:
            remap[port] = CONST_PREFIX + text.replace(".", DOT_REPLACEMENT)
    try:
        behaviour.setup_ports(port_remappings=remap, subtree_namespace=namespace)
    except ValueError as err:  # a constant the port's type cannot take
        said = str(err)
        ports_named = [p for p, v in ports.items() if f"'{v}'" in said] or sorted(ports)
        raise ValueError(
            f"{type(behaviour).__name__} {behaviour.name!r}: port "
            f"{', '.join(repr(p) for p in ports_named)}: {said}"
        ) from err
    return behaviour

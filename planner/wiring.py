"""Wire a ports-enabled behaviour in code the way the XML loader wires it from attributes.

``wire(leaf, object="parcel", from_state="{state}")``: a value in braces names a blackboard key
(relative to ``namespace``), anything else is a constant converted to the port's type, exactly
as an XML attribute would be.
"""

from __future__ import annotations

from typing import Any

from py_trees.ports import CONST_PREFIX, DOT_REPLACEMENT, PortsMixin


def wire(behaviour: PortsMixin, namespace: str = "/", /, **ports: Any) -> PortsMixin:
    """Set up ``behaviour``'s ports; returns it for chaining.

    Raises
    ------
    KeyError
        For a port the behaviour does not declare (names the behaviour and the port).
    """
    known = set(behaviour.input_ports()) | set(behaviour.output_ports())
    remap: dict[str, str] = {}
    for port, value in ports.items():
        if port not in known:
            raise KeyError(
                f"{type(behaviour).__name__} {behaviour.name!r}: unknown port {port!r}; "
                f"expected one of {', '.join(sorted(known))}"
            )
        text = str(value)
        if text.startswith("{") and text.endswith("}"):
            remap[port] = text[1:-1]
        else:
            remap[port] = CONST_PREFIX + text.replace(".", DOT_REPLACEMENT)
    behaviour.setup_ports(port_remappings=remap, subtree_namespace=namespace)
    return behaviour

"""BehaviorTree.CPP v4's ``LoopInt``, ``LoopDouble``, ``LoopString`` and ``LoopBool``.

When entered, the node takes its queue: a literal ``queue="1;2;3"`` (copied at each entry), or
a ``{key}`` holding a list (shared and consumed, as BT.CPP's ``SharedQueue``) or such a string.
Each time its child is not running it pops the next value into ``value`` and ticks the child:
a FAILURE of the child is the node's FAILURE, otherwise it is RUNNING; once the queue is empty
it returns ``if_empty`` (SUCCESS, FAILURE or RUNNING; default SUCCESS) without ticking.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.bt_leaves import StringPorts

__all__ = ["BUILTIN_LOOPS", "loop_class"]

Behaviour = py_trees.behaviour.Behaviour


def _convert(text: str, kind: type) -> Any:
    text = text.strip()
    if kind is bool:
        if text.lower() in ("true", "1"):
            return True
        if text.lower() in ("false", "0"):
            return False
        raise ValueError(f"expected true or false, got {text!r}")
    return kind(text)


class _Loop(StringPorts, py_trees.decorators.Decorator, register=False):
    kind: type = str

    def __init__(self, name: str, child: Behaviour, **kwargs: Any) -> None:
        super().__init__(name=name, child=child, **kwargs)
        self.queue: list[Any] = []

    def take_queue(self) -> list[Any]:
        """The queue for this entry: a shared list is consumed, a string parsed afresh."""
        raw = self.blackboard_client.get("queue")
        if isinstance(raw, list):
            return raw
        parts = [p for p in str(raw).split(";") if p.strip()]
        return [_convert(p, self.kind) for p in parts]

    def tick(self) -> Iterator[Behaviour]:
        """Pop a value and tick the child; ``if_empty`` when there is none."""
        if self.status != Status.RUNNING:
            try:
                self.queue = self.take_queue()
            except ValueError as exc:
                self.feedback_message = f"queue: {exc}"
                self.status = Status.FAILURE
                yield self
                return
        if self.decorated.status != Status.RUNNING:
            if not self.queue:
                empty = str(self.get_input("if_empty")).strip().upper()
                self.status = (
                    Status[empty]
                    if empty in ("SUCCESS", "FAILURE", "RUNNING")
                    else (Status.FAILURE)
                )
                yield self
                return
            self._set_output("value", self.queue.pop(0))
        yield from self.decorated.tick()
        status = Status.FAILURE if self.decorated.status == Status.FAILURE else Status.RUNNING
        if status == Status.FAILURE:
            self.stop(status)
        self.status = status
        yield self

    def update(self) -> Status:
        """Unused: :meth:`tick` decides."""
        return self.status


def loop_class(tag: str, kind: type) -> type[_Loop]:
    """The ``Loop<Type>`` class."""
    ports = {
        "queue": PortInformation(data_type=str, required=True, description="a;b;c or {key}"),
        "if_empty": PortInformation(data_type=str, default_value="SUCCESS", description="status"),
    }
    outputs = {"value": PortInformation(data_type=kind, required=False, description="popped")}
    return type(
        tag,
        (_Loop,),
        {"INPUT_PORTS": ports, "OUTPUT_PORTS": outputs, "kind": kind, "__doc__": __doc__},
        register=False,
    )


#: BT.CPP tag -> class.
BUILTIN_LOOPS: dict[str, type[Behaviour]] = {
    tag: loop_class(tag, kind)
    for tag, kind in (
        ("LoopInt", int),
        ("LoopDouble", float),
        ("LoopString", str),
        ("LoopBool", bool),
    )
}

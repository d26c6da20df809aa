"""BehaviorTree.CPP v4's ``Switch2``..``Switch6`` and ``AsyncSequence``/``AsyncFallback``.

``SwitchN`` has N+1 children: the child of the first ``case_i`` equal to ``variable`` is
ticked, the last child when none is (the default). Values compare as numbers when both parse
as numbers (an enum name registered by the host, :mod:`planner.script_enums`, as its
integer), else as text. When the choice changes, the child running before is halted.

``AsyncSequence`` is BT.CPP's Sequence (memory while running) that returns RUNNING after each
child's success instead of ticking the next child in the same tick; ``AsyncFallback`` the same
after each failure.
"""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.bt_controls import Control, Step, halt
from planner.script_enums import script_enum

__all__ = ["BUILTIN_SWITCHES", "AsyncFallback", "AsyncSequence", "switch_class"]


def same_value(a: Any, b: Any) -> bool:
    """BT.CPP's switch comparison: as numbers when both are numbers (a registered enum name,
    :mod:`planner.script_enums`, being its integer), else as text."""
    if str(a) == str(b):
        return True
    try:
        return _number(a) == _number(b)
    except (TypeError, ValueError):
        return False


def _number(value: Any) -> float:
    enum = script_enum(value) if isinstance(value, str) else None
    return float(enum if enum is not None else value)


class _Switch(Control, register=False):
    cases = 0

    def __init__(
        self, name: str, children: list[py_trees.behaviour.Behaviour] | None = None, **kw: Any
    ):
        super().__init__(name=name, children=children, **kw)
        self.running: int | None = None

    def choice(self) -> int:
        """Index of the child the variable selects (the last one by default)."""
        # Any type on the blackboard (BT.CPP compares strings, numbers, enums): read it raw.
        value = self.blackboard_client.get("variable")
        for i in range(self.cases):
            case = self.get_input(f"case_{i + 1}")
            if case is not None and same_value(value, case):
                return i
        return self.cases

    def step(self) -> Step:
        """Halt the child no longer chosen, tick the chosen one."""
        index = self.choice()
        if self.running is not None and self.running != index:
            halt(self.children[self.running])
        status = yield from self.tick_child(index)
        self.running = index if status == Status.RUNNING else None
        return status

    def reset(self) -> None:
        """No child is running."""
        self.running = None


def switch_class(cases: int) -> type[_Switch]:
    """The ``Switch<cases>`` class: ports ``variable`` and ``case_1``..``case_<cases>``."""
    ports = {"variable": PortInformation(data_type=str, required=True, description="value")}
    for i in range(1, cases + 1):
        ports[f"case_{i}"] = PortInformation(data_type=str, required=True, description="case")
    return type(
        f"Switch{cases}",
        (_Switch,),
        {"INPUT_PORTS": ports, "OUTPUT_PORTS": {}, "cases": cases, "__doc__": _Switch.__doc__},
        register=False,
    )


class AsyncSequence(Control, register=False):
    """A Sequence that gives the tick back (RUNNING) after each child that succeeds."""

    YIELD_ON = Status.SUCCESS

    def __init__(
        self, name: str, children: list[py_trees.behaviour.Behaviour] | None = None, **kw: Any
    ):
        super().__init__(name=name, children=children, **kw)
        self.index = 0

    def step(self) -> Step:
        """Tick the current child; move on one child per tick."""
        status = yield from self.tick_child(self.index)
        if status != self.YIELD_ON:
            return status
        self.index += 1
        return self.YIELD_ON if self.index == len(self.children) else Status.RUNNING

    def reset(self) -> None:
        """Start from the first child."""
        self.index = 0


class AsyncFallback(AsyncSequence, register=False):
    """A Fallback that gives the tick back (RUNNING) after each child that fails."""

    YIELD_ON = Status.FAILURE


#: BT.CPP tag -> class.
BUILTIN_SWITCHES: dict[str, type[Control]] = {
    **{f"Switch{n}": switch_class(n) for n in range(2, 7)},
    "AsyncSequence": AsyncSequence,
    "AsyncFallback": AsyncFallback,
}
#: Children each Switch takes: its cases and the default.
SWITCH_CHILD_COUNTS = {f"Switch{n}": (n + 1, n + 1) for n in range(2, 7)}

"""BehaviorTree.CPP v4's built-in leaves: AlwaysSuccess, AlwaysFailure, Sleep (on simulated
time), SetBlackboard and UnsetBlackboard.

They are ports-enabled so that the tree reader checks their attributes like any leaf's; they
are not in py_trees' global registry (``register=False``) but in :data:`BUILTIN_LEAVES`, which
:func:`planner.tree_ports.effective_registry` adds under each BT.CPP tag.
"""

from __future__ import annotations

import time
from typing import Any

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin
from py_trees.ports_utils import convert_str_to_type

from planner.decorators import Clock, clock_from_setup
from planner.tree_problems import PortValueError

__all__ = [
    "BUILTIN_LEAVES",
    "AlwaysFailure",
    "AlwaysSuccess",
    "SetBlackboard",
    "Sleep",
    "StringPorts",
]


class StringPorts(PortsMixin, register=False):
    """Ports that, as BT.CPP's, convert what is on the blackboard to the port's type when read:
    a string (``SetBlackboard value="100"`` feeding ``Sleep msec="{t}"``), and a number of the
    other kind (a script's ``t := 1000 / 4`` is 250.0, as BT.CPP's scripts make every number a
    double; an integer port takes it where it is a whole number)."""

    def get_input(self, port_name: str, default: Any = None) -> Any:
        """As :meth:`PortsMixin.get_input`, a string or a number converted to the port's type.

        Raises
        ------
        PortValueError
            If the value cannot be: it names the node, the port, the value and the type.
        """
        try:
            return super().get_input(port_name, default)
        except TypeError:
            raw = self.blackboard_client.get(port_name)
            data_type = self.input_ports()[port_name].data_type
            ok, value = _converted(raw, data_type)
            if not ok:
                kind = "" if isinstance(raw, str) else f" ({type(raw).__name__})"
                raise PortValueError(
                    f"{self.name}: port '{port_name}': cannot convert {raw!r}{kind} to "
                    f"{getattr(data_type, '__name__', data_type)}"
                ) from None
            return value


def _converted(raw: Any, data_type: Any) -> tuple[bool, Any]:
    """``raw`` as ``data_type`` the way BT.CPP converts a port's entry: a string parsed, an
    integral float to an integer, an integer to a float; (False, None) where it cannot be."""
    if isinstance(raw, str):
        try:
            return convert_str_to_type(raw, data_type)
        except ValueError:  # py_trees raises for some types where it answers for others
            return False, None
    if isinstance(raw, bool) or not isinstance(raw, int | float):
        return False, None
    if data_type is int and float(raw).is_integer():
        return True, int(raw)
    if data_type is float:
        return True, float(raw)
    return False, None


class AlwaysSuccess(PortsMixin, py_trees.behaviour.Behaviour, register=False):
    """Return SUCCESS at every tick (BT.CPP ``AlwaysSuccess``)."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        """SUCCESS."""
        return Status.SUCCESS


class AlwaysFailure(PortsMixin, py_trees.behaviour.Behaviour, register=False):
    """Return FAILURE at every tick (BT.CPP ``AlwaysFailure``)."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        """FAILURE."""
        return Status.FAILURE


class Sleep(StringPorts, py_trees.behaviour.Behaviour, register=False):
    """RUNNING until ``msec`` simulated milliseconds have passed since it was entered, then
    SUCCESS (BT.CPP ``Sleep``); ``msec`` <= 0 succeeds at once. A halt restarts the wait.

    The clock is the one given to ``setup(clock=...)`` (see :class:`planner.decorators.SimTimeout`).
    """

    INPUT_PORTS = {
        "msec": PortInformation(data_type=int, required=True, description="time to wait, ms"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.clock: Clock = time.monotonic
        self.start_time = 0.0

    def setup(self, **kwargs: Any) -> None:
        """Take the simulated clock from ``clock=``."""
        self.clock = clock_from_setup(self.name, kwargs, self.clock)

    def initialise(self) -> None:
        """Start the wait."""
        self.start_time = float(self.clock())

    def update(self) -> Status:
        """SUCCESS once the time has passed, else RUNNING."""
        msec = int(self.get_input("msec"))
        elapsed_ms = (float(self.clock()) - self.start_time) * 1000.0
        if msec <= 0 or elapsed_ms >= msec - 1e-9:
            self.feedback_message = f"slept {elapsed_ms:.0f} ms"
            return Status.SUCCESS
        self.feedback_message = f"{msec - elapsed_ms:.0f} ms left"
        return Status.RUNNING


class SetBlackboard(PortsMixin, py_trees.behaviour.Behaviour, register=False):
    """Write ``value`` (a literal, or the value of another ``{key}``) to ``output_key``; SUCCESS.

    BT.CPP writes the key named by ``output_key`` (``output_key="answer"``); the reader turns a
    bare name into ``{answer}``, so both spellings write the same key.
    """

    INPUT_PORTS = {
        "value": PortInformation(data_type=str, required=True, description="value to write"),
    }
    OUTPUT_PORTS = {
        "output_key": PortInformation(data_type=object, required=True, description="key written"),
    }
    #: Output ports a tree must connect (most leaves may leave theirs unconnected).
    REQUIRED_OUTPUTS = ("output_key",)

    def update(self) -> Status:
        """Copy the value and succeed."""
        self._set_output("output_key", self._value())
        return Status.SUCCESS

    def _value(self) -> Any:
        """The literal, or the entry of ``value="{key}"`` whatever its type: BT.CPP copies the
        "type and content" of the key (a script's number stays a number)."""
        try:
            return self.get_input("value")
        except TypeError:
            return self.blackboard_client.get("value")


class UnsetBlackboard(PortsMixin, py_trees.behaviour.Behaviour, register=False):
    """Remove the entry named by ``key`` from the blackboard (if there is one); SUCCESS."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS = {
        "key": PortInformation(data_type=object, required=True, description="key removed"),
    }

    def update(self) -> Status:
        """Unset the key and succeed."""
        self.blackboard_client.unset("key")
        return Status.SUCCESS


#: BT.CPP tag -> leaf class.
BUILTIN_LEAVES: dict[str, type[py_trees.behaviour.Behaviour]] = {
    "AlwaysSuccess": AlwaysSuccess,
    "AlwaysFailure": AlwaysFailure,
    "Sleep": Sleep,
    "SetBlackboard": SetBlackboard,
    "UnsetBlackboard": UnsetBlackboard,
}

"""Ports-enabled stub leaves for the tree tooling tests.

Importing this module registers them in py_trees' global ports registry under their class
names; every name starts with ``Stub`` so none can shadow a robot leaf.
"""

from __future__ import annotations

from typing import Any, ClassVar

from py_trees.common import Status
from py_trees.ports import BehaviourWithPorts, PortInformation


class StubCounter(BehaviourWithPorts):
    """Run for ``ticks`` ticks, then succeed; writes how many ticks it has run."""

    NODE_TYPE: ClassVar[str] = "Action"
    INPUT_PORTS = {
        "ticks": PortInformation(data_type=int, required=True, description="ticks to run"),
    }
    OUTPUT_PORTS = {
        "count": PortInformation(data_type=int, required=False, description="ticks so far"),
    }

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.count = 0

    def initialise(self) -> None:
        self.count = 0

    def update(self) -> Status:
        self.count += 1
        self._set_output("count", self.count)
        if self.count >= self.get_input("ticks"):
            self.feedback_message = f"done after {self.count} ticks"
            return Status.SUCCESS
        self.feedback_message = f"tick {self.count}"
        return Status.RUNNING


class StubCheck(BehaviourWithPorts):
    """Succeed when the ``value`` port is true, fail otherwise."""

    NODE_TYPE: ClassVar[str] = "Condition"
    INPUT_PORTS = {"value": PortInformation(data_type=bool, required=True, description="flag")}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        return Status.SUCCESS if self.get_input("value") else Status.FAILURE


class StubForever(BehaviourWithPorts):
    """Keep running until halted."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.halts = 0

    def update(self) -> Status:
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            self.halts += 1


class StubFlaky(BehaviourWithPorts):
    """Fail the first ``failures`` attempts, then run for ``ticks`` ticks and succeed."""

    NODE_TYPE: ClassVar[str] = "Action"
    INPUT_PORTS = {
        "failures": PortInformation(data_type=int, default_value=1, description="attempts to fail"),
        "ticks": PortInformation(data_type=int, default_value=1, description="ticks once working"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.attempts = 0
        self.ticks = 0

    def initialise(self) -> None:
        self.attempts += 1
        self.ticks = 0

    def update(self) -> Status:
        if self.attempts <= self.get_input("failures"):
            self.feedback_message = f"attempt {self.attempts} failed"
            return Status.FAILURE
        self.ticks += 1
        return Status.SUCCESS if self.ticks >= self.get_input("ticks") else Status.RUNNING


class StubGrasp(BehaviourWithPorts):
    """Pretend to squeeze an object; succeeds at once."""

    NODE_TYPE: ClassVar[str] = "Action"
    INPUT_PORTS = {
        "force_n": PortInformation(data_type=float, required=True, description="squeeze, N"),
        "timeout_s": PortInformation(data_type=float, default_value=1.0, description="s"),
    }
    OUTPUT_PORTS = {
        "holding": PortInformation(data_type=bool, required=False, description="grip closed"),
    }

    def update(self) -> Status:
        self._set_output("holding", self.get_input("force_n") > 0.0)
        return Status.SUCCESS


class StubAt(BehaviourWithPorts):
    """Write a position read from a list port."""

    NODE_TYPE: ClassVar[str] = "Action"
    INPUT_PORTS = {
        "position": PortInformation(data_type=list[float], required=True, description="xyz, m"),
    }
    OUTPUT_PORTS = {"echo": PortInformation(data_type=list[float], required=False)}

    def update(self) -> Status:
        self._set_output("echo", list(self.get_input("position")))
        return Status.SUCCESS


class FakeClock:
    """A simulated clock for tests: call it for the time, ``advance()`` it by ``dt``."""

    def __init__(self, dt: float = 0.1, start: float = 0.0) -> None:
        self.now = start
        self.dt = dt

    def __call__(self) -> float:
        return self.now

    def advance(self) -> None:
        self.now += self.dt


class StubScripted(BehaviourWithPorts):
    """Return the statuses in ``script`` one per tick (``"R,R,S"``: RUNNING, RUNNING,
    SUCCESS), then the last one for ever; counts its ticks and its halts."""

    NODE_TYPE: ClassVar[str] = "Action"
    INPUT_PORTS = {
        "script": PortInformation(data_type=str, required=True, description="e.g. R,R,S"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}
    _CODES: ClassVar[dict[str, Status]] = {
        "S": Status.SUCCESS,
        "F": Status.FAILURE,
        "R": Status.RUNNING,
    }

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.ticks = 0
        self.halts = 0

    def update(self) -> Status:
        codes = [c.strip() for c in str(self.get_input("script")).split(",")]
        status = self._CODES[codes[min(self.ticks, len(codes) - 1)]]
        self.ticks += 1
        return status

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self.status == Status.RUNNING:
            self.halts += 1

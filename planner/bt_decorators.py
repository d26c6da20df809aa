"""BehaviorTree.CPP v4's built-in decorators that py_trees lacks: KeepRunningUntilFailure,
RunOnce, Delay (on simulated time) and RetryUntilSuccessful with ``num_attempts="-1"``
(forever) or ``num_attempts="{key}"`` (read from the blackboard at every tick, as BT.CPP).

Ports-enabled (``register=False``); :data:`BUILTIN_DECORATORS` maps each BT.CPP tag to its class.
"""

from __future__ import annotations

import time
from typing import Any

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.bt_leaves import StringPorts
from planner.decorators import Clock, SimTimeout, clock_from_setup

__all__ = [
    "BUILTIN_DECORATORS",
    "Delay",
    "KeepRunningUntilFailure",
    "RetryForever",
    "RunOnce",
    "propagate_skips",
]

Behaviour = py_trees.behaviour.Behaviour


class KeepRunningUntilFailure(StringPorts, py_trees.decorators.Decorator, register=False):
    """RUNNING while the child runs or succeeds (a success restarts it next tick); FAILURE
    when the child fails."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        """FAILURE on the child's failure, else RUNNING."""
        if self.decorated.status == Status.FAILURE:
            return Status.FAILURE
        if self.decorated.status == Status.SUCCESS:
            self.decorated.stop(Status.INVALID)
        return Status.RUNNING


class RunOnce(StringPorts, py_trees.decorators.Decorator, register=False):
    """Tick the child until it finishes once; afterwards return the status it finished with
    without ticking it (``then_skip="false"``). BT.CPP's default ``then_skip="true"`` returns
    SKIPPED, which py_trees has no status for: it is given as the status that makes the
    parent move on (FAILURE under a Selector/Fallback, SUCCESS elsewhere)."""

    bt_can_skip = True  # see propagate_skips

    INPUT_PORTS = {
        "then_skip": PortInformation(data_type=bool, default_value=True, description="skip"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, child: Behaviour, **kwargs: Any) -> None:
        super().__init__(name=name, child=child, **kwargs)
        self.result: Status | None = None

    def tick(self):  # type: ignore[no-untyped-def]
        """Once finished, never tick the child again."""
        if self.result is None:
            yield from super().tick()
            return
        status = self.result
        if self.get_input("then_skip"):
            status = skipped_status(self)
        self.status = status
        yield self

    def update(self) -> Status:
        """Remember the child's first result."""
        status = self.decorated.status
        if status in (Status.SUCCESS, Status.FAILURE):
            self.result = status
        return status


def skipped_status(node: Behaviour) -> Status:
    """The py_trees stand-in for BT.CPP's SKIPPED: what lets ``node``'s parent carry on.

    ``node`` is marked skipped (:func:`was_skipped`) until :func:`mark_ticked`: a skipped child
    did not decide its parent's status, and a failure is not explained by it
    (:func:`planner.runner.status_chain`)."""
    node.bt_skipped = True  # type: ignore[attr-defined]
    if isinstance(node.parent, py_trees.composites.Selector):
        return Status.FAILURE
    return Status.SUCCESS


def propagate_skips(root: Behaviour) -> None:
    """BT.CPP v4's rule that a control node or decorator all of whose children were skipped
    is skipped itself (its parent carries on as past any skipped child), in place.

    Only the nodes above one that can skip (``bt_can_skip``: a ``_skipIf`` or ``_while``
    condition, ``RunOnce``, ``SkipUnlessUpdated``) are wrapped: no other can find all its
    children skipped, and the others' ticks stay as py_trees makes them."""
    above: dict[int, Behaviour] = {}
    for node in root.iterate():
        if getattr(node, "bt_can_skip", False):
            parent = node.parent
            while parent is not None and id(parent) not in above:
                above[id(parent)] = parent
                parent = parent.parent
    for node in above.values():
        _skip_when_children_are(node)


def _skip_when_children_are(node: Behaviour) -> None:
    original_tick = node.tick

    def tick():  # type: ignore[no-untyped-def]
        mark_ticked(node)
        for ticked in original_tick():
            if (
                ticked is node
                and node.status in (Status.SUCCESS, Status.FAILURE)
                and node.children
                and all(was_skipped(child) for child in node.children)
            ):
                node.status = skipped_status(node)
            yield ticked

    setattr(node, "tick", tick)  # noqa: B010 - per instance, as the conditions are


def mark_ticked(node: Behaviour) -> None:
    """``node`` ran this tick: it is no longer skipped (:func:`skipped_status`)."""
    node.bt_skipped = False  # type: ignore[attr-defined]


def was_skipped(node: Behaviour) -> bool:
    """Whether ``node``'s last status was SKIPPED's stand-in (:func:`skipped_status`)."""
    return bool(getattr(node, "bt_skipped", False))


class Delay(StringPorts, py_trees.decorators.Decorator, register=False):
    """RUNNING for ``delay_msec`` simulated milliseconds after being entered, then tick the
    child and return its status. A halt restarts the delay."""

    INPUT_PORTS = {
        "delay_msec": PortInformation(data_type=int, required=True, description="delay, ms"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, child: Behaviour, **kwargs: Any) -> None:
        super().__init__(name=name, child=child, **kwargs)
        self.clock: Clock = time.monotonic
        self.start_time = 0.0

    def setup(self, **kwargs: Any) -> None:
        """Take the simulated clock from ``clock=``."""
        self.clock = clock_from_setup(self.name, kwargs, self.clock)

    def initialise(self) -> None:
        """Start the delay."""
        self.start_time = float(self.clock())

    def tick(self):  # type: ignore[no-untyped-def]
        """Wait without ticking the child, then pass its ticks through."""
        if self.status != Status.RUNNING:
            self.initialise()
        elapsed_ms = (float(self.clock()) - self.start_time) * 1000.0
        if elapsed_ms < int(self.get_input("delay_msec")) - 1e-9:
            self.feedback_message = f"delaying, {elapsed_ms:.0f} ms so far"
            self.status = Status.RUNNING
            yield self
            return
        yield from self.decorated.tick()
        status = self.decorated.status
        if status != Status.RUNNING:
            self.stop(status)
        self.status = status
        yield self

    def update(self) -> Status:
        """Reflect the child."""
        return self.decorated.status


def _none_to_count(node: StringPorts, port: str, status: Status) -> bool:
    """Whether a loop entered afresh has no cycle to run: a count of 0, or negative but -1
    (for ever), on ``port``. Then, as BT.CPP (its loop runs while ``count < n || n == -1``),
    it is given ``status`` without ticking its child."""
    if node.status == Status.RUNNING:
        return False
    count = int(node.get_input(port))
    if count > 0 or count == -1:
        return False
    node.feedback_message = f"{port} is {count}: the child is not ticked"
    node.status = status
    return True


class RetryForever(StringPorts, py_trees.decorators.Decorator, register=False):
    """BT.CPP ``RetryUntilSuccessful`` whose ``num_attempts`` is -1 (retry forever), 0 or
    less (no attempt: FAILURE) or a ``{key}``: SUCCESS when the child succeeds; after a
    failure, RUNNING and the child is restarted, until ``num_attempts`` attempts have failed
    (then FAILURE). As BT.CPP's, the count is read at every tick and again after a failure,
    so a child that changes it is heard."""

    INPUT_PORTS = {
        "num_attempts": PortInformation(data_type=int, required=True, description="-1: forever"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, child: Behaviour, **kwargs: Any) -> None:
        super().__init__(name=name, child=child, **kwargs)
        self.failures = 0
        self.limit = -1

    def initialise(self) -> None:
        """A fresh entry: read the limit, count from zero."""
        self.failures = 0
        self.limit = int(self.get_input("num_attempts"))

    def tick(self):  # type: ignore[no-untyped-def]
        """As BT.CPP: no attempt to make (``num_attempts`` 0) is FAILURE, the child unticked."""
        if _none_to_count(self, "num_attempts", Status.FAILURE):
            yield self
            return
        if self.status == Status.RUNNING:
            self.limit = int(self.get_input("num_attempts"))
            if self.limit != -1 and self.failures >= self.limit:  # lowered since: no attempt
                self.feedback_message = f"failed {self.failures} of {self.limit} attempts"
                self.stop(Status.FAILURE)
                yield self
                return
        yield from super().tick()

    def update(self) -> Status:
        """Count the child's failures."""
        status = self.decorated.status
        if status != Status.FAILURE:
            return status
        self.failures += 1
        self.limit = int(self.get_input("num_attempts"))  # as BT.CPP, after each failure
        if self.limit != -1 and self.failures >= self.limit:
            self.feedback_message = f"failed {self.failures} of {self.limit} attempts"
            return Status.FAILURE
        self.feedback_message = f"attempt {self.failures} failed, retrying"
        return Status.RUNNING


#: BT.CPP tag -> decorator class.
BUILTIN_DECORATORS: dict[str, type[Behaviour]] = {
    "KeepRunningUntilFailure": KeepRunningUntilFailure,
    "RunOnce": RunOnce,
    "Delay": Delay,
    "RetryForever": RetryForever,
}


class TimeoutFromKey(StringPorts, SimTimeout, register=False):
    """BT.CPP ``Timeout msec="{key}"``: :class:`~planner.decorators.SimTimeout` whose
    milliseconds are read from the blackboard each time it is entered (0 or less: the child
    gets one tick)."""

    INPUT_PORTS = {
        "msec": PortInformation(data_type=int, required=True, description="time allowed, ms"),
    }

    def initialise(self) -> None:
        """Read the time allowed, start the timer."""
        # A non-positive time read at run time allows one tick of the child, never a crash.
        self.duration = max(int(self.get_input("msec")), 0) / 1000.0
        super().initialise()


class RepeatFromKey(StringPorts, py_trees.decorators.Decorator, register=False):
    """BT.CPP ``Repeat num_cycles="{key}"`` (or ``-1``, for ever; or ``0``, never): restart the
    child after each success until it has succeeded ``num_cycles`` times (SUCCESS); a failure
    is FAILURE. As BT.CPP's, the count is read at every tick, before the child; between
    cycles it returns RUNNING."""

    INPUT_PORTS = {
        "num_cycles": PortInformation(data_type=int, required=True, description="-1: forever"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, child: Behaviour, **kwargs: Any) -> None:
        super().__init__(name=name, child=child, **kwargs)
        self.successes = 0
        self.cycles = -1

    def initialise(self) -> None:
        """Read the count, start from zero."""
        self.successes = 0
        self.cycles = int(self.get_input("num_cycles"))

    def tick(self):  # type: ignore[no-untyped-def]
        """As BT.CPP: no cycle to run (``num_cycles`` 0) is SUCCESS, the child unticked."""
        if _none_to_count(self, "num_cycles", Status.SUCCESS):
            yield self
            return
        if self.status == Status.RUNNING:
            self.cycles = int(self.get_input("num_cycles"))
            if self.cycles != -1 and self.successes >= self.cycles:  # lowered since: done
                self.stop(Status.SUCCESS)
                yield self
                return
        yield from super().tick()

    def update(self) -> Status:
        """Count the child's successes."""
        status = self.decorated.status
        if status != Status.SUCCESS:
            return status
        self.successes += 1
        if self.cycles != -1 and self.successes >= self.cycles:
            return Status.SUCCESS
        return Status.RUNNING


BUILTIN_DECORATORS["TimeoutFromKey"] = TimeoutFromKey
BUILTIN_DECORATORS["RepeatFromKey"] = RepeatFromKey

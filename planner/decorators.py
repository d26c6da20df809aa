"""Decorators that run on simulated time.

py_trees' :class:`~py_trees.decorators.Timeout` reads ``time.monotonic()``, so a simulation that
runs faster or slower than real time would time out at the wrong moment. :class:`SimTimeout`
reads the clock handed to ``setup(clock=...)`` instead; tree files get it under the tag
``Timeout`` (see :func:`planner.validate.effective_registry`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin

__all__ = ["Clock", "SimTimeout", "clock_from_setup"]

#: A clock: returns the current (simulated) time in seconds.
Clock = Callable[[], float]


def clock_from_setup(name: str, kwargs: dict[str, Any], current: Clock) -> Clock:
    """The clock given to ``setup(clock=...)``, else ``current``.

    Raises
    ------
    TypeError
        If ``clock`` is given but is not callable.
    """
    clock = kwargs.get("clock")
    if clock is None:
        return current
    if not callable(clock):
        raise TypeError(
            f"{name}: clock: expected a callable returning seconds, got {type(clock).__name__}"
        )
    return clock


class SimTimeout(PortsMixin, py_trees.decorators.Decorator, register=False):
    """Fail a child that is still running ``duration`` simulated seconds after it started.

    The child is ticked first; if it is then still RUNNING and at least ``duration`` seconds
    have passed on the clock since this decorator was entered, the child is halted (stopped
    with INVALID) and the decorator returns FAILURE. Otherwise it returns the child's status.
    Halting the decorator itself (``stop(INVALID)``) resets its timer.

    Parameters
    ----------
    name : str
        Node name.
    child : py_trees.behaviour.Behaviour
        The decorated behaviour.
    duration : float
        Time allowed, s (simulated). Must be positive.
    **kwargs
        Passed on (the XML parser passes ``behaviour_class_name``).

    Notes
    -----
    The clock comes from ``setup(clock=callable_returning_seconds)``, which
    ``BehaviourTree.setup(clock=...)`` passes to every node; without one the decorator falls
    back to ``time.monotonic``. It is ports-enabled (with no ports) only so that py_trees' XML
    parser can build it from the registry under the tag ``Timeout``.
    """

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(
        self, name: str, child: py_trees.behaviour.Behaviour, duration: float = 5.0, **kwargs: Any
    ) -> None:
        duration = float(duration)
        if not duration > 0.0:
            raise ValueError(f"{name}: duration: expected a positive time in s, got {duration}")
        super().__init__(name=name, child=child, **kwargs)
        self.duration = duration
        self.clock: Clock = time.monotonic
        self.start_time: float | None = None

    def setup(self, **kwargs: Any) -> None:
        """Take the simulated clock from ``clock=`` (a callable returning seconds), if given.

        Raises
        ------
        TypeError
            If ``clock`` is given but is not callable.
        """
        self.clock = clock_from_setup(self.name, kwargs, self.clock)

    def initialise(self) -> None:
        """Start the timer: the decorator is being entered afresh."""
        self.start_time = float(self.clock())
        self.feedback_message = ""

    def elapsed(self) -> float:
        """Seconds since the decorator was entered (0 when it is not running)."""
        if self.start_time is None:
            return 0.0
        return float(self.clock()) - self.start_time

    def update(self) -> Status:
        """Halt the child and fail once the time is up, else reflect the child's status."""
        child_status = self.decorated.status
        elapsed = self.elapsed()
        if child_status == Status.RUNNING and elapsed >= self.duration:
            # What the running leaf last said is lost with the halt: keep it in the reason.
            tip = self.decorated.tip()
            said = (
                f" while {tip.name.rsplit('.', 1)[-1]} said: {tip.feedback_message}"
                if tip is not None and tip.feedback_message
                else ""
            )
            self.feedback_message = (
                f"timed out after {elapsed:.3f} s (allowed {self.duration:.3f} s); halted "
                f"'{self.decorated.name}'{said}"
            )
            self.decorated.stop(Status.INVALID)
            return Status.FAILURE
        if child_status == Status.RUNNING:
            self.feedback_message = f"{self.duration - elapsed:.3f} s left"
        else:
            self.feedback_message = f"child finished after {elapsed:.3f} s"
        return child_status

    def terminate(self, new_status: Status) -> None:
        """Reset the timer when halted, so the next entry starts from zero."""
        if new_status == Status.INVALID:
            self.start_time = None

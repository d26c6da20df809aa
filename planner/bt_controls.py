"""BehaviorTree.CPP v4's built-in control nodes that py_trees has no equivalent for, with
BT.CPP's semantics: SequenceWithMemory, IfThenElse, WhileDoElse, TryCatch, ParallelAll and
Parallel with any ``success_count``/``failure_count``.

Each is a py_trees :class:`~py_trees.composites.Composite` whose ``tick`` ticks children the
way BT.CPP's ``tick()`` does; a child left RUNNING when the node finishes, or when a
reactive node moves to another branch, is halted (``stop(INVALID)``), as BT.CPP's
``haltChild``. They are ports-enabled (``register=False``) so the tree reader can build and
check them; :data:`BUILTIN_CONTROLS` maps each BT.CPP tag to its class.
"""

from __future__ import annotations

from collections.abc import Generator, Iterator
from typing import Any

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.bt_leaves import StringPorts

__all__ = [
    "BUILTIN_CONTROLS",
    "IfThenElse",
    "ParallelAll",
    "ParallelCount",
    "SequenceWithMemory",
    "TryCatch",
    "WhileDoElse",
    "parallel_threshold",
]

Behaviour = py_trees.behaviour.Behaviour
#: A control's step: yields the nodes ticked (py_trees' tick protocol), returns its status.
Step = Generator[Behaviour, None, Status]


def halt(node: Behaviour) -> None:
    """Halt a node that is RUNNING (BT.CPP's ``haltChild``); reset a finished one quietly."""
    if node.status != Status.INVALID:
        node.stop(Status.INVALID)


class Control(StringPorts, py_trees.composites.Composite, register=False):
    """Base: ``tick`` runs :meth:`step`, then halts every child left RUNNING when it ends."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, children: list[Behaviour] | None = None, **kwargs: Any):
        super().__init__(name=name, children=children, **kwargs)

    def tick_child(self, index: int) -> Step:
        """Tick child ``index`` (as py_trees does: yield what it yields); return its status."""
        child = self.children[index]
        self.current_child = child
        yield from child.tick()
        return child.status

    def step(self) -> Step:  # pragma: no cover - every subclass defines it
        """One tick of the control's own logic."""
        raise NotImplementedError
        yield self

    def reset(self) -> None:
        """Forget progress (after finishing or a halt)."""

    def tick(self) -> Iterator[Behaviour]:
        """py_trees' tick protocol around :meth:`step`."""
        if self.status != Status.RUNNING:
            self.initialise()
        status = yield from self.step()
        if status != Status.RUNNING:
            for child in self.children:
                if child.status == Status.RUNNING:
                    halt(child)
            self.reset()
            self.stop(status)
        self.status = status
        yield self

    def stop(self, new_status: Status = Status.INVALID) -> None:
        """A halt of a RUNNING node forgets its progress as well as halting the children; a
        finished node reset by its parent keeps it (BT.CPP halts only running children)."""
        if new_status == Status.INVALID and self.status == Status.RUNNING:
            self.reset()
        super().stop(new_status)


class SequenceWithMemory(Control, register=False):
    """Tick children in order; a child that succeeded is not ticked again until the sequence
    ends. On a FAILURE the sequence fails and the index is kept: the next tick starts again
    at the child that failed (BT.CPP). A halt (and SUCCESS) start it from the first child.
    """

    def __init__(self, name: str, children: list[Behaviour] | None = None, **kwargs: Any):
        super().__init__(name=name, children=children, **kwargs)
        self.index = 0
        self._keep = False

    def step(self) -> Step:
        """Go on from the remembered child."""
        while self.index < len(self.children):
            status = yield from self.tick_child(self.index)
            if status == Status.RUNNING:
                return Status.RUNNING
            if status == Status.FAILURE:
                self._keep = True
                return Status.FAILURE
            self.index += 1
        return Status.SUCCESS

    def reset(self) -> None:
        """Keep the index only through a failure."""
        if self._keep:
            self._keep = False
            return
        self.index = 0


class IfThenElse(Control, register=False):
    """2 or 3 children: if the first succeeds tick the second, else the third (or FAILURE
    without one). Not reactive: while the chosen branch runs, the condition is not ticked."""

    def __init__(self, name: str, children: list[Behaviour] | None = None, **kwargs: Any):
        super().__init__(name=name, children=children, **kwargs)
        self.branch = 0

    def step(self) -> Step:
        """Condition once, then the chosen branch until it finishes."""
        if self.branch == 0:
            status = yield from self.tick_child(0)
            if status == Status.RUNNING:
                return Status.RUNNING
            if status == Status.SUCCESS:
                self.branch = 1
            elif len(self.children) == 3:
                self.branch = 2
            else:
                return Status.FAILURE
        return (yield from self.tick_child(self.branch))

    def reset(self) -> None:
        """Next entry ticks the condition again."""
        self.branch = 0


class WhileDoElse(Control, register=False):
    """2 or 3 children, reactive: the condition is ticked every tick; SUCCESS ticks the second
    child, FAILURE the third (or FAILURE without one). The branch no longer chosen is halted
    before the other is ticked."""

    def step(self) -> Step:
        """Condition, then the branch it selects."""
        status = yield from self.tick_child(0)
        if status == Status.RUNNING:
            return Status.RUNNING
        if status == Status.SUCCESS:
            if len(self.children) == 3:
                halt(self.children[2])
            return (yield from self.tick_child(1))
        halt(self.children[1])
        if len(self.children) == 3:
            return (yield from self.tick_child(2))
        return Status.FAILURE


class TryCatch(Control, register=False):
    """All children but the last are the try block, ticked as a sequence with memory; if one
    fails, the last child (the catch) is ticked until it finishes and the node then FAILS,
    whatever the catch returned. SUCCESS when the try block succeeds.

    ``catch_on_halt="true"``: a halt while the try block runs halts the try block, then ticks
    the catch once, there and then, and halts it if it is still RUNNING (BT.CPP 4.x
    ``TryCatchNode::halt``: a best-effort clean-up). A halt during the catch only halts it.
    """

    INPUT_PORTS = {
        "catch_on_halt": PortInformation(
            data_type=bool, default_value=False, description="run the catch when halted"
        ),
    }

    def __init__(self, name: str, children: list[Behaviour] | None = None, **kwargs: Any):
        super().__init__(name=name, children=children, **kwargs)
        self.index = 0
        self.catching = False

    def step(self) -> Step:
        """Try block in order; on a failure, the catch."""
        last = len(self.children) - 1
        while not self.catching and self.index < last:
            status = yield from self.tick_child(self.index)
            if status == Status.RUNNING:
                return Status.RUNNING
            if status == Status.FAILURE:
                self.catching = True
                break
            self.index += 1
        if not self.catching:
            return Status.SUCCESS
        status = yield from self.tick_child(last)
        return Status.RUNNING if status == Status.RUNNING else Status.FAILURE

    def reset(self) -> None:
        """Start again from the first child."""
        self.index = 0
        self.catching = False

    def stop(self, new_status: Status = Status.INVALID) -> None:
        """A halt of the running try block runs the catch once if ``catch_on_halt``."""
        if (
            new_status == Status.INVALID
            and self.status == Status.RUNNING
            and not self.catching
            and self.get_input("catch_on_halt")
        ):
            *tries, catch = self.children
            for child in tries:
                halt(child)
            for _ in catch.tick():
                pass
            if catch.status == Status.RUNNING:
                halt(catch)
        super().stop(new_status)


def parallel_threshold(count: int, children: int) -> int:
    """BT.CPP's ``Parallel`` count of ``children``: a count of 0 or more as it is, a negative
    one that many from all but one (-1: all, -2: all but one), never below 0."""
    return max(children + count + 1, 0) if count < 0 else count


class ParallelCount(Control, register=False):
    """BT.CPP's ``Parallel``: tick every child that has not finished; SUCCESS once
    ``success_count`` children succeeded, FAILURE once ``failure_count`` failed or success can
    no longer be reached (counts as :func:`parallel_threshold` reads them: -1 all, -2 all but
    one). Running children are then halted. As BT.CPP's, it decides after each child it
    visits, so a count of 0 decides at the first.

    Children that finished are not ticked again until the node itself finishes.
    """

    INPUT_PORTS = {
        "success_count": PortInformation(data_type=int, default_value=-1, description="n"),
        "failure_count": PortInformation(data_type=int, default_value=1, description="n"),
    }

    def __init__(self, name: str, children: list[Behaviour] | None = None, **kwargs: Any):
        super().__init__(name=name, children=children, **kwargs)
        self.done: dict[int, Status] = {}

    def thresholds(self) -> tuple[int, int] | None:
        """(successes needed, failures that end it), as :func:`parallel_threshold` reads the
        ports; None (and the reason in ``feedback_message``) if one exceeds the children."""
        n = len(self.children)
        success = int(self.get_input("success_count"))
        failure = int(self.get_input("failure_count"))
        needed, limit = parallel_threshold(success, n), parallel_threshold(failure, n)
        if needed > n or limit > n:
            self.feedback_message = (
                f"success_count {success} and failure_count {failure}: expected at most {n} "
                f"(the number of children)"
            )
            return None
        return needed, limit

    def step(self) -> Step:
        """Tick the unfinished children, deciding after each as BT.CPP does."""
        limits = self.thresholds()
        if limits is None:
            return Status.FAILURE
        success_needed, failure_limit = limits
        n = len(self.children)
        for i in range(n):
            if i not in self.done:
                status = yield from self.tick_child(i)
                if status != Status.RUNNING:
                    self.done[i] = status
            successes = sum(s == Status.SUCCESS for s in self.done.values())
            failures = len(self.done) - successes
            if successes >= success_needed:
                return Status.SUCCESS
            if failures == failure_limit or n - failures < success_needed:
                return Status.FAILURE
        return Status.RUNNING

    def reset(self) -> None:
        """Forget which children finished."""
        self.done = {}


class ParallelAll(Control, register=False):
    """Tick every unfinished child until all have finished; then FAILURE if at least
    ``max_failures`` failed (-1: all of them), else SUCCESS (BT.CPP ``ParallelAll``)."""

    INPUT_PORTS = {
        "max_failures": PortInformation(data_type=int, default_value=1, description="n"),
    }

    def __init__(self, name: str, children: list[Behaviour] | None = None, **kwargs: Any):
        super().__init__(name=name, children=children, **kwargs)
        self.done: dict[int, Status] = {}

    def step(self) -> Step:
        """Tick the unfinished children; decide when none is left."""
        for i in range(len(self.children)):
            if i not in self.done:
                status = yield from self.tick_child(i)
                if status != Status.RUNNING:
                    self.done[i] = status
        if len(self.done) < len(self.children):
            return Status.RUNNING
        limit = int(self.get_input("max_failures"))
        limit = len(self.children) if limit < 0 else limit
        failures = sum(s == Status.FAILURE for s in self.done.values())
        return Status.FAILURE if failures >= limit else Status.SUCCESS

    def reset(self) -> None:
        """Forget which children finished."""
        self.done = {}


#: BT.CPP tag -> control class, and the number of children each takes (low, high or None).
BUILTIN_CONTROLS: dict[str, type[Control]] = {
    "SequenceWithMemory": SequenceWithMemory,
    "IfThenElse": IfThenElse,
    "WhileDoElse": WhileDoElse,
    "TryCatch": TryCatch,
    "ParallelAll": ParallelAll,
    "ParallelCount": ParallelCount,
}
CHILD_COUNTS: dict[str, tuple[int, int | None]] = {
    "IfThenElse": (2, 3),
    "WhileDoElse": (2, 3),
    "TryCatch": (2, None),
}

"""Run a tree against a world: tick at the control rate, advance the world between ticks.

Leaves never step the world (``update()`` never blocks); this loop does, so the same tree runs
against the PyBullet world and the in-memory fake.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import py_trees
from py_trees.common import Status

from planner.bt_decorators import was_skipped
from planner.port import WorldPort
from skills.library import SkillLibrary


@dataclass(frozen=True)
class RunResult:
    """How a run ended.

    Attributes
    ----------
    status : Status
        The root's final status (INVALID if stopped at the time limit).
    sim_time : float
        Simulated seconds.
    wall_time : float
        Wall-clock seconds.
    ticks : int
    reason : str
        Why the run failed or was stopped (:func:`explain`: the node where it happened and what
        it said); "" after a success.
    """

    status: Status
    sim_time: float
    wall_time: float
    ticks: int
    reason: str

    @property
    def success(self) -> bool:
        """The root succeeded."""
        return self.status == Status.SUCCESS


def seed_blackboard(values: Mapping[str, Any]) -> None:
    """Write initial values (e.g. ``{"/object": "parcel"}``) to the global blackboard."""
    client = py_trees.blackboard.Client(name="runner")
    for key, value in values.items():
        client.register_key(key=key, access=py_trees.common.Access.WRITE)
        client.set(key, value)


def status_chain(root: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    """The nodes that gave ``root`` its status, from ``root`` down to the deepest.

    A composite's status comes from its current child (a sequence's failing child, a
    fallback's last one tried), a decorator's from its child: each step goes to the child
    with the parent's status, so the chain of a failed root ends at the node where the failure
    started (a leaf that failed, or a Timeout that halted a child still running).
    """
    chain = [root]
    node = root
    while node.children:
        current = getattr(node, "current_child", None)
        if (
            current is not None
            and current in node.children
            and current.status == node.status
            and not was_skipped(current)
        ):
            node = current
        else:
            # A skipped child (BT.CPP's SKIPPED) gave its parent nothing: not the reason.
            same = [c for c in node.children if c.status == node.status and not was_skipped(c)]
            if not same:
                break
            node = same[-1]
        chain.append(node)
    return chain


def progress_node(tree: py_trees.trees.BehaviourTree) -> py_trees.behaviour.Behaviour | None:
    """The node a progress line names after a tick: py_trees' ``tip`` (the deepest node the
    tick reached: a running leaf, or a node that just failed, a Timeout saying it timed out),
    unless that is a control node or decorator still running with no running leaf under it;
    then the :func:`working_leaf` of the tree. py_trees' tip follows a parallel's last running
    child: a transport beside a watch (``Parallel(Timeout(Transport),
    KeepRunningUntilFailure(IsHeld))``) had read as the watch's decorator, saying nothing."""
    tip = tree.tip()
    if tip is None or tip.status != Status.RUNNING or not tip.children:
        return tip
    return working_leaf(tree.root) or tip


def working_leaf(root: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour | None:
    """The first, in tree order, of the running leaves under ``root`` that says what it is
    doing, else the first running one; None if nothing runs."""
    first = None
    stack = [root]
    while stack:
        node = stack.pop()
        if node.status != Status.RUNNING:
            continue
        if not node.children:
            if node.feedback_message:
                return node
            first = first or node
        stack.extend(reversed(node.children))
    return first


#: The suffix py_trees gives a node the file does not name (``Transport_<uuid4>``), and the
#: bare uuid4 it names an unnamed composite above it by (``<uuid4>.``).
_UUID = r"[0-9a-f]{8}-[0-9a-f]{4}-4[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}"
_UNNAMED = re.compile(rf"_{_UUID}|(?<![\w-]){_UUID}\.")
_OWN_UUID = re.compile(rf"_{_UUID}$")


def unnamed(name: str) -> bool:
    """Whether a node's name is one py_trees made for a node the file leaves unnamed."""
    return _OWN_UUID.search(name) is not None


def readable(text: str) -> str:
    """``text`` with the uuids py_trees names the file's unnamed nodes by taken out: an
    unnamed node reads as its type, as BehaviorTree.CPP names it (``Transport``), and an
    unnamed composite above it drops out of its path."""
    return _UNNAMED.sub("", text)


def explain(root: py_trees.behaviour.Behaviour) -> str:
    """Why ``root`` has its status: the deepest node of :func:`status_chain`, named, and what it
    said; never empty.

    A node that says nothing is still named, with its status and what the nearest node above it
    said (e.g. a Retry's count), so a failure always names where it happened.
    """
    chain = status_chain(root)
    deepest = chain[-1]
    if deepest.feedback_message:
        return readable(f"{deepest.name}: {deepest.feedback_message}")
    text = f"{deepest.name}: {deepest.status.value.lower()} without a feedback message"
    above = [n for n in chain[:-1] if n.feedback_message]
    if above:
        text += f" (under {above[-1].name}: {above[-1].feedback_message})"
    return readable(text)


def tick_tree(tree: py_trees.trees.BehaviourTree) -> None:
    """Tick ``tree`` once, as :meth:`py_trees.trees.BehaviourTree.tick` does: pre-tick
    handlers, visitors initialised, the root ticked with the partial visitors visiting each
    ticked node, full visitors visiting every node, visitors finalised, post-tick handlers.

    py_trees walks the whole tree after every tick even when no visitor asks for it; this
    walks it only for a full visitor. On a run's trees (hundreds of nodes, a few ticked per
    tick) that walk was an eighth of a run.
    """
    for handler in tree.pre_tick_handlers:
        handler(tree)
    visitors = list(tree.visitors)
    for visitor in visitors:
        visitor.initialise()
    partial = [visitor for visitor in visitors if not visitor.full]
    for node in tree.root.tick():
        for visitor in partial:
            node.visit(visitor)
    full = [visitor for visitor in visitors if visitor.full]
    if full:
        for node in tree.root.iterate():
            for visitor in full:
                node.visit(visitor)
    for visitor in visitors:
        visitor.finalise()
    for handler in tree.post_tick_handlers:
        handler(tree)
    tree.count += 1


def run_tree(
    root: py_trees.behaviour.Behaviour,
    world: WorldPort,
    library: SkillLibrary,
    control_dt: float,
    max_sim_time: float,
    blackboard: Mapping[str, Any] | None = None,
    on_tick: Callable[[py_trees.trees.BehaviourTree], None] | None = None,
    attach: tuple[Callable[[py_trees.trees.BehaviourTree], Any], ...] = (),
    max_wall_time: float = math.inf,
) -> RunResult:
    """Set up ``root`` with the world and tick it until it finishes or time runs out.

    Parameters
    ----------
    root : Behaviour
    world : WorldPort
    library : SkillLibrary
    control_dt : float
        Tick period, s of simulated time.
    max_sim_time : float
        Stop (halting the tree, which stops the arms) after this much simulated time, s.
    blackboard : mapping, optional
        Initial blackboard values, absolute keys.
    on_tick : callable, optional
        Called after every tick (progress display).
    attach : tuple of callables
        Each is given the tree before setup (e.g. ``RunLog.attach``, or a function adding a
        post-tick handler).
    max_wall_time : float
        Stop the same way after this much wall-clock time, s: a guard against a run that
        cannot end in any sensible time (the only place wall time changes an outcome).
    """
    seed_blackboard(blackboard or {})
    tree = py_trees.trees.BehaviourTree(root)
    for hook in attach:
        hook(tree)
    tree.setup(world=world, library=library, control_dt=control_dt, clock=world.time)
    start_sim, start_wall = world.time(), time.perf_counter()
    ticks = 0
    while True:
        tick_tree(tree)
        ticks += 1
        if on_tick is not None:
            on_tick(tree)
        if root.status in (Status.SUCCESS, Status.FAILURE):
            break
        over_sim = world.time() - start_sim >= max_sim_time
        over_wall = time.perf_counter() - start_wall >= max_wall_time
        if over_sim or over_wall:
            reason = explain(root)
            root.stop(Status.INVALID)
            limit = (
                f"time limit {max_sim_time:g} s reached"
                if over_sim
                else f"wall-clock limit {max_wall_time:g} s reached"
            )
            return RunResult(
                Status.INVALID,
                world.time() - start_sim,
                time.perf_counter() - start_wall,
                ticks,
                f"{limit}; {reason}",
            )
        world.advance(control_dt)
    return RunResult(
        root.status,
        world.time() - start_sim,
        time.perf_counter() - start_wall,
        ticks,
        explain(root) if root.status == Status.FAILURE else "",
    )

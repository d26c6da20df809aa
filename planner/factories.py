"""The paper's task built in code: the same tree as ``planner/trees/pick_and_place.xml``.

Subtrees are factory functions, never subclasses of composites (house style). Blackboard keys
are the XML's: ``/object``, ``/plan`` and ``/state``. Where the XML instantiates a subtree, the
factory returns the subtree's root (the XML loader adds no node for a ``SubTree`` either; it
only prefixes the names).
"""

from __future__ import annotations

from py_trees.behaviour import Behaviour
from py_trees.composites import Selector, Sequence
from py_trees.decorators import Retry

from planner.decorators import SimTimeout
from planner.leaves import (
    Approach,
    AtGoal,
    Grasp,
    IsHeld,
    PathClear,
    Release,
    Retreat,
    SelectSkills,
    Transport,
)
from planner.wiring import wire

OBJECT, PLAN, STATE = "{object}", "{plan}", "{state}"

#: The compositions a move tries, in order: (name, transport weight, avoidance gain).
COMPOSITIONS: tuple[tuple[str, float, float], ...] = (
    ("as_demonstrated", 1.0, 0.0),
    ("low_carry", 0.25, 0.0),
    ("flat_carry", 0.1, 0.0),
    ("as_planned", 1.0, 1.0),
    ("low_careful", 0.25, 1.0),
)


def guard(name: str, child: Behaviour, seconds: float) -> SimTimeout:
    """A simulated-time Timeout around ``child``."""
    node = SimTimeout(name, child, duration=seconds)
    wire(node)
    return node


def grasp_object(name: str = "grasp_retry") -> Behaviour:
    """Approach the object's sides through set-points, then grasp; two attempts."""
    approach = wire(Approach("approach"), object=OBJECT)
    grasp = wire(Grasp("grasp"), object=OBJECT, plan=PLAN, state=STATE)
    seq = Sequence(
        "approach_and_grasp",
        memory=True,
        children=[
            guard("approach_guard", approach, 8.0),
            guard("grasp_guard", grasp, 5.0),
        ],
    )
    retry = Retry("grasp_retry", seq, num_failures=2)
    retry.name = name
    return retry


def carry_if_clear(name: str, move: int, transport_weight: float, avoid_gain: float) -> Behaviour:
    """Check a composition's predicted path with FCL, then carry with it."""
    ports = {"transport_weight": transport_weight, "avoid_gain": avoid_gain}
    # The XML's {composition} is a key of its CarryIfClear alone; here one key per move and
    # variant does the same.
    checked = f"{{composition_{move}_{name}}}"
    clear = wire(
        PathClear("path_clear"),
        object=OBJECT,
        move=move,
        plan=PLAN,
        from_state=STATE,
        margin_m=0.01,
        composition=checked,
        **ports,
    )
    carry = wire(
        Transport("transport"),
        object=OBJECT,
        move=move,
        plan=PLAN,
        from_state=STATE,
        to_state=STATE,
        composition=checked,
        **ports,
    )
    seq = Sequence(
        "check_then_carry",
        memory=True,
        children=[
            clear,
            guard("transport_guard", carry, 20.0),
        ],
    )
    return seq


def move_subtree(name: str, move: int) -> Behaviour:
    """One pick-and-place move: hold (or re-grasp), choose a composition, carry, check."""
    held = wire(IsHeld("is_held"), object=OBJECT)
    back_off = wire(Retreat("back_off"), segment_s=1.0)
    regrasp = Sequence(
        "regrasp",
        memory=True,
        children=[
            guard("reopen_guard", back_off, 4.0),
            grasp_object(),
        ],
    )
    hold = Selector("hold_or_regrasp", memory=False, children=[held, regrasp])
    careful = wire(
        Transport("careful_transport"),
        object=OBJECT,
        move=move,
        plan=PLAN,
        avoid_gain=2.0,
        from_state=STATE,
        to_state=STATE,
    )
    choose = Selector(
        "choose_composition",
        memory=True,
        children=[
            *(carry_if_clear(n, move, w, g) for n, w, g in COMPOSITIONS),
            guard("careful_guard", careful, 25.0),
        ],
    )
    at_goal = wire(AtGoal("at_goal"), object=OBJECT, move=move)
    carry = Sequence("carry", memory=True, children=[hold, choose, at_goal])
    return Retry("move_retry", carry, num_failures=2)


def pick_and_place(moves: int = 3) -> Behaviour:
    """The paper's task: select skills, grasp, ``moves`` moves, release, retreat."""
    names = ("move_centre", "move_right", "move_left")
    select = wire(SelectSkills("select_skills"), object=OBJECT, plan=PLAN)
    release = wire(Release("release"), object=OBJECT, from_state=STATE, to_state=STATE)
    retreat = wire(Retreat("retreat"))
    return Sequence(
        "pick_and_place",
        memory=True,
        children=[
            select,
            grasp_object(),
            *(move_subtree(names[i] if i < len(names) else f"move_{i}", i) for i in range(moves)),
            guard("release_guard", release, 6.0),
            guard("retreat_guard", retreat, 8.0),
        ],
    )


__all__ = ["COMPOSITIONS", "carry_if_clear", "grasp_object", "move_subtree", "pick_and_place"]

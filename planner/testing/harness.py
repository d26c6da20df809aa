"""Tick a leaf (or a tree) against a world, advancing the world between ticks."""

from __future__ import annotations

from dataclasses import dataclass

import py_trees
from py_trees.common import Status

from affordances import SemanticAction
from planner.leaves import Approach, Grasp, SelectSkills, Transport
from planner.leaves.base import DEFAULT_CONTROL_DT as CONTROL_DT
from planner.port import WorldPort
from planner.wiring import wire
from skills.library import SkillLibrary


@dataclass(frozen=True)
class TickLog:
    """What happened: the status after each tick and the final feedback."""

    statuses: tuple[Status, ...]
    feedback: str
    sim_time: float

    @property
    def final(self) -> Status:
        """The last status."""
        return self.statuses[-1]


def tick_until(
    behaviour: py_trees.behaviour.Behaviour,
    world: WorldPort,
    dt: float = CONTROL_DT,
    max_ticks: int = 2000,
) -> TickLog:
    """Tick ``behaviour`` until it stops RUNNING (or ``max_ticks``), advancing ``world`` by ``dt``.

    The behaviour must already be set up (``setup(world=..., library=..., control_dt=dt)``).
    """
    statuses = []
    for _ in range(max_ticks):
        behaviour.tick_once()
        statuses.append(behaviour.status)
        if behaviour.status != Status.RUNNING:
            break
        world.advance(dt)
    return TickLog(tuple(statuses), behaviour.feedback_message, world.time())


def set_up(
    leaf: py_trees.behaviour.Behaviour,
    world: WorldPort,
    library: SkillLibrary,
    dt: float = CONTROL_DT,
    **ports: object,
) -> py_trees.behaviour.Behaviour:
    """Wire ``leaf``'s ports (values in braces name blackboard keys, others are constants, as
    in XML) and set it up against ``world`` with a control period of ``dt`` s; returns it."""
    wire(leaf, **ports)  # type: ignore[arg-type]
    leaf.setup(world=world, library=library, control_dt=dt)
    return leaf


def _tick_to_success(leaf: py_trees.behaviour.Behaviour, world: WorldPort, dt: float) -> None:
    """Tick a set-up ``leaf`` until it stops; an AssertionError with its feedback unless it
    succeeded."""
    log = tick_until(leaf, world, dt)
    assert log.final == Status.SUCCESS, f"{leaf.name}: {log.feedback}"


def select_skills(
    world: WorldPort,
    library: SkillLibrary,
    name: str = "parcel",
    dt: float = CONTROL_DT,
    plan_key: str = "plan",
) -> SemanticAction:
    """Tick :class:`planner.leaves.SelectSkills` for ``name`` against ``world``: the reasoner's
    plan, also left in blackboard key ``plan_key``. An AssertionError with the leaf's feedback
    if it fails."""
    leaf = set_up(SelectSkills("select"), world, library, dt, object=name, plan=f"{{{plan_key}}}")
    _tick_to_success(leaf, world, dt)
    plan = py_trees.blackboard.Blackboard.get(f"/{plan_key}")
    assert isinstance(plan, SemanticAction), f"blackboard /{plan_key}: {plan!r}"
    return plan


def grasp_object(
    world: WorldPort,
    library: SkillLibrary,
    name: str = "parcel",
    dt: float = CONTROL_DT,
    plan_key: str = "plan",
    state_key: str = "state",
) -> SemanticAction:
    """Bring ``world`` to ``name`` held, as the shipped tree does before a carry: the skills
    selected (:func:`select_skills`, into blackboard key ``plan_key``), the palms brought
    beside the faces and closed (the grasp's full state into ``state_key``). Returns the plan;
    an AssertionError with the leaf's feedback if a step fails. A leaf that needs a held
    object is tested from here."""
    plan = select_skills(world, library, name, dt, plan_key)
    approach = set_up(Approach("approach"), world, library, dt, object=name)
    grasp = set_up(
        Grasp("grasp"),
        world,
        library,
        dt,
        object=name,
        plan=f"{{{plan_key}}}",
        state=f"{{{state_key}}}",
    )
    for leaf in (approach, grasp):
        _tick_to_success(leaf, world, dt)
    return plan


def set_up_carry(
    world: WorldPort,
    library: SkillLibrary,
    move: int = 0,
    name: str = "parcel",
    dt: float = CONTROL_DT,
    plan_key: str = "plan",
    state_key: str = "state",
    leaf_name: str = "carry",
    **ports: object,
) -> Transport:
    """A :class:`planner.leaves.Transport` of ``name``'s ``move``, wired as the shipped tree
    wires it (the plan from ``plan_key``, the full state handed over from and back to
    ``state_key``; ``ports`` add or replace ports) and set up against ``world``: after
    :func:`grasp_object`, tick it to carry."""
    wiring: dict[str, object] = {
        "object": name,
        "move": move,
        "plan": f"{{{plan_key}}}",
        "from_state": f"{{{state_key}}}",
        "to_state": f"{{{state_key}}}",
        **ports,
    }
    leaf = Transport(leaf_name)
    set_up(leaf, world, library, dt, **wiring)
    return leaf

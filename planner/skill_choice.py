"""Which learnt skill carries a move: the one a port or the move names, the level carry when
the plan keeps the object level, else the plan's transport; and why a named one cannot.
"""

from __future__ import annotations

import numpy as np

from affordances import SemanticAction, SkillSelection
from planner.port import Move, WorldPort
from skills.level_carry import level_carry_tau, max_carry_acceleration
from skills.library import SkillLibrary
from skills.skill import Skill, SkillKind
from skills.vocabulary import Action, Space


class SkillChoiceError(ValueError):
    """A move or a port names a skill the library cannot carry a move with."""


def transport_skill(library: SkillLibrary, key: str) -> Skill:
    """The absolute learnt skill called (or labelled) ``key``, to carry a move with.

    Raises
    ------
    SkillChoiceError
        Naming ``key`` and the library's skills, when none is called so, or it is not a
        learnt motion.
    """
    try:
        skill = library.named(key, Space.ABSOLUTE)
    except KeyError as err:
        raise SkillChoiceError(str(err.args[0])) from None
    if skill.kind is not SkillKind.LEARNT_DMP:
        learnt = ", ".join(
            s.name for s in library if s.kind is SkillKind.LEARNT_DMP and s.space is Space.ABSOLUTE
        )
        raise SkillChoiceError(
            f"skill {key!r}: expected a learnt motion ({SkillKind.LEARNT_DMP.value}) to carry "
            f"the move, got {skill.name!r} ({skill.kind.value}); the library's learnt motions: "
            f"{learnt or 'none'}"
        )
    return skill


def level_carry_key(plan: SemanticAction, library: SkillLibrary) -> str | None:
    """The label of the level carry (``keep_level``) when the plan keeps the object level and
    the library has a learnt absolute motion so labelled; else None (the plan's transport)."""
    if plan.skill(Action.KEEP_LEVEL) is None:
        return None
    key = Action.KEEP_LEVEL.value
    try:
        skill = library.named(key, Space.ABSOLUTE)
    except KeyError:
        return None
    return key if skill.kind is SkillKind.LEARNT_DMP else None


def level_carry_duration(world: WorldPort, name: str, move: Move) -> float:
    """The shortest ``tau`` that keeps the balls loose on ``name`` on it across ``move`` (0 if
    it carries none): :func:`skills.level_carry.max_carry_acceleration` at the judge's tilt."""
    balls = world.loose_balls(name)
    if not balls:
        return 0.0
    start = world.object_pose(name).position
    across = float(np.linalg.norm(np.asarray(move.goal.position)[:2] - np.asarray(start)[:2]))
    bound = min(max_carry_acceleration(b, gravity=world.gravity()) for b in balls)
    if bound <= 0.0:
        raise SkillChoiceError(
            f"{name}: no level carry keeps its loose balls on (their rim is too low to hold "
            "them at the tilt allowed)"
        )
    return level_carry_tau(across, bound)


def skill_for(
    library: SkillLibrary, selection: SkillSelection, transport: Skill | None = None
) -> Skill:
    """The library's skill for ``selection``: ``transport`` (the carry chosen for the move)
    for the plan's transport, else the first skill of the selection's action and space."""
    if transport is not None and selection.action is Action.TRANSPORT:
        return transport
    return library.first(selection.action, selection.space)


def carried_skill(
    plan: SemanticAction, library: SkillLibrary, key: str | None = None
) -> str | None:
    """Name of the learnt skill a move is carried with: the one called ``key`` (a port's or
    the move's choice), else the plan's transport selection; None when the plan composes no
    transport. The same lookups :func:`transport_composition` composes with, so a move's
    record names the skill (and so the demonstration) it actually ran."""
    sel = plan.skill(Action.TRANSPORT)
    if sel is None or sel.space is not Space.ABSOLUTE or sel.weight == 0.0:
        return None
    key = key or level_carry_key(plan, library)
    if key:
        return transport_skill(library, key).name
    return skill_for(library, sel).name


__all__ = [
    "SkillChoiceError",
    "carried_skill",
    "level_carry_duration",
    "level_carry_key",
    "skill_for",
    "transport_skill",
]

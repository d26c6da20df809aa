"""SelectSkills: ask the affordance reasoner which skills to compose for an object."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from affordances import SemanticAction, reason
from affordances.config import ReasonerConfig
from planner.leaves.base import WorldLeaf
from planner.port import ObjectSensing, ObstacleScene, PalmControl
from skills.vocabulary import Action, GraspType


def parse_weights(text: str) -> dict[Action, float]:
    """``"hold_lateral=0; avoid_links=0.5"`` as ``{Action: weight}`` ("" is none).

    Raises
    ------
    ValueError
        Naming the entry that is not ``ACTION=NUMBER`` with a known action and a finite number.
    """
    weights: dict[Action, float] = {}
    for entry in text.replace(",", ";").split(";"):
        if not entry.strip():
            continue
        name, sep, value = entry.partition("=")
        try:
            action = Action(name.strip())
        except ValueError:
            known = ", ".join(a.value for a in Action)
            raise ValueError(
                f"weights: {entry.strip()!r}: expected ACTION=NUMBER with ACTION one of {known}"
            ) from None
        try:
            weight = float(value) if sep else math.nan
        except ValueError:
            weight = math.nan
        if not math.isfinite(weight):
            raise ValueError(f"weights: {entry.strip()!r}: expected a finite number after '='")
        weights[action] = weight
    return weights


class SelectSkills(WorldLeaf):
    """Rank semantic actions for the object and write the best one as the plan."""

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing, PalmControl, ObstacleScene)

    INPUT_PORTS = {
        "object": PortInformation(str, description="object to reason about"),
        "grasp": PortInformation(
            str,
            required=False,
            default_value="two_palm_lateral",
            description="grasp type the tree's leaves implement",
        ),
        "weights": PortInformation(
            str,
            required=False,
            default_value="",
            description=(
                "composition weights that replace the reasoner's, ACTION=NUMBER separated by "
                "';' (avoid_links=0.5: half the link-level avoidance in every composition)"
            ),
        ),
    }
    OUTPUT_PORTS = {
        "plan": PortInformation(SemanticAction, description="chosen grasp and weighted skills"),
    }

    @staticmethod
    def port_literal_problem(port: str, value: str) -> str | None:
        """What is wrong with a literal ``weights`` (checked when the tree is read), or None."""
        if port != "weights":
            return None
        try:
            parse_weights(value)
        except ValueError as err:
            return str(err)
        return None

    def update(self) -> Status:
        """Reason once: SUCCESS with the plan, FAILURE when no action fits the tree's grasp."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        name = self.get_input("object")
        wanted = GraspType(self.get_input("grasp"))
        try:
            weights = parse_weights(str(self.get_input("weights") or ""))
        except ValueError as err:
            return self.fail(str(err))
        world = self.world
        ranked = reason(
            world.object_context(name),
            world.robot_capabilities(),
            scene=world.scene_query(),
            config=ReasonerConfig.under(world.gravity()),  # the world's, not the Earth's
        )
        for action in ranked:
            if action.grasp is wanted:
                missing = [a.value for a in weights if action.skill(a) is None]
                if missing:
                    chosen = ", ".join(sel.action.value for sel in action.skills)
                    return self.fail(
                        f"weights: {', '.join(missing)} not in the plan for {name} ({chosen})"
                    )
                action = replace(
                    action,
                    skills=tuple(
                        replace(sel, weight=weights.get(sel.action, sel.weight))
                        for sel in action.skills
                    ),
                )
                self._set_output("plan", action)
                skills = ", ".join(f"{s.action.value} w={s.weight:g}" for s in action.skills)
                return self.succeed(f"{wanted.value}: {skills}")
        offered = ", ".join(a.grasp.value for a in ranked) or "nothing"
        return self.fail(f"the reasoner offers {offered} for {name}, not {wanted.value}")

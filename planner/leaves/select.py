"""SelectSkills: ask the affordance reasoner which skills to compose for an object."""

from __future__ import annotations

from typing import ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from affordances import SemanticAction, reason
from planner.leaves.base import WorldLeaf
from planner.port import ObjectSensing, ObstacleScene, PalmControl
from skills.vocabulary import GraspType


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
    }
    OUTPUT_PORTS = {
        "plan": PortInformation(SemanticAction, description="chosen grasp and weighted skills"),
    }

    def update(self) -> Status:
        """Reason once: SUCCESS with the plan, FAILURE when no action fits the tree's grasp."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        name = self.get_input("object")
        wanted = GraspType(self.get_input("grasp"))
        world = self.world
        ranked = reason(
            world.object_context(name), world.robot_capabilities(), scene=world.scene_query()
        )
        for action in ranked:
            if action.grasp is wanted:
                self._set_output("plan", action)
                skills = ", ".join(f"{s.action.value} w={s.weight:g}" for s in action.skills)
                return self.succeed(f"{wanted.value}: {skills}")
        offered = ", ".join(a.grasp.value for a in ranked) or "nothing"
        return self.fail(f"the reasoner offers {offered} for {name}, not {wanted.value}")

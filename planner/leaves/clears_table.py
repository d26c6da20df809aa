"""TurnClearsTable: a box turned about its grasp axis keeps its corners off the table."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.composition import MovePlan
from planner.leaves.base import WorldLeaf
from planner.port import ObjectSensing, PalmControl
from skills.flip import turn_lift_m, vertical_half_extent


class TurnClearsTable(WorldLeaf):
    """The predicted rollout of a move's composition keeps the held box above the table top.

    A box turned about the axis through the palms sweeps its corners a radius of half its x-z
    diagonal about its centre (:mod:`skills.flip`): turned too low, a corner meets the table,
    and the box is wrenched in the palms. This rolls the composition PathClear checked out
    open loop and takes, at each step, the box's lowest point (its centre less half its
    vertical extent as turned then); it must stay above the table top less ``tolerance_m``
    (the box starts and ends resting on it). A move that does not turn the box about its grasp
    axis passes at once. Reads the table top as the workspace's floor less half the box's z
    extent (:meth:`~planner.port.ObjectSensing.workspace_bounds`).
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing, PalmControl)

    NODE_TYPE: ClassVar[str] = "Condition"
    INPUT_PORTS = {
        "object": PortInformation(str, description="the held object"),
        "composition": PortInformation(
            MovePlan, description="the move as PathClear composed and checked it"
        ),
        "tolerance_m": PortInformation(
            float,
            required=False,
            default_value=0.003,
            description="how far below the table top the predicted lowest point may pass, m",
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        """SUCCESS if the turning box clears the table all the way; FAILURE saying where not."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        world = self.world
        name = self.get_input("object")
        plan: MovePlan = self.get_input("composition")
        extents = world.object_extents(name)
        start = plan.start.object.orientation
        goal = plan.move.goal.orientation
        needed = turn_lift_m(extents, start, goal)
        if needed == 0.0:
            return self.succeed("no turn about the grasp axis")
        top = float(world.workspace_bounds(name)[0][2] - extents[2] / 2.0)
        n = int(np.ceil((plan.composer.target.tau + 0.5) / self.control_dt))
        path = plan.fresh().rollout(n, self.control_dt)
        lowest = path.object_positions[:, 2] - vertical_half_extent(
            extents, path.object_orientations
        )
        gap = lowest - top
        k = int(np.argmin(gap))
        lift = float(np.max(path.object_positions[:, 2]) - path.object_positions[0, 2])
        text = (
            f"lowest corner {gap[k] * 1000:.1f} mm above the table at step {k} of {n} "
            f"(the turn needs a lift of {needed * 1000:.0f} mm; predicted {lift * 1000:.0f} mm)"
        )
        if gap[k] >= -float(self.get_input("tolerance_m")):
            return self.succeed(text)
        return self.fail(text)

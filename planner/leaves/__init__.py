"""The robot's leaves. Importing this package registers them for the XML loader."""

from planner.leaves.approach import Approach
from planner.leaves.base import MotionLeaf, WorldLeaf
from planner.leaves.clears_table import TurnClearsTable
from planner.leaves.conditions import AtGoal, IsHeld, PathClear
from planner.leaves.grasp import Grasp
from planner.leaves.insert import Insert
from planner.leaves.release import Release, Retreat
from planner.leaves.select import SelectSkills
from planner.leaves.transport import Transport
from planner.leaves.turning import GripTurns

__all__ = [
    "Approach",
    "AtGoal",
    "Grasp",
    "GripTurns",
    "Insert",
    "IsHeld",
    "MotionLeaf",
    "PathClear",
    "Release",
    "Retreat",
    "SelectSkills",
    "Transport",
    "TurnClearsTable",
    "WorldLeaf",
]

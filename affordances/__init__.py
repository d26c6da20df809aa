"""Affordance reasoning: object context to semantic actions. Never imports pybullet."""

from affordances.actions import (
    DEFAULT_SPACE,
    GRASP_ORDER,
    ParamValue,
    SemanticAction,
    SkillSelection,
)
from affordances.config import ReasonerConfig
from affordances.context import (
    PAPER_ROBOT,
    Fragility,
    ObjectContext,
    ObjectState,
    Obstacle,
    RobotCapabilities,
    Shape,
    make_object_context,
)
from affordances.grip_physics import (
    combined_friction,
    grip_friction_n,
    palm_contact_friction,
    required_squeeze_force,
    spare_grip_acceleration,
)
from affordances.reasoner import AffordanceReasoner, needs_both_arms, reason
from affordances.report import render_json, render_text, to_json_data
from affordances.rule_file import RuleFileError, default_rules, load_rules, parse_rules, rule_set
from affordances.rules import Rule
from affordances.scene import GeometricSceneQuery, SceneQuery

__all__ = [
    "DEFAULT_SPACE",
    "GRASP_ORDER",
    "PAPER_ROBOT",
    "AffordanceReasoner",
    "Fragility",
    "GeometricSceneQuery",
    "ObjectContext",
    "ObjectState",
    "Obstacle",
    "ParamValue",
    "ReasonerConfig",
    "RobotCapabilities",
    "Rule",
    "RuleFileError",
    "SceneQuery",
    "SemanticAction",
    "Shape",
    "SkillSelection",
    "combined_friction",
    "default_rules",
    "grip_friction_n",
    "load_rules",
    "make_object_context",
    "needs_both_arms",
    "palm_contact_friction",
    "parse_rules",
    "reason",
    "render_json",
    "render_text",
    "required_squeeze_force",
    "rule_set",
    "spare_grip_acceleration",
    "to_json_data",
]

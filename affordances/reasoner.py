"""Object context -> ranked semantic actions, in three stages.

1. Hard physics constraints (:mod:`affordances.physics`) fix how many arms and which grasps
   are feasible, the grasp-maintenance skill and the orientation constraints.
2. Scene checks (:mod:`affordances.scene`) ask the collision port how close obstacles come
   to the object's path and to the arms, per grasp, and add avoidance skills.
3. Soft rules (:mod:`affordances.rules`) score each grasp and tune skills; they see the
   facts of stages 1 and 2 (e.g. ``elements: [obstacle_near_path]``).

Grasps are ranked by summed rule weight; ties keep :data:`~affordances.actions.GRASP_ORDER`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

from affordances.actions import GRASP_ORDER, ParamValue, SemanticAction, SkillSelection, sort_skills
from affordances.config import ReasonerConfig
from affordances.context import ObjectContext, RobotCapabilities
from affordances.object_geometry import grip_width, object_height
from affordances.physics import GraspOption, HardAssessment, assess
from affordances.rule_file import default_rules
from affordances.rules import (
    Fact,
    FactValue,
    GraspEffect,
    ParamEffect,
    Rule,
    SkillEffect,
)
from affordances.scene import GeometricSceneQuery, SceneQuery, check_scene
from skills.vocabulary import Action, GraspType


def object_facts(context: ObjectContext, hard: HardAssessment) -> dict[Fact, FactValue]:
    """Facts about the object that rules can match (the grasp and scene facts come later)."""
    return {
        Fact.NAME: context.name.lower(),
        Fact.CATEGORY: context.category,
        Fact.SHAPE: context.shape.value,
        Fact.MATERIAL: context.material,
        Fact.FRAGILITY: context.fragility.value,
        Fact.MASS_KG: context.mass_kg,
        Fact.FRICTION: context.friction,
        Fact.WIDTH_M: grip_width(context),
        Fact.HEIGHT_M: object_height(context),
        Fact.STATE: frozenset(s.value for s in context.state),
        Fact.ELEMENTS: frozenset(e.value for e in hard.elements),
    }


def _fmt_weight(weight: float) -> str:
    return f"{weight:+g}"


def _apply_param(
    skills: dict[Action, SkillSelection], effect: ParamEffect, hard_limits: dict[str, float]
) -> tuple[bool, str]:
    """Set a parameter on a composed skill; a squeeze force is clamped to what physics allows."""
    skill = skills.get(effect.action)
    if skill is None:
        return False, ""
    value: ParamValue = effect.value
    note = ""
    if (
        effect.name == "squeeze_force_n"
        and isinstance(value, float)
        and "required_force_n" in skill.params
    ):
        required = skill.params["required_force_n"]
        low = required if isinstance(required, float) else 0.0
        high = hard_limits["squeeze_force_n"]
        clamped = min(max(value, low), high)
        if clamped != value:
            note = f" (clamped to {clamped:.3g} N: needs >= {low:.3g}, has <= {high:.3g})"
        value = clamped
    params = dict(skill.params)
    params[effect.name] = value
    skills[effect.action] = replace(skill, params=params)
    shown = f"{value:g}" if isinstance(value, float) else value
    return True, f"{effect.name} = {shown} for {effect.action.value}{note}"


def _compose(
    context: ObjectContext,
    robot: RobotCapabilities,
    hard: HardAssessment,
    option: GraspOption,
    rules: Sequence[Rule],
    scene: SceneQuery,
    config: ReasonerConfig,
) -> tuple[SemanticAction | None, list[str]]:
    """The option's action with its skills and score; or None and why, when a rule vetoes it."""
    skills: dict[Action, SkillSelection] = {s.action: s for s in (*option.skills, *hard.skills)}
    because = [*hard.because, *option.because]

    findings = check_scene(context, option, scene, config)
    for skill in findings.skills:
        skills[skill.action] = skill
    because.extend(findings.because)

    facts = object_facts(context, hard)
    elements = frozenset(e.value for e in hard.elements | findings.elements)
    facts[Fact.ELEMENTS] = elements
    facts[Fact.GRASP] = option.grasp.value
    limits = {"squeeze_force_n": robot.squeeze_force_n}

    score = 0.0
    vetoes: list[str] = []
    for rule in rules:
        if not rule.matches(facts):
            continue
        matched = rule.describe(facts)
        for effect in rule.effects:
            if isinstance(effect, GraspEffect):
                if effect.grasp == option.grasp and effect.veto:
                    vetoes.append(f"rule {rule.name} vetoes {option.grasp.value}: {matched}")
                elif effect.grasp == option.grasp:
                    score += effect.weight
                    because.append(f"rule {rule.name} ({_fmt_weight(effect.weight)}): {matched}")
            elif isinstance(effect, SkillEffect):
                old = skills.get(effect.action)
                params = {**(dict(old.params) if old else {}), **effect.params}
                skills[effect.action] = SkillSelection(
                    effect.action, effect.space, effect.weight, params
                )
                because.append(
                    f"rule {rule.name}: {effect.action.value} (weight {effect.weight:g}): {matched}"
                )
            else:
                applied, what = _apply_param(skills, effect, limits)
                if applied:
                    because.append(f"rule {rule.name}: {what}: {matched}")
    if vetoes:
        return None, vetoes
    action = SemanticAction(
        option.grasp, sort_skills(tuple(skills.values())), score, tuple(because)
    )
    return action, []


def reason(
    context: ObjectContext,
    robot: RobotCapabilities,
    rules: Sequence[Rule] | None = None,
    scene: SceneQuery | None = None,
    config: ReasonerConfig | None = None,
) -> tuple[SemanticAction, ...]:
    """Rank the ways to manipulate an object, best first.

    Parameters
    ----------
    context : ObjectContext
        The object, its surroundings and goals.
    robot : RobotCapabilities
        What the robot can carry and squeeze.
    rules : sequence of Rule, optional
        Soft rules in evaluation order; the shipped defaults if ``None``.
    scene : SceneQuery, optional
        Collision-query port; a :class:`~affordances.scene.GeometricSceneQuery` if ``None``.
    config : ReasonerConfig, optional
        Safety factor and margins; defaults if ``None``.

    Returns
    -------
    tuple of SemanticAction
        Feasible actions no rule vetoes, by descending score (ties in grasp order); a single
        ``GraspType.NONE`` action explaining why when nothing is left.
    """
    config = config or ReasonerConfig()
    rules = default_rules() if rules is None else rules
    scene = scene or GeometricSceneQuery()
    hard = assess(context, robot, config)
    if not hard.options:
        return (SemanticAction(GraspType.NONE, (), 0.0, hard.because),)
    actions: list[SemanticAction] = []
    vetoes: list[str] = []
    for option in hard.options:
        action, vetoed = _compose(context, robot, hard, option, rules, scene, config)
        if action is None:
            vetoes.extend(vetoed)
        else:
            actions.append(action)
    if not actions:
        return (SemanticAction(GraspType.NONE, (), 0.0, (*hard.because, *vetoes)),)
    order = {g: i for i, g in enumerate(GRASP_ORDER)}
    return tuple(sorted(actions, key=lambda a: (-a.score, order[a.grasp])))


@dataclass(frozen=True)
class AffordanceReasoner:
    """Holds the robot, the rules, the scene port and the config; ranks objects.

    Attributes
    ----------
    robot : RobotCapabilities
        What the robot can carry and squeeze.
    rules : tuple of Rule
        Soft rules in evaluation order (the shipped defaults unless given).
    scene : SceneQuery
        Collision-query port.
    config : ReasonerConfig
        Safety factor and margins.
    """

    robot: RobotCapabilities
    rules: tuple[Rule, ...] = field(default_factory=default_rules)
    scene: SceneQuery = field(default_factory=GeometricSceneQuery)
    config: ReasonerConfig = field(default_factory=ReasonerConfig)

    def rank(self, context: ObjectContext) -> tuple[SemanticAction, ...]:
        """Ranked actions for one object (see :func:`reason`)."""
        return reason(context, self.robot, self.rules, self.scene, self.config)

    def rank_all(self, contexts: Sequence[ObjectContext]) -> dict[str, tuple[SemanticAction, ...]]:
        """Ranked actions per object name, in the order given."""
        return {c.name: self.rank(c) for c in contexts}


def needs_both_arms(action: SemanticAction) -> bool:
    """Whether an action's grasp uses both arms."""
    return action.grasp in (GraspType.TWO_PALM_LATERAL, GraspType.TWO_ARM_SUPPORT)

"""What the reasoner outputs: a grasp with the skills to compose, its score and its reasons."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from skills.vocabulary import Action, GraspType, Space

#: A skill parameter: a number (SI units named in the key), a word, or a tuple of words.
ParamValue = float | str | tuple[str, ...]

#: The space each action acts in unless a rule says otherwise (paper Sec. 2.2).
DEFAULT_SPACE: Mapping[Action, Space] = MappingProxyType(
    {
        Action.APPROACH: Space.ABSOLUTE,
        Action.GRASP_LATERAL: Space.RELATIVE,
        Action.TRANSPORT: Space.ABSOLUTE,
        Action.ROTATE_Z: Space.ABSOLUTE,
        Action.ROTATE_GRASP_AXIS: Space.ABSOLUTE,
        Action.AVOID_OBSTACLE: Space.ABSOLUTE,
        Action.AVOID_LINKS: Space.ABSOLUTE,
        Action.HOLD_LATERAL: Space.RELATIVE,
        Action.HOLD_FORCE: Space.RELATIVE,
        Action.KEEP_UPRIGHT: Space.RELATIVE,
        Action.KEEP_LEVEL: Space.RELATIVE,
        Action.LIMIT_REPULSION: Space.ABSOLUTE,
        Action.RELEASE: Space.RELATIVE,
        Action.RETREAT: Space.ABSOLUTE,
        Action.INSERT: Space.ABSOLUTE,
    }
)

#: Order in which grasps are listed when their scores tie: the earlier, the preferred.
GRASP_ORDER: tuple[GraspType, ...] = (
    GraspType.TWO_PALM_LATERAL,
    GraspType.TWO_ARM_SUPPORT,
    GraspType.ONE_ARM_SIDE,
    GraspType.ONE_ARM_TOP,
    GraspType.NONE,
)

_ACTION_ORDER = {action: i for i, action in enumerate(Action)}


def _freeze_params(params: Mapping[str, ParamValue], owner: str) -> Mapping[str, ParamValue]:
    frozen: dict[str, ParamValue] = {}
    for key in sorted(params):
        value = params[key]
        if isinstance(value, bool) or not isinstance(value, int | float | str | tuple | list):
            raise ValueError(
                f"{owner}.params[{key!r}]: expected a number, a string or strings, got {value!r}"
            )
        if isinstance(value, int | float):
            if not math.isfinite(value):
                raise ValueError(
                    f"{owner}.params[{key!r}]: expected a finite number, got {value!r}"
                )
            frozen[key] = float(value)
        elif isinstance(value, tuple | list):
            if not all(isinstance(v, str) for v in value):
                raise ValueError(f"{owner}.params[{key!r}]: expected strings, got {value!r}")
            frozen[key] = tuple(value)
        else:
            frozen[key] = value
    return MappingProxyType(frozen)


@dataclass(frozen=True)
class SkillSelection:
    """One skill to compose into the action.

    Attributes
    ----------
    action : Action
        What the skill does.
    space : Space
        Absolute (object pose in {W}) or relative (palm poses in {O}).
    weight : float
        Composition weight of the skill's coupling term (dimensionless).
    params : mapping of str to ParamValue
        Skill parameters, keys sorted; units are in the key names (``squeeze_force_n``).
    """

    action: Action
    space: Space
    weight: float = 1.0
    params: Mapping[str, ParamValue] = field(default_factory=dict)

    def __post_init__(self) -> None:
        owner = f"SkillSelection {self.action!s}"
        if not math.isfinite(self.weight):
            raise ValueError(f"{owner}.weight: expected a finite number, got {self.weight!r}")
        object.__setattr__(self, "weight", float(self.weight))
        object.__setattr__(self, "params", _freeze_params(self.params, owner))

    def __hash__(self) -> int:
        return hash((self.action, self.space, self.weight, tuple(self.params.items())))


def sort_skills(skills: tuple[SkillSelection, ...]) -> tuple[SkillSelection, ...]:
    """Absolute skills before relative ones, each in :class:`~skills.vocabulary.Action`'s order."""
    return tuple(
        sorted(skills, key=lambda s: (s.space is not Space.ABSOLUTE, _ACTION_ORDER[s.action]))
    )


@dataclass(frozen=True)
class SemanticAction:
    """A grasp and the skills to compose for it, ranked by ``score``.

    Attributes
    ----------
    grasp : GraspType
        How the object is held.
    skills : tuple of SkillSelection
        Skills to compose, in :class:`~skills.vocabulary.Action` order.
    score : float
        Summed weight of the rules that prefer this grasp; higher ranks first.
    because : tuple of str
        Short human-readable reasons: hard constraints, scene checks and fired rules.
    """

    grasp: GraspType
    skills: tuple[SkillSelection, ...]
    score: float
    because: tuple[str, ...]

    def skill(self, action: Action) -> SkillSelection | None:
        """Return the selected skill with this action, or ``None``."""
        return next((s for s in self.skills if s.action == action), None)

    @property
    def actions(self) -> tuple[Action, ...]:
        """Actions of the selected skills, in order."""
        return tuple(s.action for s in self.skills)

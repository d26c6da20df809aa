"""Stage 2: weighted soft rules, written in YAML files users extend without code: what a rule
is, the facts it matches and what it does (reading the files: :mod:`affordances.rule_file`).

A rule file::

    version: 1
    rules:
      - name: parcel_lateral
        description: the paper's parcel is held between both palms
        when:
          category: parcel                 # equals
          material: [glass, ceramic]       # one of
          mass_kg: {gt: 2.0, le: 10.0}     # operators on numbers
          state: {contains: open}          # sets: contains (all), contains_any, excludes
          elements: [wide, parallel_faces] # a list on a set means "contains all"
        effects:
          - {grasp: two_palm_lateral, weight: 2.0}            # adds to that grasp's score
          - {grasp: two_arm_support, veto: true}              # never offers that grasp
          - {skill: hold_force, weight: 0.5, params: {...}}   # composes a skill
          - {param: max_speed, value: 0.2}                    # sets a parameter of a skill

Facts a rule can match are listed in :class:`Fact`. Every condition must hold for the rule
to fire. Rules are evaluated per candidate grasp, so ``grasp`` and the scene elements are
facts too. When several rules set the same parameter or skill weight, the later rule wins
(a user file loaded after the default file overrides it).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum, StrEnum
from types import MappingProxyType
from typing import Any

from affordances.actions import ParamValue
from affordances.context import Fragility, ObjectState, Shape
from skills.vocabulary import Action, AffordanceElement, GraspType, Space


class Fact(StrEnum):
    """Facts about an object and a candidate grasp that rules can match."""

    NAME = "name"
    CATEGORY = "category"
    SHAPE = "shape"
    MATERIAL = "material"
    FRAGILITY = "fragility"
    MASS_KG = "mass_kg"
    FRICTION = "friction"
    WIDTH_M = "width_m"
    HEIGHT_M = "height_m"
    STATE = "state"
    ELEMENTS = "elements"
    GRASP = "grasp"


class Op(StrEnum):
    """Operators of a condition."""

    EQ = "eq"
    NE = "ne"
    GT = "gt"
    GE = "ge"
    LT = "lt"
    LE = "le"
    IN = "in"
    NOT_IN = "not_in"
    CONTAINS = "contains"
    CONTAINS_ANY = "contains_any"
    EXCLUDES = "excludes"


class FactKind(Enum):
    NUMBER = "number"
    TEXT = "text"
    SET = "set"


#: How each fact is compared, and the enum its values must belong to (if any).
FACT_KINDS: Mapping[Fact, tuple[FactKind, type[StrEnum] | None]] = {
    Fact.NAME: (FactKind.TEXT, None),
    Fact.CATEGORY: (FactKind.TEXT, None),
    Fact.SHAPE: (FactKind.TEXT, Shape),
    Fact.MATERIAL: (FactKind.TEXT, None),
    Fact.FRAGILITY: (FactKind.TEXT, Fragility),
    Fact.MASS_KG: (FactKind.NUMBER, None),
    Fact.FRICTION: (FactKind.NUMBER, None),
    Fact.WIDTH_M: (FactKind.NUMBER, None),
    Fact.HEIGHT_M: (FactKind.NUMBER, None),
    Fact.STATE: (FactKind.SET, ObjectState),
    Fact.ELEMENTS: (FactKind.SET, AffordanceElement),
    Fact.GRASP: (FactKind.TEXT, GraspType),
}

KIND_OPS: Mapping[FactKind, tuple[Op, ...]] = {
    FactKind.NUMBER: (Op.EQ, Op.NE, Op.GT, Op.GE, Op.LT, Op.LE, Op.IN, Op.NOT_IN),
    FactKind.TEXT: (Op.EQ, Op.NE, Op.IN, Op.NOT_IN),
    FactKind.SET: (Op.CONTAINS, Op.CONTAINS_ANY, Op.EXCLUDES),
}

_SYMBOLS = {Op.EQ: "=", Op.NE: "!=", Op.GT: ">", Op.GE: ">=", Op.LT: "<", Op.LE: "<="}

#: Skill each known parameter belongs to when an effect does not name one.
PARAM_SKILLS: Mapping[str, Action] = MappingProxyType(
    {
        "squeeze_force_n": Action.HOLD_LATERAL,
        "max_speed": Action.TRANSPORT,
        "obstacle_gain": Action.AVOID_OBSTACLE,
        "link_gain": Action.AVOID_LINKS,
    }
)

#: What each known parameter may be: (low, high, unit, low end open). A squeeze of 0 N holds
#: nothing and a speed of -1 m/s is no speed; gains of 0 switch a skill off, which is allowed.
PARAM_RANGES: Mapping[str, tuple[float, float, str, bool]] = MappingProxyType(
    {
        "squeeze_force_n": (0.0, 1000.0, "N", True),
        "max_speed": (0.0, 10.0, "m/s", True),
        "obstacle_gain": (0.0, 100.0, "", False),
        "link_gain": (0.0, 100.0, "", False),
    }
)

#: A fact's value: text, a number, or a set of words.
FactValue = str | float | frozenset[str]
Facts = Mapping[Fact, FactValue]


@dataclass(frozen=True)
class Condition:
    """One test of a fact, e.g. ``mass_kg > 2.0``.

    Attributes
    ----------
    fact : Fact
        The fact tested.
    op : Op
        The operator.
    value : float, str or tuple of str
        The operand; a tuple for ``in``, ``not_in`` and the set operators.
    """

    fact: Fact
    op: Op
    value: float | str | tuple[str, ...] | tuple[float, ...]

    def holds(self, facts: Facts) -> bool:
        """Whether the condition holds for these facts (a missing fact never holds)."""
        if self.fact not in facts:
            return False
        actual = facts[self.fact]
        value = self.value
        if isinstance(actual, frozenset):
            wanted = set(value) if isinstance(value, tuple) else {value}
            if self.op == Op.CONTAINS:
                return wanted <= actual
            if self.op == Op.CONTAINS_ANY:
                return bool(wanted & actual)
            return not wanted & actual
        if self.op == Op.IN:
            return isinstance(value, tuple) and actual in value
        if self.op == Op.NOT_IN:
            return isinstance(value, tuple) and actual not in value
        if self.op == Op.EQ:
            return actual == value
        if self.op == Op.NE:
            return actual != value
        if not isinstance(actual, float) or not isinstance(value, float):
            return False
        if self.op == Op.GT:
            return actual > value
        if self.op == Op.GE:
            return actual >= value
        if self.op == Op.LT:
            return actual < value
        return actual <= value

    def describe(self, facts: Facts) -> str:
        """Short text, e.g. ``mass_kg 12 > 5`` or ``category parcel``."""
        actual = facts.get(self.fact)
        shown = ", ".join(sorted(actual)) if isinstance(actual, frozenset) else _show(actual)
        value = self.value
        operand = ", ".join(_show(v) for v in value) if isinstance(value, tuple) else _show(value)
        if self.op == Op.EQ:
            return f"{self.fact.value} {operand}"
        if self.op in _SYMBOLS:
            return f"{self.fact.value} {shown} {_SYMBOLS[self.op]} {operand}"
        if self.op in (Op.IN, Op.NOT_IN):
            word = "in" if self.op == Op.IN else "not in"
            return f"{self.fact.value} {shown} {word} [{operand}]"
        word = {
            Op.CONTAINS: "contains",
            Op.CONTAINS_ANY: "contains any of",
            Op.EXCLUDES: "excludes",
        }[self.op]
        return f"{self.fact.value} {word} {operand}"


def _show(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


@dataclass(frozen=True)
class GraspEffect:
    """Add ``weight`` to the score of ``grasp``; or, with ``veto``, never offer it."""

    grasp: GraspType
    weight: float
    veto: bool = False


@dataclass(frozen=True)
class SkillEffect:
    """Compose ``action`` in ``space`` with composition ``weight`` and extra ``params``."""

    action: Action
    space: Space
    weight: float
    params: Mapping[str, ParamValue]


@dataclass(frozen=True)
class ParamEffect:
    """Set parameter ``name`` of the skill ``action`` to ``value`` (if that skill is composed)."""

    name: str
    value: float | str
    action: Action


Effect = GraspEffect | SkillEffect | ParamEffect


@dataclass(frozen=True)
class Rule:
    """A named pattern of facts and what it does when it matches.

    Attributes
    ----------
    name : str
        Unique name within its file.
    conditions : tuple of Condition
        All must hold; none means the rule always fires.
    effects : tuple of Effect
        What the rule does.
    source : str
        File (or label) the rule came from.
    description : str
        Free text for people.
    """

    name: str
    conditions: tuple[Condition, ...]
    effects: tuple[Effect, ...]
    source: str = "<memory>"
    description: str = ""

    def matches(self, facts: Facts) -> bool:
        """Whether every condition holds."""
        return all(c.holds(facts) for c in self.conditions)

    def describe(self, facts: Facts) -> str:
        """The matched conditions as text, e.g. ``category parcel, mass_kg 1 <= 5``."""
        return ", ".join(c.describe(facts) for c in self.conditions) or "always"

"""A skill: a coupling term, the space it acts in, its semantic labels and its provenance.

A skill is stored as data (its kind, scalar parameters and arrays) so that a library can be
saved and loaded; :meth:`Skill.pose_model` rebuilds a learnt DMP from it, and the skill's
coupling term is built at run time, when the scene (obstacles, distances, forces) is known,
by :mod:`skills.runtime`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime
from enum import StrEnum
from types import MappingProxyType

import numpy as np

from skills.basis import RBFBasis
from skills.dmp import DMPParams, ForcingTerm, PositionModel
from skills.pose_dmp import PoseModel
from skills.quaternion_dmp import OrientationModel
from skills.scaling import Scaling
from skills.types import Array
from skills.vocabulary import Action, AffordanceElement, Space


class SkillKind(StrEnum):
    """How a skill's coupling term is represented."""

    LEARNT_DMP = "learnt_dmp"
    OBSTACLE_STEERING = "obstacle_steering"
    POTENTIAL_FIELD = "potential_field"
    GRASP_MAINTENANCE = "grasp_maintenance"
    FORCE_TRACKING = "force_tracking"
    WORKSPACE_REPULSION = "workspace_repulsion"


Scalar = float | int | str | bool

#: What a skill label must look like: an identifier, so that world files and trees can name it.
LABEL_PATTERN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def is_skill_name(name: str) -> bool:
    """Whether ``name`` can name a skill: letters, digits, '_' or '-', at least one."""
    return bool(name) and name.replace("_", "").replace("-", "").isalnum()


def check_label(label: str, field_name: str = "skill label") -> str:
    """``label`` if it is an identifier (``[A-Za-z_][A-Za-z0-9_]*``); ValueError otherwise."""
    if not isinstance(label, str) or LABEL_PATTERN.fullmatch(label) is None:
        raise ValueError(
            f"{field_name}: expected an identifier (a letter or '_', then letters, digits "
            f"or '_'), got {label!r}"
        )
    return label


@dataclass(frozen=True)
class Provenance:
    """Where a skill came from.

    Attributes
    ----------
    demonstrations : tuple of str
        Demonstration files or ids it was learnt from.
    learnt_at : str
        ISO 8601 UTC time stamp.
    method : str
        How it was learnt, in words.
    fit : Mapping[str, float]
        Fit figures (residuals, sample counts).
    """

    demonstrations: tuple[str, ...]
    learnt_at: str
    method: str
    fit: Mapping[str, float] = field(default_factory=dict)

    @staticmethod
    def now(
        demonstrations: tuple[str, ...],
        method: str,
        fit: Mapping[str, float] | None = None,
        when: datetime | None = None,
    ) -> Provenance:
        """Provenance stamped with ``when`` (default: now, UTC, to the second)."""
        stamp = (when or datetime.now(UTC)).replace(microsecond=0).isoformat()
        return Provenance(demonstrations, stamp, method, MappingProxyType(dict(fit or {})))


@dataclass(frozen=True)
class Skill:
    """A primitive skill of the library.

    Attributes
    ----------
    name : str
        Unique within a library.
    action : Action
        Its kind: how the planner uses it (``transport``, ``rotate_z``, ``avoid_obstacle``,
        ``hold_lateral``, ...).
    space : Space
        Absolute (the object's pose) or relative (each palm in the object frame).
    kind : SkillKind
        How its coupling term is represented.
    elements : tuple of AffordanceElement
        The affordance elements it serves.
    params : Mapping[str, Scalar]
        Scalar parameters.
    arrays : Mapping[str, ndarray]
        Array parameters (DMP weights, reference displacements, ...).
    provenance : Provenance
    label : str
        What a user calls it, an identifier (a taught ``my_wave``); a world's move or a
        Transport port can name it. Defaults to the action's value (``transport``).
    """

    name: str
    action: Action
    space: Space
    kind: SkillKind
    elements: tuple[AffordanceElement, ...]
    params: Mapping[str, Scalar]
    arrays: Mapping[str, Array]
    provenance: Provenance
    label: str = ""

    def __post_init__(self) -> None:
        if not is_skill_name(self.name):
            raise ValueError(f"skill name: expected letters, digits, '_' or '-', got {self.name!r}")
        object.__setattr__(self, "label", check_label(self.label or self.action.value))
        object.__setattr__(self, "params", MappingProxyType(dict(self.params)))
        object.__setattr__(
            self, "arrays", MappingProxyType({k: np.asarray(v) for k, v in self.arrays.items()})
        )

    def serves(self, element: AffordanceElement) -> bool:
        """Whether the skill is labelled with ``element``."""
        return element in self.elements

    def pose_model(self) -> PoseModel:
        """The learnt pose DMP of a ``LEARNT_DMP`` skill."""
        if self.kind is not SkillKind.LEARNT_DMP:
            raise ValueError(f"skill {self.name!r}: expected a learnt_dmp skill, got {self.kind}")
        return model_from_data(self.params, self.arrays)


def model_to_data(model: PoseModel) -> tuple[dict[str, Scalar], dict[str, Array]]:
    """Split a pose DMP into scalar parameters and arrays for storage."""
    p = model.params
    params: dict[str, Scalar] = {
        "alpha": p.alpha,
        "alpha_s": p.alpha_s,
        "n_basis": p.n_basis,
        "overlap": p.overlap,
        "regularisation": p.regularisation,
        "position_scaling": model.position.forcing.scaling.value,
        "orientation_scaling": model.orientation.forcing.scaling.value,
        "min_amplitude": model.position.forcing.min_amplitude,
        "min_rotation": model.orientation.forcing.min_amplitude,
        "demo_tau": model.demo_tau,
    }
    arrays = {
        "position_weights": model.position.forcing.weights,
        "orientation_weights": model.orientation.forcing.weights,
        "position_reference": model.position.forcing.reference,
        "orientation_reference": model.orientation.forcing.reference,
        "centres": model.position.forcing.basis.centres,
        "widths": model.position.forcing.basis.widths,
        "demo_start_position": model.position.demo_start,
        "demo_goal_position": model.position.demo_goal,
        "demo_start_orientation": model.orientation.demo_start,
        "demo_goal_orientation": model.orientation.demo_goal,
    }
    return params, arrays


def model_from_data(params: Mapping[str, Scalar], arrays: Mapping[str, Array]) -> PoseModel:
    """Inverse of :func:`model_to_data`."""
    p = DMPParams(
        alpha=float(params["alpha"]),
        alpha_s=float(params["alpha_s"]),
        n_basis=int(params["n_basis"]),
        overlap=float(params["overlap"]),
        regularisation=float(params["regularisation"]),
    )
    basis = RBFBasis(np.asarray(arrays["centres"], float), np.asarray(arrays["widths"], float))
    shapes = {
        "centres": (p.n_basis,),
        "widths": (p.n_basis,),
        "position_weights": (p.n_basis, 3),
        "orientation_weights": (p.n_basis, 3),
        "position_reference": (3,),
        "orientation_reference": (3,),
        "demo_start_position": (3,),
        "demo_goal_position": (3,),
        "demo_start_orientation": (4,),
        "demo_goal_orientation": (4,),
    }
    for key, shape in shapes.items():
        got = np.shape(arrays[key])
        if got != shape:
            raise ValueError(f"{key}: expected shape {shape} for n_basis={p.n_basis}, got {got}")
    tau = float(params["demo_tau"])
    pos = PositionModel(
        p,
        ForcingTerm(
            np.asarray(arrays["position_weights"], float),
            basis,
            np.asarray(arrays["position_reference"], float),
            Scaling(str(params["position_scaling"])),
            float(params["min_amplitude"]),
        ),
        np.asarray(arrays["demo_start_position"], float),
        np.asarray(arrays["demo_goal_position"], float),
        tau,
    )
    ori = OrientationModel(
        p,
        ForcingTerm(
            np.asarray(arrays["orientation_weights"], float),
            basis,
            np.asarray(arrays["orientation_reference"], float),
            Scaling(str(params["orientation_scaling"])),
            float(params["min_rotation"]),
        ),
        np.asarray(arrays["demo_start_orientation"], float),
        np.asarray(arrays["demo_goal_orientation"], float),
        tau,
    )
    return PoseModel(pos, ori)


def learnt_skill(
    name: str,
    action: Action,
    space: Space,
    model: PoseModel,
    elements: tuple[AffordanceElement, ...],
    provenance: Provenance,
    label: str = "",
) -> Skill:
    """A ``LEARNT_DMP`` skill holding ``model`` (``label`` defaults to the action's value)."""
    params, arrays = model_to_data(model)
    return Skill(
        name, action, space, SkillKind.LEARNT_DMP, elements, params, arrays, provenance, label
    )

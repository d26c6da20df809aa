"""Teaching a skill from a recorded demonstration, as ``app.py teach`` does, from Python.

:func:`teach` reads a demonstration CSV, smooths it (:func:`skills.demo_conditioning.low_pass`),
recognises it against a library's learnt skills (:func:`skills.recognition.recognise`) and,
when it matches none (or ``force``), learns it as a pose DMP, rolls the skill out between the
demonstration's own start and goal to check that it settles there
(:func:`skills.demo_conditioning.reproduction`), and adds it to the library folder, saved
atomically. Nothing is written unless the skill is added.

Bad input raises :class:`TeachingError`: its ``field`` names the argument at fault (None when
the message already starts with the file), and the message says what was expected. A caller
that offers the arguments under other names (a command line's ``--smooth-ms``) passes them in
``names``, and the messages use them.

    >>> from skills.teaching import teach
    >>> lesson = teach("my_wave.csv", "mylib", "my_wave", Space.ABSOLUTE)  # doctest: +SKIP
    >>> lesson.added, lesson.reproduction.rms_m  # doctest: +SKIP
    ('my_wave', 0.0007)
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import TypeVar

from skills import quaternion as quat
from skills.default_library import default_library
from skills.demo_conditioning import (
    DEFAULT_SMOOTHING_S,
    END_SPEED_SHARE,
    END_WINDOW_S,
    MAX_REPRODUCTION_SHARE,
    MAX_SETTLE_DEG,
    MAX_SETTLE_M,
    Reproduction,
    ends_moving,
    even_steps,
    low_pass,
    reproduction,
    trim_rest,
)
from skills.demonstration import Demonstration
from skills.demos.io import read_demo_csv
from skills.library import SkillLibrary, check_save_target
from skills.pose_dmp import fit_pose
from skills.pose_model import (
    MIN_AMPLITUDE_M,
    MIN_ROTATION_RAD,
    PoseModel,
    check_pose_demonstration,
)
from skills.recognition import DEFAULT_THRESHOLD, Recognition, recognise
from skills.scaling import SHAPE_SHARE, Scaling, shape_floor
from skills.skill import Provenance, Skill, check_label, is_skill_name, learnt_skill
from skills.vocabulary import Action, Space

__all__ = ["Lesson", "TeachingError", "teach", "teaching_action"]

EnumT = TypeVar("EnumT", bound=Enum)

#: How the skill is learnt, as its provenance records it.
METHOD = "pose DMP, 50 RBF per dimension, ridge regression"
#: What a ``transport`` skill adds to :data:`METHOD`.
TRANSPORT_METHOD = (
    "; forcing turned and scaled about the vertical to new starts and goals, its turn scaled "
    "to theirs"
)


class TeachingError(ValueError):
    """A demonstration, library or argument :func:`teach` cannot take.

    Attributes
    ----------
    field : str or None
        The argument at fault, as the caller named it (``names``), which the message starts
        with; None when it starts with the file at fault.
    """

    def __init__(self, message: str, field: str | None = None) -> None:
        self.field = field
        super().__init__(message)


@dataclass(frozen=True)
class Lesson:
    """What :func:`teach` found and did.

    Attributes
    ----------
    recognition : Recognition
        The smoothed demonstration against the library's learnt skills of its space.
    smoothing_s : float
        The smoothing it was recognised and learnt with, s.
    library : Path
        The library folder.
    reproduction : Reproduction or None
        The learnt skill rolled out against the demonstration; None when nothing was learnt
        (it matched a skill already there).
    added : Skill or None
        The skill added to the library, None when it matched one (and not ``force``).
    """

    recognition: Recognition
    smoothing_s: float
    library: Path
    reproduction: Reproduction | None = None
    added: Skill | None = None


def teaching_action(
    label: str,
    space: Space,
    action: Action | str | None = None,
    names: Mapping[str, str] | None = None,
) -> Action:
    """The action kind a taught skill gets: ``action`` if given; else its label's when the label
    is an action kind; else ``transport`` for an absolute skill (a learnt motion of the object,
    which a move can name). A relative skill with any other label needs ``action``."""
    field = (names or {}).get("action", "action")
    if action is not None:
        return _member(Action, action, field)
    kinds = {a.value: a for a in Action}
    if label in kinds:
        return kinds[label]
    if Space(space) is Space.ABSOLUTE:
        return Action.TRANSPORT
    raise TeachingError(
        f"{field}: expected one of {', '.join(kinds)} for the relative skill {label!r} "
        "(its label is not an action kind)",
        field,
    )


def teach(
    demo: str | os.PathLike[str],
    library: str | os.PathLike[str],
    label: str,
    space: Space | str,
    action: Action | str | None = None,
    name: str | None = None,
    smoothing_s: float = DEFAULT_SMOOTHING_S,
    threshold: float = DEFAULT_THRESHOLD,
    force: bool = False,
    report: Callable[[str], None] | None = None,
    names: Mapping[str, str] | None = None,
) -> Lesson:
    """Learn the demonstration in CSV file ``demo`` as a skill of ``library`` (a folder; a new
    one starts from the default library) unless it is a skill the library has already.

    Parameters
    ----------
    demo : path
        The demonstration CSV (:func:`skills.demos.io.read_demo_csv`).
    library : path
        The library folder to add to: a saved library, or nothing yet.
    label : str
        The skill's label, an identifier (``my_wave``).
    space : Space or str
        Absolute (the object's motion) or relative (the palms' in the object's frame).
    action : Action or str, optional
        Its kind (:func:`teaching_action` when None).
    name : str, optional
        The new skill's name; None: the file's stem.
    smoothing_s : float
        The Gaussian smoothing's standard deviation, s, in [0, 1]; 0 learns the samples.
    threshold : float
        The cosine similarity in [-1, 1] at which it is a known skill.
    force : bool
        Add it even when it matches a skill of the library.
    report : callable, optional
        Called with each line of what was found (the closest skill, the reproduction, what
        was added), as ``app.py teach`` prints them.
    names : mapping of str to str
        The caller's names of the arguments, for the messages (``{"smoothing_s":
        "--smooth-ms"}``); an argument not in it goes by its own name.

    Returns
    -------
    Lesson

    Raises
    ------
    TeachingError
        A bad argument, an unreadable or unusable demonstration, a library folder that is
        not one, a name already in the library, or a skill that does not settle at its goal;
        nothing is written.
    """
    names = dict(names or {})
    say = report or (lambda line: None)

    def name_of(argument: str) -> str:
        return names.get(argument, argument)

    try:
        label = check_label(label, name_of("label"))
    except ValueError as err:
        raise TeachingError(str(err), name_of("label")) from None
    space = _member(Space, space, name_of("space"))
    kind = teaching_action(label, space, action, names)
    if not (math.isfinite(smoothing_s) and 0.0 <= smoothing_s <= 1.0):
        field = name_of("smoothing_s")
        raise TeachingError(f"{field}: expected 0 to 1 s, got {smoothing_s}", field)
    if not -1.0 <= threshold <= 1.0:
        field = name_of("threshold")
        raise TeachingError(
            f"{field}: expected a cosine similarity in [-1, 1], got {threshold}", field
        )
    new_name = name if name is not None else Path(demo).stem
    if not is_skill_name(new_name):  # before the recording is read, smoothed and fitted
        field = name_of("name")
        given = "" if name is not None else f" (the file's name, without {field})"
        raise TeachingError(
            f"{field}: expected a skill name of letters, digits, '_' or '-', got "
            f"{new_name!r}{given}",
            field,
        )
    folder = Path(library)
    try:
        check_save_target(folder)
        recorded = read_demo_csv(demo).demonstration
        skills = (
            SkillLibrary.load(folder) if (folder / "library.json").exists() else default_library()
        )
        check_pose_demonstration(recorded)  # before recognition compares it with anything
    except ValueError as err:  # DemoFileError, LibraryFileError: the message starts with the file
        raise TeachingError(str(err)) from None
    even, resampled = even_steps(recorded)
    if resampled:
        say(f"note: {resampled}")
    # The rest before the motion and after it, found smoothed at least as the default does,
    # is cut from the recording and from what is learnt alike.
    motion = low_pass(even, max(smoothing_s, DEFAULT_SMOOTHING_S))
    even, before, after = trim_rest(even, motion)
    if before or after:
        recorded, _, _ = trim_rest(recorded, motion)
        say(
            f"note: trimmed the rest recorded before the motion ({before:.2f} s) and after it "
            f"({after:.2f} s): the skill would have waited as long at every use"
        )
    smoothed = low_pass(even, smoothing_s)  # recognised and learnt smoothed
    match = recognise(skills, smoothed, space, threshold)
    lesson = Lesson(match, smoothing_s, folder)
    if match.best is None:
        say(f"no {space.value} learnt skill to compare with: a new skill")
    else:
        verdict = "matches" if match.matched else "does not match"
        say(
            f"closest skill: {match.best} (similarity {match.similarity:.3f}); "
            f"{verdict} at threshold {match.threshold:g}"
        )
    if match.matched and not force:
        say(
            f"not added: it is the skill {match.best!r} already "
            f"(use {name_of('force')} to add anyway)"
        )
        return lesson
    if new_name in skills:
        field = name_of("name")
        raise TeachingError(
            f"{field}: expected a new skill name, got {new_name!r} (already in the library)", field
        )
    model, method, shaped = _learn(demo, smoothed, kind)
    if shaped:
        say(f"note: {shaped}")
    # The skill must do what was shown before it is kept: rolled out between the
    # demonstration's own start and goal, and past its duration, where a forcing fitted to
    # noise throws it off its goal.
    # Measured against the recording itself: the smoothing's own change is part of what is
    # learnt (a 40 ms smoothing moved a 0.6 s demonstration 10 mm).
    shown = reproduction(model, recorded)
    say(
        f"reproduces the demonstration within {1000.0 * shown.rms_m:.1f} mm RMS; after its "
        f"duration stays within {1000.0 * shown.settle_m:.1f} mm and "
        f"{shown.settle_deg:.1f} deg of its goal"
    )
    moving = _moving_end(recorded, smoothed, smoothing_s)
    if moving:
        # Whether or not its skill strays: the motion's end was never shown.
        raise TeachingError(
            f"{demo}: expected a recording that ends at rest (over its last "
            f"{1000.0 * END_WINDOW_S:.0f} ms under {END_SPEED_SHARE:.0%} of its peak speed and "
            f"turn rate), got {moving}: record until the motion has stopped. Nothing was "
            "added."
        )
    if not shown.settles:
        raise TeachingError(_unsettled(demo, shown, smoothing_s, name_of))
    if not shown.follows:
        raise TeachingError(
            f"{demo}: expected a skill that follows its demonstration (within "
            f"{1000.0 * shown.allowed_rms_m:.0f} mm RMS, {MAX_REPRODUCTION_SHARE:.0%} of its "
            f"{1000.0 * shown.extent_m:.0f} mm extent), got {1000.0 * shown.rms_m:.0f} mm: "
            f"spikes or jumps in the recording, or a smoothing ({name_of('smoothing_s')}) too "
            "wide for so short a motion. Nothing was added."
        )
    try:
        skill = learnt_skill(
            new_name,
            kind,
            space,
            model,
            (),
            Provenance.now((Path(demo).name,), method),
            label,
        )
    except ValueError as err:
        raise TeachingError(f"{name_of('name')}: {err}", name_of("name")) from None
    skills.add(skill)
    try:
        skills.save(folder)
    except OSError as err:  # a read-only parent, a full disk: nothing half-written stays
        raise TeachingError(
            f"{folder}: expected to save the library, got {err.strerror or err}"
        ) from None
    say(f"added skill {new_name!r} labelled {label!r} ({kind.value}, {space.value}) to {folder}")
    winner = skills.named(label, space)
    if winner.name != new_name:
        # A label names one skill to a move or a tree: the skill so named, else the first so
        # labelled. A re-recorded skill under the old label would never run, without a word.
        say(
            f"note: {label!r} names {winner.name!r} to a move or a tree that gives it "
            f"({'its name' if winner.name == label else 'labelled so before'}); give "
            f"{new_name!r} to run this one"
        )
    return Lesson(match, smoothing_s, folder, shown, skill)


def _member(kind: type[EnumT], value: object, field: str) -> EnumT:
    """``value`` as a member of the enum ``kind`` (a member or its value); TeachingError
    naming ``field`` and the members otherwise."""
    try:
        return kind(value)
    except ValueError:
        members = ", ".join(str(m.value) for m in kind)
        raise TeachingError(f"{field}: expected one of {members}, got {value!r}", field) from None


def _learn(
    demo: str | os.PathLike[str], smoothed: Demonstration, kind: Action
) -> tuple[PoseModel, str, str]:
    """The pose DMP fitted to ``smoothed``, how it was learnt and what it replays unscaled
    ("" if nothing). A transport is turned and scaled about the vertical to any start and
    goal, as the shipped carry, so that a move in another direction is the same shape; any
    other skill scales each axis by its change (:data:`skills.scaling.Scaling.AMPLITUDE`),
    but an axis whose change is small beside its excursion keeps its shape as shown
    (:func:`skills.scaling.shape_floor`)."""
    try:
        positions, orientations = smoothed.positions, smoothed.orientations
        assert orientations is not None  # a pose demonstration (check_pose_demonstration)
        turned = quat.rotation_error(orientations, orientations[0])
        min_rotation, turns = shape_floor(turned, turned[-1], MIN_ROTATION_RAD)
        if kind is Action.TRANSPORT:
            # Its turn scaled to each move's, as its path is turned to each move's direction:
            # replayed as shown, a demonstrated 30 degree turn swung the object 22 degrees on
            # a move of none, and overshot a -30 degree goal to -49.
            model = fit_pose(
                smoothed,
                position_scaling=Scaling.ROTATION_Z,
                orientation_scaling=Scaling.AMPLITUDE,
                min_rotation=min_rotation,
            )
            note = _shaped_text([], turns)
            return model, METHOD + TRANSPORT_METHOD + (f"; {note}" if note else ""), note
        min_amplitude, shaped = shape_floor(
            positions, positions[-1] - positions[0], MIN_AMPLITUDE_M
        )
        model = fit_pose(smoothed, min_amplitude=min_amplitude, min_rotation=min_rotation)
        note = _shaped_text(shaped, turns)
        return model, METHOD + (f"; {note}" if note else ""), note
    except ValueError as err:
        text = str(err)
        # The recording's own name (its file's) may already open the message: once is enough.
        if text.startswith(f"{smoothed.name}: "):
            text = text[len(smoothed.name) + 2 :]
        raise TeachingError(f"{demo}: {text}") from None


def _shaped_text(shaped: list[int], turns: list[int]) -> str:
    """What the method says of the axes :func:`skills.scaling.shape_floor` left unscaled."""
    axes = ["xyz"[i] for i in shaped] + [f"rotation about {'xyz'[i]}" for i in turns]
    if not axes:
        return ""
    return (
        f"{', '.join(axes)} replayed as shown, unscaled to new starts and goals (the start-to-"
        f"goal change under {SHAPE_SHARE:.0%} of the excursion: the motion's shape, not its "
        "displacement)"
    )


def _moving_end(recorded: Demonstration, smoothed: Demonstration, smoothing_s: float) -> str:
    """How a recording ends moving (``one that ends moving at 0.152 m/s, its peak 0.236
    m/s``), read smoothed at least as the default does (raw, its speeds are the noise's); ""
    if it ends at rest (:func:`skills.demo_conditioning.ends_moving`)."""
    settled = smoothed if smoothing_s >= DEFAULT_SMOOTHING_S else low_pass(recorded)
    how = ends_moving(settled)
    return f"one that ends {how}" if how else ""


def _unsettled(
    demo: str | os.PathLike[str],
    shown: Reproduction,
    smoothing_s: float,
    name_of: Callable[[str], str],
) -> str:
    """Why a skill that strays from its goal was not added, from a recording that ends at
    rest (:func:`_moving_end`): one too noisy for the smoothing."""
    return (
        f"{demo}: expected a skill that settles at its goal (within "
        f"{1000.0 * MAX_SETTLE_M:.0f} mm and {MAX_SETTLE_DEG:g} deg after its duration), got "
        f"one that strays {1000.0 * shown.settle_m:.0f} mm and {shown.settle_deg:.1f} deg "
        f"from it: the recording is too noisy to learn from as it is (smoothed over "
        f"{1000.0 * smoothing_s:g} ms); try a larger {name_of('smoothing_s')}. Nothing was "
        "added."
    )

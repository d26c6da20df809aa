"""The skill library: add, find by label, list; save and load as a versioned directory.

On disk a library is a folder with ``library.json`` (format name, version, and per skill its
label, action kind, affordance elements, representation, scalar parameters, array names and
provenance) and ``arrays.npz`` (arrays keyed
``<skill>/<array>``). Saving writes a new folder beside the target and swaps it in, so a crash
never leaves half a library; loading validates every field and names the file, the field and
what was expected.

Versions: 2 gives each skill a ``label`` (any identifier, what a world's move names) beside
its ``action`` kind; version 1 files, whose skills had only an action, still load, each skill
labelled with its action's value.
"""

from __future__ import annotations

import json
import os
import shutil
import stat
import tempfile
import zipfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skills.skill import Provenance, Skill, SkillKind, check_label, model_from_data
from skills.skill_data import SkillDataError, check_skill_data, finite_within, short_repr
from skills.types import Array
from skills.vocabulary import Action, AffordanceElement, Space

FORMAT = "duet-skill-library"
VERSION = 2
#: Versions :meth:`SkillLibrary.load` reads (1: no labels; each skill's label is its action).
READABLE_VERSIONS = (1, 2)
META_FILE = "library.json"
ARRAYS_FILE = "arrays.npz"
#: Largest ``library.json`` read (the shipped one is ~10 kB).
MAX_META_BYTES = 16 * 2**20
#: Largest total the arrays of ``arrays.npz`` may expand to (a zip can claim far more than
#: its own size).
MAX_ARRAY_BYTES = 256 * 2**20


class LibraryFileError(ValueError):
    """A library folder that cannot be loaded; names the file, the field and the problem."""

    def __init__(self, file: str | Path, field: str, expected: str, got: Any) -> None:
        self.file, self.field, self.expected, self.got = str(file), field, expected, got
        where = f"{self.file}: {field}: " if field else f"{self.file}: "
        super().__init__(f"{where}expected {expected}, got {got}")


class SkillLibrary:
    """An ordered collection of uniquely named skills."""

    def __init__(self, skills: tuple[Skill, ...] | list[Skill] = ()) -> None:
        self._skills: dict[str, Skill] = {}
        for s in skills:
            self.add(s)

    def add(self, skill: Skill, replace: bool = False) -> None:
        """Add ``skill``; a name already present, or data out of bounds, is a ValueError."""
        if skill.name in self._skills and not replace:
            raise ValueError(
                f"skill name: expected a new name, got {skill.name!r} (already present)"
            )
        try:
            check_skill_data(skill.kind, skill.params, skill.arrays)
        except SkillDataError as err:
            raise ValueError(f"skill {skill.name!r}: {err}") from None
        self._skills[skill.name] = skill

    def __len__(self) -> int:
        return len(self._skills)

    def __iter__(self) -> Iterator[Skill]:
        return iter(self._skills.values())

    def __contains__(self, name: object) -> bool:
        return name in self._skills

    def get(self, name: str) -> Skill:
        """The skill called ``name``."""
        try:
            return self._skills[name]
        except KeyError:
            known = ", ".join(self._skills) or "none"
            raise KeyError(f"skill: expected one of {known}, got {name!r}") from None

    def by_action(self, action: Action, space: Space | None = None) -> tuple[Skill, ...]:
        """Skills labelled with ``action`` (and in ``space`` if given), in insertion order."""
        return tuple(s for s in self if s.action is action and (space is None or s.space is space))

    def first(self, action: Action, space: Space | None = None) -> Skill:
        """The first skill labelled ``action``; KeyError naming the action if none."""
        found = self.by_action(action, space)
        if not found:
            raise KeyError(f"skill library: expected a skill for action {action.value!r}, got none")
        return found[0]

    def named(self, key: str, space: Space | None = None) -> Skill:
        """The skill called ``key``, else the first labelled ``key`` (in ``space`` if given).

        Raises
        ------
        KeyError
            Naming ``key`` and the library's skill names and labels.
        """
        skill = self._skills.get(key)
        if skill is not None and (space is None or skill.space is space):
            return skill
        for s in self:
            if s.label == key and (space is None or s.space is space):
                return s
        pool = [s for s in self if space is None or s.space is space]
        names = ", ".join(s.name for s in pool) or "none"
        labels = ", ".join(dict.fromkeys(s.label for s in pool)) or "none"
        which = (
            f"the library's {space.value} skills" if space is not None else "the library's skills"
        )
        raise KeyError(
            f"skill {key!r}: expected the name or label of one of {which} "
            f"(names: {names}; labels: {labels})"
        )

    def serving(self, element: AffordanceElement) -> tuple[Skill, ...]:
        """Skills labelled with affordance ``element``."""
        return tuple(s for s in self if s.serves(element))

    def names(self) -> tuple[str, ...]:
        """Skill names in insertion order."""
        return tuple(self._skills)

    def describe(self) -> list[dict[str, Any]]:
        """One plain dictionary per skill: labels, kind and provenance (no arrays)."""
        return [
            {
                "name": s.name,
                "label": s.label,
                "action": s.action.value,
                "space": s.space.value,
                "kind": s.kind.value,
                "elements": [e.value for e in s.elements],
                "demonstrations": list(s.provenance.demonstrations),
                "learnt_at": s.provenance.learnt_at,
                "method": s.provenance.method,
                "fit": dict(s.provenance.fit),
            }
            for s in self
        ]

    # -- storage ---------------------------------------------------------------------------

    def save(self, folder: str | os.PathLike[str]) -> Path:
        """Write the library to ``folder`` atomically (replacing an existing library there)."""
        target = check_save_target(folder)
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.new-"))
        try:
            meta = {"format": FORMAT, "version": VERSION, "skills": self._metadata()}
            (tmp / META_FILE).write_text(json.dumps(meta, indent=2) + "\n", encoding="utf-8")
            arrays = {f"{s.name}/{k}": np.asarray(v) for s in self for k, v in s.arrays.items()}
            with open(tmp / ARRAYS_FILE, "wb") as fh:
                np.savez(fh, **arrays)  # type: ignore[arg-type]
            _swap_in(tmp, target)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return target

    def _metadata(self) -> list[dict[str, Any]]:
        return [
            {
                "name": s.name,
                "label": s.label,
                "action": s.action.value,
                "space": s.space.value,
                "kind": s.kind.value,
                "elements": [e.value for e in s.elements],
                "params": dict(s.params),
                "arrays": sorted(s.arrays),
                "provenance": {
                    "demonstrations": list(s.provenance.demonstrations),
                    "learnt_at": s.provenance.learnt_at,
                    "method": s.provenance.method,
                    "fit": dict(s.provenance.fit),
                },
            }
            for s in self
        ]

    @staticmethod
    def load(folder: str | os.PathLike[str]) -> SkillLibrary:
        """Load and validate a library folder.

        Raises
        ------
        LibraryFileError
            Naming the file, the field (``skills[2].action``) and what was expected.
        """
        root = Path(folder)
        meta_path = root / META_FILE
        if not root.is_dir():
            what = "a file" if root.exists() else "no such folder"
            raise LibraryFileError(root, "", "a skill library folder", what)
        meta = _read_meta(meta_path)
        arrays = _load_arrays(root / ARRAYS_FILE)
        return SkillLibrary(_parse_metadata(meta, meta_path, arrays, root / ARRAYS_FILE))


def check_save_target(folder: str | os.PathLike[str]) -> Path:
    """``folder`` if a library may be saved there: nothing yet, or a library folder.

    Raises
    ------
    LibraryFileError
        For a file, a link, or a folder that holds something other than a library (which
        saving would replace); before anything is written. An empty folder is fine.
    """
    target = Path(folder)
    expected = f"a skill library folder (with {META_FILE}) or nothing"
    if target.is_symlink():
        raise LibraryFileError(target, "", expected, "a link: not writing through it")
    if target.exists() and not target.is_dir():
        raise LibraryFileError(target, "", expected, "a file: not overwriting it")
    if target.is_dir() and not (target / META_FILE).is_file() and any(target.iterdir()):
        raise LibraryFileError(target, "", expected, "another folder: not overwriting it")
    return target


def _swap_in(new: Path, target: Path) -> None:
    if target.exists():
        check_save_target(target)
        old = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.old-"))
        os.replace(target, old / "lib")
        os.replace(new, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(new, target)


def _regular_file(path: Path, what: str, limit: int) -> None:
    """Refuse a missing file, a folder, a device or a file over ``limit`` bytes, unread."""
    try:
        info = path.stat()
    except FileNotFoundError:
        raise LibraryFileError(path, "", what, "no such file") from None
    except OSError as err:
        raise LibraryFileError(path, "", what, err.strerror or err) from None
    if not stat.S_ISREG(info.st_mode):
        got = "a folder" if stat.S_ISDIR(info.st_mode) else "not a regular file"
        raise LibraryFileError(path, "", what, got)
    if info.st_size > limit:
        raise LibraryFileError(path, "", f"{what} of at most {limit} bytes", info.st_size)


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    seen: dict[str, Any] = {}
    for key, value in pairs:
        if key in seen:
            raise ValueError(f"a key given once, got {key!r} twice")
        seen[key] = value
    return seen


def _read_meta(path: Path) -> Any:
    _regular_file(path, "a library.json file", MAX_META_BYTES)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as err:
        raise LibraryFileError(path, "", "a readable file", err.strerror or err) from None
    except UnicodeDecodeError as err:
        raise LibraryFileError(
            path, "", "UTF-8 text", f"byte 0x{err.object[err.start]:02x} at offset {err.start}"
        ) from None
    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as err:
        raise LibraryFileError(
            f"{path}:{err.lineno}:{err.colno}", "", "valid JSON", err.msg
        ) from None
    except RecursionError:
        raise LibraryFileError(path, "", "JSON nested to a sane depth", "too deep") from None
    except ValueError as err:  # a repeated key, from _unique_keys
        raise LibraryFileError(path, "", *str(err).split(", got ", 1)) from None


def _load_arrays(path: Path) -> dict[str, Array]:
    _regular_file(path, "an arrays.npz file", MAX_ARRAY_BYTES)
    try:
        with zipfile.ZipFile(path) as archive:
            claimed = sum(i.file_size for i in archive.infolist())
    except (zipfile.BadZipFile, OSError) as err:
        raise LibraryFileError(path, "", "an NPZ archive (a zip of .npy arrays)", err) from None
    if claimed > MAX_ARRAY_BYTES:
        raise LibraryFileError(
            path, "", f"arrays of at most {MAX_ARRAY_BYTES} bytes in all", f"{claimed} bytes"
        )
    try:
        with np.load(path, allow_pickle=False) as npz:
            return {k: npz[k] for k in npz.files}
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as err:
        raise LibraryFileError(path, "", "a readable NPZ archive", err) from None


def _enum(value: Any, enum: type[Any], file: Path, field: str) -> Any:
    try:
        return enum(value)
    except ValueError:
        options = ", ".join(m.value for m in enum)
        raise LibraryFileError(file, field, f"one of {options}", repr(value)) from None


def _need(
    entry: Mapping[str, Any],
    key: str,
    kind: type | tuple[type, ...],
    file: Path,
    field: str,
    what: str,
) -> Any:
    if key not in entry:
        raise LibraryFileError(file, f"{field}.{key}", what, "nothing (missing)")
    value = entry[key]
    if not isinstance(value, kind) or (isinstance(value, bool) and bool not in _as_tuple(kind)):
        raise LibraryFileError(file, f"{field}.{key}", what, repr(value))
    return value


def _as_tuple(kind: type | tuple[type, ...]) -> tuple[type, ...]:
    return kind if isinstance(kind, tuple) else (kind,)


def _provenance(entry: Mapping[str, Any], file: Path, field: str) -> Provenance:
    prov = _need(entry, "provenance", dict, file, field, "an object")
    where = f"{field}.provenance"
    demos = _need(prov, "demonstrations", list, file, where, "a list")
    for j, d in enumerate(demos):
        if not isinstance(d, str):
            raise LibraryFileError(file, f"{where}.demonstrations[{j}]", "a file name", repr(d))
    fit = _need(prov, "fit", dict, file, where, "an object")
    for k, v in fit.items():
        if isinstance(v, bool) or not isinstance(v, int | float) or not finite_within(v, 1e300):
            raise LibraryFileError(file, f"{where}.fit.{k}", "a finite number", short_repr(v))
    return Provenance(
        tuple(demos),
        _need(prov, "learnt_at", str, file, where, "a time stamp"),
        _need(prov, "method", str, file, where, "a description"),
        dict(fit),
    )


def _parse_metadata(
    meta: Any, file: Path, arrays: Mapping[str, Array], arrays_file: Path
) -> list[Skill]:
    if not isinstance(meta, dict):
        raise LibraryFileError(file, "", "a JSON object", type(meta).__name__)
    if meta.get("format") != FORMAT:
        raise LibraryFileError(file, "format", repr(FORMAT), repr(meta.get("format")))
    version = meta.get("version")
    if isinstance(version, bool) or version not in READABLE_VERSIONS:
        known = " or ".join(str(v) for v in READABLE_VERSIONS)
        raise LibraryFileError(file, "version", known, repr(version))
    unknown = sorted(set(meta) - {"format", "version", "skills"})
    if unknown:
        raise LibraryFileError(file, unknown[0], "only format, version and skills", "unknown key")
    entries = meta.get("skills")
    if not isinstance(entries, list):
        raise LibraryFileError(file, "skills", "a list of skills", repr(entries))
    if not entries:
        raise LibraryFileError(file, "skills", "at least one skill", "an empty list")
    keys = {"name", "action", "space", "kind", "elements", "params", "arrays", "provenance"}
    if version >= 2:
        keys.add("label")
    skills = []
    for i, entry in enumerate(entries):
        field = f"skills[{i}]"
        if not isinstance(entry, dict):
            raise LibraryFileError(file, field, "an object", repr(entry))
        extra = sorted(set(entry) - keys)
        if extra:
            raise LibraryFileError(file, f"{field}.{extra[0]}", "a known key", "unknown key")
        name = _need(entry, "name", str, file, field, "a skill name")
        action = _enum(
            _need(entry, "action", str, file, field, "an action"), Action, file, f"{field}.action"
        )
        label = action.value
        if version >= 2:
            label = _need(entry, "label", str, file, field, "a skill label (an identifier)")
            try:
                check_label(label)
            except ValueError:
                raise LibraryFileError(
                    file, f"{field}.label", "an identifier ([A-Za-z_][A-Za-z0-9_]*)", repr(label)
                ) from None
        space = _enum(
            _need(entry, "space", str, file, field, "a space"), Space, file, f"{field}.space"
        )
        kind = _enum(
            _need(entry, "kind", str, file, field, "a skill kind"), SkillKind, file, f"{field}.kind"
        )
        elements = tuple(
            _enum(e, AffordanceElement, file, f"{field}.elements[{j}]")
            for j, e in enumerate(_need(entry, "elements", list, file, field, "a list"))
        )
        params = _need(entry, "params", dict, file, field, "an object of parameters")
        for k, v in params.items():
            if not isinstance(v, int | float | str | bool):
                raise LibraryFileError(file, f"{field}.params.{k}", "a number or string", repr(v))
        names = _need(entry, "arrays", list, file, field, "a list of array names")
        own: dict[str, Array] = {}
        for a in names:
            key = f"{name}/{a}"
            if key not in arrays:
                raise LibraryFileError(
                    arrays_file, key, "an array named in library.json", "nothing (missing)"
                )
            own[str(a)] = arrays[key]
        provenance = _provenance(entry, file, field)
        try:
            check_skill_data(kind, params, own)
        except SkillDataError as err:
            if err.field.startswith("arrays."):  # named as arrays.npz keys them
                key = f"{name}/{err.field.removeprefix('arrays.')}"
                raise LibraryFileError(arrays_file, key, err.expected, err.got) from None
            raise LibraryFileError(file, f"{field}.{err.field}", err.expected, err.got) from None
        try:
            skill = Skill(name, action, space, kind, elements, params, own, provenance, label)
            if kind is SkillKind.LEARNT_DMP:
                model_from_data(params, own)
        except (ValueError, KeyError, TypeError) as err:
            raise LibraryFileError(file, field, f"a consistent {kind.value} skill", err) from None
        skills.append(skill)
    seen: set[str] = set()
    for i, s in enumerate(skills):
        if s.name in seen:
            raise LibraryFileError(file, f"skills[{i}].name", "a unique name", repr(s.name))
        seen.add(s.name)
    return skills

"""The default skill library, learnt deterministically from the demonstrations in ``demos/``.

The paper's four primitives (its Sec. 4.2), plus link-level avoidance, the skill the paper
lacked (all its failures were forearms hitting the obstacle):

=================  ==========  =====================================================  ========
skill              space       learnt how                                             from
=================  ==========  =====================================================  ========
pick_and_place     absolute    RBF forcing by ridge regression, horizontal rotation   CSV
level_carry        absolute    as pick_and_place, from a waiter's level carry;        CSV
                               labelled keep_level (the reasoner's choice for an
                               object that contains loose items)
rotate_z           absolute    RBF forcing by ridge regression                        CSV
rotate_grasp_axis  absolute    RBF forcing by ridge regression, horizontal rotation   CSV
avoid_obstacle     absolute    steering gains by least squares (Rai et al. 2014)      CSV
avoid_links        absolute    Park et al. 2008 dynamic potential, set by hand        --
workspace_limits   absolute    Gams et al. 2009 repulsion from the table top, by hand --
hold_lateral       relative    spring-damper and squeeze fitted to a held palm        CSV
insert             absolute    pose DMP of a descent; admittance by least squares     CSV
=================  ==========  =====================================================  ========
"""

from __future__ import annotations

import os
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from skills import file_cache
from skills.couplings.steering_fit import AvoidanceDemo, fit_obstacle_steering
from skills.demonstration import Demonstration
from skills.demos.io import DemoFile, columns, read_demo_csv
from skills.insertion_fit import fit_insertion
from skills.library import ARRAYS_FILE, META_FILE, LibraryFileError, SkillLibrary
from skills.pose_dmp import fit_pose
from skills.scaling import Scaling
from skills.skill import Provenance, Skill, SkillKind, learnt_skill
from skills.vocabulary import Action, AffordanceElement, Space

DEMOS_DIR = Path(__file__).resolve().parent / "demos"
#: Provenance time stamp of the shipped library: fixed so the build is reproducible.
BUILT_AT = "2026-11-22T00:00:00+00:00"

#: Link-level avoidance (Park et al. 2008): lambda (m^2/s), beta, influence distance (m).
#: The field sums over some 40 points (the arms' links and the parcel's surface), so a long
#: reach adds up to detours around obstacles the carry would have missed: with the paper's
#: composition alone (planner/trees/paper_composition.xml, 20 iiwa trials) an influence of
#: 0.25 m succeeded in 0 trials, 0.10 m in 8 of 10, 0.06 m in 17 of 20 and 0.04 m in 20.
LINK_FIELD = {"gain": 0.4, "beta": 2.0, "influence": 0.04}
#: Workspace repulsion (Gams et al. 2009): k (m^2/s^2) and the margin where it starts (m).
WORKSPACE = {"gain": 0.05, "margin": 0.03}


@dataclass(frozen=True)
class GraspFit:
    """A spring-damper fitted to a palm held at a face, per unit mass.

    Attributes
    ----------
    stiffness : float
        ``K``, 1/s^2.
    damping : float
        ``D``, 1/s.
    reference : ndarray, shape (3,)
        Where the spring pulls the palm, in {O}, m.
    squeeze_force_n : float
        Median contact force the teacher held with, N.
    residual_rms : float
        RMS of the fit's acceleration error, m/s^2.
    relative_residual : float
        ``residual_rms`` over the RMS demonstrated acceleration.
    """

    stiffness: float
    damping: float
    reference: np.ndarray
    squeeze_force_n: float
    residual_rms: float
    relative_residual: float


def fit_grasp_maintenance(demo_file: DemoFile) -> GraspFit:
    """Fit ``a = K (r - p) - D v`` to a held palm (Gams et al. 2014's pose-tracking hold).

    The teacher's taps are forces the recording does not see, so the samples where they act
    do not follow the spring. Least squares over all samples and axes for ``K``, ``D`` and
    ``K r`` is repeated without the samples whose residual exceeds three median absolute
    deviations, until no more are dropped, so the taps do not bend the gains.
    """
    force = columns(demo_file, ["force"])[:, 0]
    demo = demo_file.demonstration
    p = demo.positions
    v, a = demo.position_derivatives()
    n = p.shape[0]
    rows = np.zeros((3 * n, 5))
    for i in range(3):  # three axes share K and D; each has its own K r_i
        rows[i::3, i] = 1.0
        rows[i::3, 3] = -p[:, i]
        rows[i::3, 4] = -v[:, i]
    target = a.reshape(-1)
    keep = np.ones(target.shape[0], dtype=bool)
    for _ in range(20):  # trimming rounds, not samples
        sol, *_ = np.linalg.lstsq(rows[keep], target[keep], rcond=None)
        r = np.abs(rows @ sol - target)
        mad = float(np.median(r[keep])) + 1e-12
        new_keep = r <= 3.0 * 1.4826 * mad
        if np.array_equal(new_keep, keep):
            break
        keep = new_keep
    k, d = float(sol[3]), float(sol[4])
    if not (k > 0 and d >= 0):
        raise ValueError(
            f"{demo.name}: positions: expected a demonstration of a palm pulled back to a "
            f"reference (positive stiffness), got K={k:.3g}, D={d:.3g}"
        )
    residual = rows @ sol - target
    inliers = keep  # where the spring acts
    rms = float(np.sqrt(np.mean(residual[inliers] ** 2)))
    return GraspFit(
        k,
        d,
        sol[:3] / k,
        float(np.median(force)),
        rms,
        rms / max(float(np.sqrt(np.mean(target[inliers] ** 2))), 1e-12),
    )


def build_default_library(demos_dir: Path = DEMOS_DIR) -> SkillLibrary:
    """Learn the default skills from the CSV demonstrations in ``demos_dir``.

    Raises
    ------
    skills.demos.io.DemoFileError
        When a demonstration file is missing or malformed (names the file and the problem).
    """
    lib = SkillLibrary()
    pick = read_demo_csv(demos_dir / "pick_place.csv")
    model = fit_pose(
        pick.demonstration, position_scaling=Scaling.ROTATION_Z, orientation_scaling=Scaling.NONE
    )
    lib.add(
        learnt_skill(
            "pick_and_place",
            Action.TRANSPORT,
            Space.ABSOLUTE,
            model,
            (AffordanceElement.ON_SURFACE, AffordanceElement.GRASPABLE_LATERAL),
            Provenance(
                ("pick_place.csv",),
                BUILT_AT,
                "pose DMP, 50 RBF per dimension, ridge regression; forcing turned and "
                "scaled about the vertical to new starts and goals",
                {},
            ),
        )
    )
    level = read_demo_csv(demos_dir / "level_carry.csv")
    lib.add(
        learnt_skill(
            "level_carry",
            Action.TRANSPORT,
            Space.ABSOLUTE,
            fit_pose(
                level.demonstration,
                position_scaling=Scaling.ROTATION_Z,
                orientation_scaling=Scaling.NONE,
            ),
            (
                AffordanceElement.ON_SURFACE,
                AffordanceElement.GRASPABLE_LATERAL,
                AffordanceElement.CONTAINS_ITEMS,
            ),
            Provenance(
                ("level_carry.csv",),
                BUILT_AT,
                "pose DMP, 50 RBF per dimension, ridge regression, from a waiter's level "
                "carry; its duration bounded by what keeps a loose ball on "
                "(skills.level_carry)",
                {},
            ),
            label=Action.KEEP_LEVEL.value,
        )
    )
    rot = read_demo_csv(demos_dir / "rotate_z.csv")
    lib.add(
        learnt_skill(
            "rotate_z",
            Action.ROTATE_Z,
            Space.ABSOLUTE,
            fit_pose(rot.demonstration, position_scaling=Scaling.NONE),
            (AffordanceElement.ROTATABLE,),
            Provenance(
                ("rotate_z.csv",),
                BUILT_AT,
                "pose DMP, 50 RBF per dimension, ridge regression; rotation forcing "
                "scaled by the new turn over the demonstrated one",
                {},
            ),
        )
    )
    flip = read_demo_csv(demos_dir / "rotate_grasp_axis.csv")
    lib.add(
        learnt_skill(
            "rotate_grasp_axis",
            Action.ROTATE_GRASP_AXIS,
            Space.ABSOLUTE,
            # The turn's axis is horizontal (through the palms) and turns with the box's yaw:
            # the rotation forcing is turned about the vertical and scaled onto the new turn.
            fit_pose(
                flip.demonstration,
                position_scaling=Scaling.NONE,
                orientation_scaling=Scaling.ROTATION_Z,
            ),
            (AffordanceElement.ROTATABLE, AffordanceElement.GRASPABLE_LATERAL),
            Provenance(
                ("rotate_grasp_axis.csv",),
                BUILT_AT,
                "pose DMP, 50 RBF per dimension, ridge regression; rotation forcing turned "
                "about the vertical and scaled onto the new turn about the grasp axis",
                {},
            ),
        )
    )
    avoid = read_demo_csv(demos_dir / "avoid_obstacle.csv")
    obstacle = columns(avoid, ["ox", "oy", "oz", "radius"])[0]
    # The coupling is what the teacher did beyond its own unobstructed reach: learn that reach
    # as a DMP and fit the steering to the difference (Rai et al. 2014).
    demo = avoid.demonstration
    base_demo = Demonstration.create(
        demo.t, columns(avoid, ["bx", "by", "bz"]), demo.orientations, name=f"{demo.name} (base)"
    )
    base = fit_pose(base_demo)
    fit = fit_obstacle_steering(AvoidanceDemo.create(demo, obstacle[:3], obstacle[3]), model=base)
    lib.add(
        Skill(
            "avoid_obstacle",
            Action.AVOID_OBSTACLE,
            Space.ABSOLUTE,
            SkillKind.OBSTACLE_STEERING,
            (AffordanceElement.OBSTACLE_NEAR_PATH,),
            {"gamma": fit.steering.gamma, "beta": fit.steering.beta, "k": fit.steering.k},
            {},
            Provenance(
                ("avoid_obstacle.csv",),
                BUILT_AT,
                "Hoffmann et al. 2009 steering with the distance factor of Pairet et al. "
                "2019, gains fitted by bounded least squares (Rai et al. 2014)",
                {
                    "residual_rms": fit.residual_rms,
                    "relative_residual": fit.relative_residual,
                    "n_samples": float(fit.n_samples),
                },
            ),
        )
    )
    lib.add(
        Skill(
            "avoid_links",
            Action.AVOID_LINKS,
            Space.ABSOLUTE,
            SkillKind.POTENTIAL_FIELD,
            (AffordanceElement.OBSTACLE_NEAR_LINKS,),
            dict(LINK_FIELD),
            {},
            Provenance(
                (),
                BUILT_AT,
                "Park et al. 2008 dynamic potential over arm-link points, distances "
                "from FCL; parameters set by hand",
                {},
            ),
        )
    )
    lib.add(
        Skill(
            "workspace_limits",
            Action.LIMIT_REPULSION,
            Space.ABSOLUTE,
            SkillKind.WORKSPACE_REPULSION,
            (AffordanceElement.ON_SURFACE,),
            dict(WORKSPACE),
            {},
            Provenance(
                (),
                BUILT_AT,
                "Gams et al. 2009 repulsion from the workspace's faces (the table top "
                "below all): k (1/d - 1/margin); parameters set by hand",
                {},
            ),
        )
    )
    hold = read_demo_csv(demos_dir / "grasp_maintenance.csv")
    g = fit_grasp_maintenance(hold)
    lib.add(
        Skill(
            "hold_lateral",
            Action.HOLD_LATERAL,
            Space.RELATIVE,
            SkillKind.GRASP_MAINTENANCE,
            (AffordanceElement.GRASPABLE_LATERAL, AffordanceElement.PARALLEL_FACES),
            {
                "stiffness": g.stiffness,
                "damping": g.damping,
                "rotational_stiffness": g.stiffness / 2.0,
                "squeeze_force_n": g.squeeze_force_n,
            },
            {"reference_object": g.reference},
            Provenance(
                ("grasp_maintenance.csv",),
                BUILT_AT,
                "grasp geometry tracked as a pose reference (Gams et al. 2014): "
                "spring, damping and squeeze fitted by linear least squares",
                {"residual_rms": g.residual_rms, "relative_residual": g.relative_residual},
            ),
        )
    )
    lib.add(insertion_skill(read_demo_csv(demos_dir / "insertion.csv")))
    return lib


def insertion_skill(demo_file: DemoFile) -> Skill:
    """The ``insert`` skill: a pose DMP of the teacher's planned descent into a fixture, with
    the force coupling (:func:`skills.insertion_fit.fit_insertion`) as its parameters."""
    demo = demo_file.demonstration
    plan = Demonstration.create(
        demo.t,
        columns(demo_file, ["bx", "by", "bz"]),
        demo.orientations,
        name=f"{demo.name} (plan)",
    )
    fit = fit_insertion(demo_file)
    skill = learnt_skill(
        "insert",
        Action.INSERT,
        Space.ABSOLUTE,
        fit_pose(plan, position_scaling=Scaling.ROTATION_Z, orientation_scaling=Scaling.NONE),
        (AffordanceElement.IN_FIXTURE,),
        Provenance(
            ("insertion.csv",),
            BUILT_AT,
            "pose DMP of the teacher's planned descent, 50 RBF per dimension; admittance "
            "(compliance, centring) fitted by linear least squares to what the teacher did "
            "beyond the plan against the recorded fixture forces",
            {
                "residual_rms": fit.residual_rms,
                "relative_residual": fit.relative_residual,
                "n_contact_samples": float(fit.contact_samples),
            },
        ),
    )
    g = fit.gains
    params = {
        **skill.params,
        "compliance": g.compliance,
        "centring": g.centring,
        "soft_force_n": g.soft_force_n,
        "stop_force_n": g.stop_force_n,
    }
    return replace(skill, params=params)


#: The package whose source the learning runs: all of it keys the cached library.
_SKILLS_DIR = Path(__file__).resolve().parent


def default_library_key(demos_dir: Path = DEMOS_DIR) -> str:
    """The name of the default library learnt from ``demos_dir``: a digest of everything the
    learning reads (every CSV there, the source of the whole ``skills`` package, the Python,
    numpy and scipy it runs on, and the BLAS kernel asked of OpenBLAS), so an edit to any of
    them is a new name."""
    # The BLAS kernel numpy's products ran on (duet_robot.blas pins it, by this variable):
    # learnt on another, the library differs in its last bits, and a trial run with it can
    # end elsewhere (a library learnt by a process that had not pinned it changed trial 352
    # of the default world's campaign once it was cached).
    kernel = f"OPENBLAS_CORETYPE={os.environ.get('OPENBLAS_CORETYPE', '')}"
    parts: list[bytes | str] = [sys.version, kernel, *file_cache.versions("numpy", "scipy")]
    for path in sorted(demos_dir.glob("*.csv")):
        parts += [path.name, path.read_bytes()]
    return file_cache.content_key([*parts, *file_cache.source_files(_SKILLS_DIR)])


def default_library(demos_dir: Path = DEMOS_DIR, cache_dir: Path | None = None) -> SkillLibrary:
    """:func:`build_default_library`, learnt once per content and then read from the cache.

    The learning is pure and deterministic, so the library read back is the one learnt (every
    parameter and array bit for bit; :meth:`SkillLibrary.load` validates it as any library).
    A cache that cannot be read or written costs the time of learning, never the library.

    Parameters
    ----------
    demos_dir : Path
        The demonstrations (:data:`DEMOS_DIR`).
    cache_dir : Path, optional
        Default: :func:`skills.file_cache.cache_folder` of ``"skills"``.
    """
    try:
        folder = file_cache.cache_folder("skills", "cached skill libraries", cache_dir)
        entry = folder / f"default_library_{default_library_key(demos_dir)}.bin"
    except OSError:
        return build_default_library(demos_dir)
    payload = file_cache.read_entry(entry)
    if payload is not None:
        try:
            return _unpacked(payload)
        except (LibraryFileError, ValueError, OSError):
            pass  # a payload of an older layout: learnt again below, and replaced
    library = build_default_library(demos_dir)
    try:
        file_cache.write_entry(entry, _packed(library))
    except OSError:
        pass
    return library


def _packed(library: SkillLibrary) -> bytes:
    """A library's two files as :meth:`SkillLibrary.save` writes them, in one payload."""
    with tempfile.TemporaryDirectory(prefix="duet-library-") as tmp:
        folder = library.save(Path(tmp) / "library")
        meta, arrays = (folder / META_FILE).read_bytes(), (folder / ARRAYS_FILE).read_bytes()
    return len(meta).to_bytes(8, "little") + meta + arrays


def _unpacked(payload: bytes) -> SkillLibrary:
    """The library :func:`_packed` packed, through :meth:`SkillLibrary.load`'s checks."""
    size = int.from_bytes(payload[:8], "little")
    if not 0 < size <= len(payload) - 8:
        raise ValueError("cached library: expected the length of library.json first")
    with tempfile.TemporaryDirectory(prefix="duet-library-") as tmp:
        folder = Path(tmp)
        (folder / META_FILE).write_bytes(payload[8 : 8 + size])
        (folder / ARRAYS_FILE).write_bytes(payload[8 + size :])
        return SkillLibrary.load(folder)

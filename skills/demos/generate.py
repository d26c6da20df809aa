"""Write the five synthetic demonstrations the default library is learnt from.

Run ``python -m skills.demos.generate [--out DIR] [--seed N]``. The same seed writes the same
files byte for byte. The teachers are synthetic and human-like (see ``README.md`` here):

1. ``pick_place.csv``: the parcel lifted, carried 0.3 m across and lowered: a minimum-jerk
   carry inside a lift-and-lower profile, with a hand's tremor fading out at both ends.
2. ``rotate_z.csv``: a 90 degree turn about the vertical (:mod:`skills.demos.rotation`).
3. ``avoid_obstacle.csv``: a reach bent around a sphere through a via-point
   (:mod:`skills.demos.avoidance`); columns ``ox, oy, oz, radius`` give the obstacle and
   ``bx, by, bz`` the same teacher's unobstructed reach, sampled at the same times.
4. ``grasp_maintenance.csv``: a palm's pose in the object frame while the teacher holds the
   parcel's face and the palm is pushed off and pulls back (a spring-damper the fit recovers);
   column ``force`` is the contact force the teacher's palm sensor read.
5. ``rotate_grasp_axis.csv``: a 90 degree turn about the horizontal axis through the palms
   (the box's y axis: a pitch) with the box held lifted (:mod:`skills.demos.rotation`).
6. ``level_carry.csv``: a waiter's carry of a tray with a loose ball on it: the same 0.3 m
   across, lifted only 6 cm, taken over 4 s, minimum-jerk, the tray held level (a steadier
   hand: half the tremor, a tenth of the wobble).
7. ``insertion.csv``: a box lowered into an open fixture, reacting to a wall it meets
   (:mod:`skills.demos.insertion`); ``fx, fy, fz`` the fixture's force on the box, ``bx, by,
   bz`` the teacher's plan, ``gx, gy, gz`` the seated goal.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from skills import quaternion as quat
from skills.demos._smooth import min_jerk, tremor
from skills.demos.avoidance import avoidance_demo, straight_demo
from skills.demos.insertion import insertion_demo
from skills.demos.io import write_demo_csv
from skills.demos.rotation import rotation_demo
from skills.dual_arm import GraspGeometry
from skills.level_carry import CARRY_SHARE
from skills.types import Array
from skills.vocabulary import Arm

HERE = Path(__file__).resolve().parent
DEFAULT_SEED = 2019

#: The parcel of the paper, and the grasp the grasp-maintenance teacher holds.
PARCEL_WIDTH_M = 0.30
PALM_THICKNESS_M = 0.02
#: Teacher's hold: spring and damping per unit mass (1/s^2, 1/s), squeeze past the face (m).
TEACHER_STIFFNESS = 400.0
TEACHER_DAMPING = 40.0
TEACHER_SQUEEZE_M = 0.012
TEACHER_PALM_STIFFNESS_N_PER_M = 1000.0


def pick_place(
    rng: np.random.Generator, n: int = 300, duration: float = 2.5
) -> tuple[Array, Array, Array]:
    """Lift, carry 0.3 m along -y, lower; orientation held level."""
    t = np.linspace(0.0, duration, n)
    u = t / duration
    start = np.array([0.55, 0.15, 0.675])
    goal = np.array([0.55, -0.15, 0.675])
    carry = min_jerk(np.clip((u - 0.12) / 0.76, 0.0, 1.0))
    up = min_jerk(np.clip(u / 0.4, 0.0, 1.0)) * min_jerk(np.clip((1.0 - u) / 0.4, 0.0, 1.0))
    positions = start + carry[:, None] * (goal - start)
    positions[:, 2] += 0.12 * up
    positions += tremor(n, 3, 1.5e-3, 12, rng)
    yaw = tremor(n, 1, 0.01, 12, rng)[:, 0]
    orientations = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), yaw)
    return t, positions, orientations


def rotate_z(rng: np.random.Generator) -> tuple[Array, Array, Array]:
    """A 90 degree turn about z, held at the parcel's carrying height."""
    return rotation_demo(np.pi / 2, 0.0, (0.6, 0.0, 0.78), 2.0, 300, 0.005, rng)


def rotate_grasp_axis(rng: np.random.Generator) -> tuple[Array, Array, Array]:
    """A 90 degree turn about the palms' axis (world y, the box at yaw 0), held lifted: the
    box's centre 0.2 m above the table top, where a parcel's corners clear it as it turns."""
    return rotation_demo(np.pi / 2, 0.0, (0.6, 0.0, 0.8), 2.0, 300, 0.005, rng, axis=1)


def avoid(rng: np.random.Generator) -> tuple[tuple[Array, ...], Array, Array, float]:
    """A reach whose straight line passes through a sphere; the teacher goes over it.

    Returns the avoiding demonstration, the same teacher's unobstructed reach (the base motion
    the avoidance is learnt against), the obstacle's centre and radius.
    """
    start, goal = np.array([0.55, 0.15, 0.70]), np.array([0.55, -0.15, 0.70])
    centre, radius = np.array([0.55, 0.0, 0.70]), 0.06
    demo = avoidance_demo(start, goal, centre, radius, 0.06, None, 2.5, 300, 5e-4, rng)
    _, base, _ = straight_demo(start, goal, 2.5, 300, 5e-4, rng)
    return demo, base, centre, radius


def grasp_maintenance(
    rng: np.random.Generator, n: int = 600, duration: float = 4.0
) -> tuple[Array, ...]:
    """The left palm in {O}, squeezing, tapped off and into the face and pulled back.

    The palm's offset ``e`` from its squeezed reference follows ``e'' = -K e - D e' + f(t)``;
    the contact force is the palm's spring on the squeeze depth.
    """
    g = GraspGeometry.lateral(PARCEL_WIDTH_M, PALM_THICKNESS_M)
    t = np.linspace(0.0, duration, n)
    dt = t[1] - t[0]
    normal = g.normal(Arm.LEFT)
    # Forces per unit mass on the palm, m/s^2: the teacher's taps along the face normal (off
    # the face, into it, off again; each moves the palm about 1.5 cm). Recorded at 500 Hz so
    # that finite differences resolve the hold's dynamics (damping x period / 2 about 4 %).
    force = np.zeros((n, 3))
    for centre, size in ((0.8, -22.0), (2.0, 14.0), (3.1, -17.0)):
        force += size * np.exp(-0.5 * ((t - centre) / 0.015) ** 2)[:, None] * normal[None]
    e = np.zeros((n, 3))  # palm offset from its squeezed reference, {O}
    v = np.zeros(3)
    for k in range(1, n):  # the teacher's physics, integrated once when the file is written
        acc = -TEACHER_STIFFNESS * e[k - 1] - TEACHER_DAMPING * v + force[k - 1]
        v = v + acc * dt
        e[k] = e[k - 1] + v * dt
    reference = g.position(Arm.LEFT) + TEACHER_SQUEEZE_M * normal
    positions = reference[None] + e + 5e-6 * rng.standard_normal((n, 3))  # encoder noise
    orientations = np.tile(g.orientation(Arm.LEFT), (n, 1))
    depth = TEACHER_SQUEEZE_M + e @ normal  # e along the inward normal presses deeper
    contact = TEACHER_PALM_STIFFNESS_N_PER_M * np.clip(depth, 0.0, None)
    return t, positions, orientations, contact


def level_carry(
    rng: np.random.Generator, n: int = 480, duration: float = 4.0
) -> tuple[Array, Array, Array]:
    """A waiter's level carry: lift 6 cm, carry 0.3 m along -y, lower; tray level throughout.

    The carry begins only once the lift is under way and ends before the lowering, as in
    :func:`pick_place`, but over 4 s instead of 2.5 (a peak acceleration of about 0.13 m/s^2
    across), lower, and with a steadier hand: what a teacher does with something loose on top.
    """
    t = np.linspace(0.0, duration, n)
    u = t / duration
    start = np.array([0.55, 0.15, 0.675])
    goal = np.array([0.55, -0.15, 0.675])
    carry = min_jerk(np.clip((u - (1.0 - CARRY_SHARE) / 2.0) / CARRY_SHARE, 0.0, 1.0))
    up = min_jerk(np.clip(u / 0.35, 0.0, 1.0)) * min_jerk(np.clip((1.0 - u) / 0.35, 0.0, 1.0))
    positions = start + carry[:, None] * (goal - start)
    positions[:, 2] += 0.06 * up
    positions += tremor(n, 3, 0.75e-3, 12, rng)
    # Small tilts about x and y as well as a yaw wobble: the tray is level within 0.1 degree.
    wobble = tremor(n, 3, 1e-3, 12, rng)
    orientations = quat.from_rotation_vector(wobble)
    return t, positions, orientations


def write_all(out: Path = HERE, seed: int = DEFAULT_SEED) -> list[Path]:
    """Write the five CSV files into ``out``; returns their paths."""
    rng = np.random.default_rng(seed)
    paths = [write_demo_csv(out / "pick_place.csv", *pick_place(rng))]
    paths.append(write_demo_csv(out / "rotate_z.csv", *rotate_z(rng)))
    (t, p, q), base, centre, radius = avoid(rng)
    n = t.shape[0]
    paths.append(
        write_demo_csv(
            out / "avoid_obstacle.csv",
            t,
            p,
            q,
            {
                "ox": np.full(n, centre[0]),
                "oy": np.full(n, centre[1]),
                "oz": np.full(n, centre[2]),
                "radius": np.full(n, radius),
                "bx": base[:, 0],
                "by": base[:, 1],
                "bz": base[:, 2],
            },
        )
    )
    t, p, q, force = grasp_maintenance(rng)
    paths.append(write_demo_csv(out / "grasp_maintenance.csv", t, p, q, {"force": force}))
    # Last: the draws of the files above stay those they were written with.
    paths.append(write_demo_csv(out / "rotate_grasp_axis.csv", *rotate_grasp_axis(rng)))
    # A stream of its own, so the four files above are the bytes they were before this one.
    paths.append(
        write_demo_csv(out / "level_carry.csv", *level_carry(np.random.default_rng([seed, 5])))
    )
    # A stream of its own, so the files above are the bytes they were before this one.
    t, p, q, fixture_force, plan, goal = insertion_demo(np.random.default_rng([seed, 7]))
    n = t.shape[0]
    extra = {f"f{a}": fixture_force[:, i] for i, a in enumerate("xyz")}
    extra.update({f"b{a}": plan[:, i] for i, a in enumerate("xyz")})
    extra.update({f"g{a}": np.full(n, goal[i]) for i, a in enumerate("xyz")})
    paths.append(write_demo_csv(out / "insertion.csv", t, p, q, extra))
    return paths


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE, help="folder to write into")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED, help="random seed")
    args = parser.parse_args()
    for path in write_all(args.out, args.seed):
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

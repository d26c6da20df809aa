"""The insertion teacher: a box lowered into an open fixture, reacting to the walls by feel.

A human-like teacher holds a box 6 cm above its seated pose, 12 mm off the slot's centre
sideways (7 mm more than the 5 mm clearance), and lowers it along a minimum-jerk descent
(the *plan*, columns ``bx, by, bz``: down, and across to the slot too late to miss the wall).
The box's bottom edge meets the top of a wall; the wall (a stiff spring with a chamfered
edge) pushes it back and up. The teacher is compliant: the held box moves with the push at
``TEACHER_COMPLIANCE`` m/s per newton and is pulled back towards the plan at
``TEACHER_CENTRING`` 1/s, and the descent slows as the force grows (stops at
``TEACHER_STOP_N``). Columns ``fx, fy, fz`` are the force the fixture exerted on the box, as
a wrist sensor minus the box's weight would read it; ``gx, gy, gz`` the seated goal.
"""

from __future__ import annotations

import numpy as np

from skills import quaternion as quat
from skills.demos._smooth import min_jerk, tremor
from skills.types import Array

#: The teacher's admittance: m/(s N), 1/s, and the forces (N) where it slows and stops.
TEACHER_COMPLIANCE = 1.0e-3
TEACHER_CENTRING = 0.3
TEACHER_SOFT_N = 5.0
TEACHER_STOP_N = 15.0
#: The fixture: clearance per side (m), wall height above the floor (m), wall stiffness (N/m).
CLEARANCE_M = 0.005
WALL_HEIGHT_M = 0.04
WALL_STIFFNESS = 4000.0
#: Where the descent starts above the seated pose, and how far off the slot, m.
HOVER_M = 0.06
OFF_SLOT_M = 0.012


def _plan(start: Array, goal: Array, phase: float) -> Array:
    """The teacher's plan at ``phase`` in [0, 1]: down by minimum jerk, and across to the
    slot late (it starts moving sideways a fifth of the way down), so the box meets a wall."""
    s = min(phase, 1.0)
    down = float(min_jerk(np.array(s)))
    across = float(min_jerk(np.array(np.clip((s - 0.2) / 0.6, 0.0, 1.0))))
    return start + np.array([0.0, -OFF_SLOT_M * across, -HOVER_M * down])


def insertion_demo(
    rng: np.random.Generator, n: int = 700, duration: float = 3.5, descent_s: float = 2.5
) -> tuple[Array, Array, Array, Array, Array, Array]:
    """Times (N,), positions (N, 3), quaternions (N, 4), fixture forces (N, 3), the plan
    (N, 3) and the seated goal (3,), world frame, SI units."""
    t = np.linspace(0.0, duration, n)
    dt = float(t[1] - t[0])
    goal = np.array([0.60, 0.0, 0.675])
    half_height = 0.075
    start = goal + np.array([0.0, OFF_SLOT_M, HOVER_M])
    phase = 0.0
    p = start.copy()
    positions = np.zeros((n, 3))
    plan = np.zeros((n, 3))
    forces = np.zeros((n, 3))
    for i in range(n):  # a closed loop through the contact: one sample at a time
        base = _plan(start, goal, phase)
        bottom = p[2] - half_height
        wall_top = goal[2] - half_height + WALL_HEIGHT_M
        over = (p[1] - goal[1]) - CLEARANCE_M  # how far the box's face is past the wall's
        force = np.zeros(3)
        if over > 0.0 and bottom < wall_top:
            # The chamfered edge pushes back and, near its top, up.
            up = 0.5 if wall_top - bottom < 0.004 else 0.0
            force = WALL_STIFFNESS * over * np.array([0.0, -1.0, up])
        norm = float(np.linalg.norm(force))
        rate = float(np.clip((TEACHER_STOP_N - norm) / (TEACHER_STOP_N - TEACHER_SOFT_N), 0, 1))
        phase += rate * dt / descent_s
        nxt = _plan(start, goal, phase)
        v = TEACHER_COMPLIANCE * force + TEACHER_CENTRING * (base - p)
        v[2] = (nxt[2] - base[2]) / dt  # the descent itself follows the (slowed) plan
        positions[i], plan[i], forces[i] = p, base, force
        p = p + v * dt
    positions = positions + tremor(n, 3, 5e-5, 30, rng)
    yaw = tremor(n, 1, 0.005, 12, rng)[:, 0]
    orientations = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), yaw)
    return t, positions, orientations, forces, plan, goal

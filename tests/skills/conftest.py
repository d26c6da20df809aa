"""Demonstrations with known shapes for the DMP tests."""

from __future__ import annotations

import numpy as np
import pytest

from skills import quaternion as quat
from skills.demonstration import Demonstration


def min_jerk(u: np.ndarray) -> np.ndarray:
    """Minimum-jerk profile from 0 to 1 over ``u`` in [0, 1]."""
    return 10 * u**3 - 15 * u**4 + 6 * u**5


def pick_place_demo(n: int = 1000, duration: float = 2.0) -> Demonstration:
    """A lift-carry-lower motion at rest at both ends, turning 1.2 rad about a tilted axis."""
    t = np.linspace(0.0, duration, n)
    u = t / duration
    s = min_jerk(u)
    positions = np.stack(
        (0.4 * s, 0.2 * np.sin(np.pi * s), 0.15 * np.sin(np.pi * u) ** 2), axis=1
    ) + np.array([0.5, -0.1, 0.7])
    orientations = quat.from_axis_angle(np.array([0.2, 0.3, 1.0]), 1.2 * s)
    return Demonstration.create(t, positions, orientations, name="pick_place")


@pytest.fixture
def demo() -> Demonstration:
    return pick_place_demo()


def waved_carry(amplitude_m: float, seed: int = 0, cycles: float = 3.0) -> Demonstration:
    """The shipped pick-and-place teacher's motion (another seed: other tremor) with a lateral
    wave of ``amplitude_m`` laid over it, ``cycles`` cycles, fading in and out like a hand's."""
    from skills.demos.generate import pick_place

    t, positions, orientations = pick_place(np.random.default_rng(seed))
    u = (t - t[0]) / (t[-1] - t[0])
    waved = positions.copy()
    waved[:, 0] += amplitude_m * np.sin(2.0 * np.pi * cycles * u) * np.sin(np.pi * u)
    return Demonstration.create(t, waved, orientations, name=f"wave {amplitude_m} m")

"""Movement recognition separates shapes: repeats of a skill match it, a wave over it does not."""

from __future__ import annotations

import numpy as np
import pytest

from skills.default_library import DEMOS_DIR, build_default_library
from skills.demonstration import Demonstration
from skills.demos.generate import pick_place
from skills.demos.io import read_demo_csv
from skills.library import SkillLibrary
from skills.recognition import DEFAULT_THRESHOLD, demo_signature, recognise
from tests.skills.conftest import waved_carry


@pytest.fixture(scope="module")
def library() -> SkillLibrary:
    return build_default_library()


@pytest.mark.parametrize(
    ("file", "skill"), [("pick_place.csv", "pick_and_place"), ("rotate_z.csv", "rotate_z")]
)
def test_the_shipped_demonstrations_recognise_themselves(
    library: SkillLibrary, file: str, skill: str
) -> None:
    r = recognise(library, read_demo_csv(DEMOS_DIR / file).demonstration)
    assert r.best == skill and r.matched
    assert r.similarity == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_noisy_repeat_of_the_carry_matches_it(library: SkillLibrary, seed: int) -> None:
    t, p, q = pick_place(np.random.default_rng(seed))  # the same teacher, other tremor
    r = recognise(library, Demonstration.create(t, p, q))
    assert r.best == "pick_and_place" and r.matched
    assert r.similarity == pytest.approx(0.998, abs=1e-3)


@pytest.mark.parametrize(("amplitude", "expected"), [(0.02, 0.944), (0.03, 0.886), (0.05, 0.753)])
def test_a_wave_over_the_carry_is_a_new_skill(
    library: SkillLibrary, amplitude: float, expected: float
) -> None:
    r = recognise(library, waved_carry(amplitude, seed=1))
    assert r.best == "pick_and_place" and not r.matched
    assert r.similarity == pytest.approx(expected, abs=5e-3)
    assert r.similarity < DEFAULT_THRESHOLD


def test_the_signature_ignores_place_direction_and_speed() -> None:
    d = waved_carry(0.03, seed=4)
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg about z
    moved = (d.positions - d.positions[0]) @ turn.T * 1.5 + np.array([0.2, -0.4, 0.1])
    assert d.orientations is not None
    again = Demonstration.create(d.t * 2.5, moved, d.orientations)
    np.testing.assert_allclose(demo_signature(again), demo_signature(d), atol=1e-9)

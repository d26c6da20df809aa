"""Scripted disturbances: which physics steps they act on, and the impulse they give."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import yaml
from numpy.testing import assert_allclose

from worlds.spec import DisturbanceSpec
from worlds.testing import DEFAULT_WORLD
from worlds.world_file import World, world_from_data

HZ = 240
#: The default world's parcel: kg and full extents along its x, y, z, m.
MASS = 1.0
SIZE = np.array([0.20, 0.30, 0.15])


def test_a_window_holds_the_steps_that_start_inside_it() -> None:
    push = DisturbanceSpec("parcel", 0.5, 0.25, (1.0, 0.0, 0.0))
    assert push.steps(HZ) == range(120, 180)  # 0.25 s at 240 Hz: 60 steps, from t = 0.5 s
    # Times that do not fall on a step start: the first step at or after at_s, the last
    # before at_s + duration_s.
    assert DisturbanceSpec("p", 0.001, 0.01, (1, 0, 0)).steps(HZ) == range(1, 3)
    # Windows written in decimals do not lose or gain a step to rounding (0.6 * 240 is
    # 143.99999999999997).
    assert DisturbanceSpec("p", 0.1, 0.5, (1, 0, 0)).steps(HZ) == range(24, 144)
    assert DisturbanceSpec("p", 0.0, 1.0 / 3.0, (1, 0, 0)).steps(60) == range(0, 20)
    # A window shorter than a step, between two step starts, holds none.
    assert len(DisturbanceSpec("p", 0.001, 0.002, (1, 0, 0)).steps(HZ)) == 0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"at_s": -1.0}, "expected at_s >= 0 and duration_s > 0"),
        ({"duration_s": 0.0}, "expected at_s >= 0 and duration_s > 0"),
        ({"force_n": (1.0, 0.0)}, "expected finite numbers and 3-vectors"),
        ({"torque_nm": (0.0, float("nan"), 0.0)}, "expected finite numbers and 3-vectors"),
    ],
)
def test_a_bad_spec_is_refused(kwargs: dict[str, Any], match: str) -> None:
    fields: dict[str, Any] = {
        "object": "parcel",
        "at_s": 0.0,
        "duration_s": 0.1,
        "force_n": (1.0, 0.0, 0.0),
    }
    with pytest.raises(ValueError, match=match):
        DisturbanceSpec(**{**fields, **kwargs})


def _world(disturbances: list[dict[str, Any]], gravity: float = -9.81, **pose: Any) -> World:
    data = yaml.safe_load(DEFAULT_WORLD.read_text(encoding="utf-8"))
    data["sim"]["gravity"] = gravity
    data["objects"][0]["pose"].update(pose)
    data["disturbances"] = disturbances
    return world_from_data(data, None)


def _floating_parcel(disturbances: list[dict[str, Any]]) -> Any:
    """A SimWorld whose parcel floats, gravity off, far from the palms, undamped."""
    import pybullet as pb

    from worlds.sim_world import SimWorld

    sim = SimWorld(_world(disturbances, gravity=0.0, position=[0.65, 0.0, 1.2]))
    # Bullet damps every body's velocity by default (0.04 /s); without it the impulse is
    # exact, and one physics step more or less (1/60 of it here) would show.
    pb.changeDynamics(
        sim.scene.object_ids["parcel"],
        -1,
        linearDamping=0.0,
        angularDamping=0.0,
        physicsClientId=sim.scene.client,
    )
    return sim


@pytest.mark.sim
def test_a_force_gives_its_impulse_and_a_torque_its_angular_impulse() -> None:
    force = np.array([0.8, 0.0, 0.0])  # N, world frame
    torque = np.array([0.0, 0.0, 0.01])  # N m, about the parcel's z axis (a principal axis)
    at_s, duration_s = 0.5, 0.25
    push = {
        "at_s": at_s,
        "object": "parcel",
        "force_n": force.tolist(),
        "duration_s": duration_s,
        "torque_nm": torque.tolist(),
    }
    with _floating_parcel([push]) as sim:
        sim.advance(at_s)  # through the SimWorld's stepping, as a run's ticks are
        assert_allclose(sim.object_twist("parcel"), np.zeros(6), atol=1e-12)
        sim.advance(duration_s + 0.1)  # and past the window: nothing after it
        twist = sim.object_twist("parcel")
        (applied,) = sim.scene.disturbances.applied()
    # Momentum gained: F T (along the force; nothing across it).
    assert_allclose(MASS * twist[:3], force * duration_s, rtol=1e-6, atol=1e-12)
    # Angular momentum gained: I w = tau T, I of a solid box about its centre.
    squares = SIZE**2
    inertia = MASS / 12.0 * (squares.sum() - squares)  # (3,) kg m^2, I_xx = m (y^2 + z^2) / 12
    assert_allclose(twist[3:], torque * duration_s / inertia, rtol=1e-6, atol=1e-12)
    assert (applied.first_step, applied.last_step, applied.steps) == (120, 179, 60)


@pytest.mark.sim
def test_an_entry_outside_the_run_applies_nothing() -> None:
    # The default world, gravity on, the parcel on the table: a push after the steps run
    # leaves every joint and body exactly where the same world without it goes.
    from worlds.sim_world import SimWorld

    late = {"at_s": 10.0, "object": "parcel", "force_n": [0.0, 50.0, 0.0], "duration_s": 1.0}
    states = []
    for disturbances in ([], [late]):
        with SimWorld(_world(disturbances)) as sim:
            sim.advance(0.25)
            states.append(sim.scene.state_vector())
            applied = sim.scene.disturbances.applied()
    np.testing.assert_array_equal(states[1], states[0])
    assert [(a.first_step, a.last_step, a.steps) for a in applied] == [(None, None, 0)]
    assert applied[0].summary()["steps"] == 0


@pytest.mark.sim
def test_a_push_while_held_is_skipped_when_nothing_holds_the_object() -> None:
    # The floating parcel is far from the palms: a while_held push never acts, a plain one does.
    push = {"at_s": 0.1, "object": "parcel", "force_n": [0.8, 0.0, 0.0], "duration_s": 0.1}
    with _floating_parcel([{**push, "while_held": True}, push]) as sim:
        sim.advance(0.3)
        twist = sim.object_twist("parcel")
        held_push, plain_push = sim.scene.disturbances.applied()
    assert (held_push.steps, held_push.skipped) == (0, True)
    assert held_push.summary()["skipped"] is True
    assert (plain_push.steps, plain_push.skipped) == (24, False)
    assert_allclose(MASS * twist[0], 0.8 * 0.1, rtol=1e-6)


@pytest.mark.sim
def test_a_push_while_held_acts_on_a_parcel_the_palms_hold() -> None:
    from experiment.episode import run_episode

    # Mid-carry of the default world's first move, both palms hold the parcel.
    push = {
        "at_s": 4.3,
        "object": "parcel",
        "force_n": [0.0, 10.0, 0.0],
        "duration_s": 0.1,
        "while_held": True,
    }
    report = run_episode(_world([push]), None, out=None, animation=False)
    (entry,) = report.disturbances
    assert (entry["steps"], entry["skipped"]) == (24, False)
    assert report.success, report.failure


@pytest.mark.sim
def test_a_push_while_held_skips_a_parcel_held_on_the_table(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from experiment.episode import run_episode
    from worlds.scene import HELD_FORCE_N, Scene

    # Closing on the default world's parcel, before the first carry lifts it: both palms press
    # it, but the table carries it, and a push during a carry is not one during a grasp (or a
    # set-down, or a release).
    asked: list[bool] = []
    is_held = Scene.is_held

    def held(self: Scene, name: str, min_force_n: float = HELD_FORCE_N) -> bool:
        answer = is_held(self, name, min_force_n)
        if min_force_n == HELD_FORCE_N:  # asked for the push (not where the grasp locates it)
            asked.append(answer)
        return answer

    monkeypatch.setattr(Scene, "is_held", held)
    push = {
        "at_s": 2.45,
        "object": "parcel",
        "force_n": [0.0, 10.0, 0.0],
        "duration_s": 0.05,
        "while_held": True,
    }
    report = run_episode(_world([push]), None, out=None, animation=False)
    (entry,) = report.disturbances
    assert entry["skipped"] is True and entry["steps"] == 0
    # The palms held it then (2 N each or more): it was skipped for resting on the table.
    assert asked[:1] == [True]
    assert report.success, report.failure

"""Hard mode (``app.py trials --hard``, issue 16): each trial's physics differs from its world.

A Hard trial is the Easy trial of the same seed and index (:func:`experiment.layout.draw_trial`:
the same start, goals and obstacles) run against a physical truth drawn, from the campaign seed
and the trial's index alone, within the world file's ``trials.hard`` ranges
(:class:`worlds.world_file.HardSettings`):

- each object's mass and friction scaled, the palms' friction scaled, the table top raised or
  lowered (the object starting on it), each fixture moved sideways (a distance uniform in
  ``fixture_offset_m``, a direction uniform on the table): :class:`worlds.truth.PhysicalTruth`,
  which only the physics sees; the reasoner, the tree and the skills read the world file's
  values;
- each object's sensed start pose off by a normal error along x, y and in yaw, until both
  palms first hold it (:class:`worlds.sim_world.SimWorld`);
- the actuators' faults: a torque scale and a bias per joint, one lag time constant for all,
  a latency of whole physics steps (:mod:`worlds.actuators`);
- pushes on each object, a Poisson process of ``push_rate_hz`` over the run's whole time
  window ``[0, max_sim_time_s)``, each of a uniform force in a direction uniform on the sphere
  (up and down included) for a uniform duration, added to the trial world's
  ``disturbances``. They fall where the clock puts them: during carries, and also while the
  object rests or is being grasped.

Each kind of draw comes from a generator of its own, ``default_rng([seed, trial, 3, part])``
(the layout's streams are ``[seed, trial]`` and ``[seed, trial, 1 or 2, redraw]``), so that
changing one range leaves the other draws as they were.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.actuators import ActuatorFaults
from worlds.robots import robot_model_of
from worlds.spec import DisturbanceSpec
from worlds.truth import FixtureTruth, ObjectTruth, PhysicalTruth
from worlds.world_file import HardSettings, World, as_world_spec, world_from_data

#: Third key of every Hard trial's generators.
HARD_STREAM = 3
#: Fourth key, per kind of draw.
OBJECTS, BODIES, ACTUATORS, PUSHES, FIXTURES = range(5)


@dataclass(frozen=True)
class HardTrial:
    """What one Hard trial drew.

    Attributes
    ----------
    truth : PhysicalTruth
        The physics the trial runs against.
    pushes : tuple of DisturbanceSpec
        Pushes on the objects, in each object's time order, objects in world order.
    """

    truth: PhysicalTruth
    pushes: tuple[DisturbanceSpec, ...]

    def summary(self) -> dict[str, Any]:
        """JSON-ready: every value drawn, as used (a record's ``hard``)."""
        return {
            **self.truth.summary(),
            "pushes": [
                {
                    "object": p.object,
                    "at_s": p.at_s,
                    "duration_s": p.duration_s,
                    "force_n": list(p.force_n),
                }
                for p in self.pushes
            ],
        }


def _rng(seed: int, trial: int, part: int) -> np.random.Generator:
    return np.random.default_rng([seed, trial, HARD_STREAM, part])


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(*bounds))


def draw_pushes(
    rng: np.random.Generator,
    name: str,
    rate_hz: float,
    window_s: float,
    force_n: tuple[float, float],
    duration_s: tuple[float, float],
) -> tuple[DisturbanceSpec, ...]:
    """Pushes on object ``name``: a Poisson process of ``rate_hz`` over ``[0, window_s)``
    (exponential gaps), each of a force uniform in ``force_n`` (N) in a direction uniform on
    the sphere, for a duration uniform in ``duration_s`` (s); each acts only if the palms hold
    the object when it starts (``while_held``: pushes during carries)."""
    if rate_hz <= 0.0:
        return ()
    pushes = []
    t = float(rng.exponential(1.0 / rate_hz))
    while t < window_s:
        magnitude = _uniform(rng, force_n)
        duration = _uniform(rng, duration_s)
        direction = rng.normal(size=3)
        while (norm := float(np.linalg.norm(direction))) < 1e-12:  # never, but not a NaN
            direction = rng.normal(size=3)
        fx, fy, fz = (float(v) for v in magnitude * direction / norm)
        pushes.append(DisturbanceSpec(name, t, duration, (fx, fy, fz), while_held=True))
        t += float(rng.exponential(1.0 / rate_hz))
    return tuple(pushes)


def draw_hard(world: World, seed: int, trial: int) -> HardTrial:
    """The physical truth and the pushes of Hard trial ``trial`` of campaign ``seed``, within
    ``world.trials.hard``; the same numbers for the same world, seed and trial, always."""
    ranges: HardSettings = world.trials.hard
    spec = as_world_spec(world)
    rng = _rng(seed, trial, OBJECTS)
    objects = []
    for obj in spec.scene.objects:
        mass = _uniform(rng, ranges.mass_scale)
        friction = _uniform(rng, ranges.friction_scale)
        dx, dy = (float(v) for v in rng.normal(0.0, ranges.pose_sigma_m, size=2))
        dyaw = float(rng.normal(0.0, math.radians(ranges.yaw_sigma_deg)))
        objects.append(ObjectTruth(obj.name, mass, friction, (dx, dy), dyaw))
    rng = _rng(seed, trial, BODIES)
    palm = _uniform(rng, ranges.palm_friction_scale)
    table_dz = _uniform(rng, ranges.table_dz_m)
    model = robot_model_of(spec.scene.robot)
    # One fault per driven joint, in the controller's order (the iiwas: left arm, right arm;
    # the iCub: torso, left arm, right arm).
    limits = np.array([joint.max_torque for joint in model.driven_joints()], dtype=float)
    rng = _rng(seed, trial, ACTUATORS)
    scale = rng.uniform(*ranges.torque_scale, size=limits.size)
    bias = rng.uniform(-1.0, 1.0, size=limits.size) * ranges.torque_bias * limits
    faults = ActuatorFaults(
        tuple(float(v) for v in scale),
        tuple(float(v) for v in bias),
        _uniform(rng, ranges.torque_lag_s),
        ranges.latency_ticks,
    )
    rng = _rng(seed, trial, PUSHES)
    pushes = tuple(
        push
        for obj in spec.scene.objects
        for push in draw_pushes(
            rng,
            obj.name,
            ranges.push_rate_hz,
            spec.max_sim_time_s,
            ranges.push_force_n,
            ranges.push_duration_s,
        )
    )
    rng = _rng(seed, trial, FIXTURES)
    fixtures = []
    for fixture in spec.scene.fixtures:
        distance = _uniform(rng, ranges.fixture_offset_m)
        heading = float(rng.uniform(0.0, 2.0 * math.pi))
        offset = (distance * math.cos(heading), distance * math.sin(heading))
        fixtures.append(FixtureTruth(fixture.name, offset))
    truth = PhysicalTruth(tuple(objects), palm, table_dz, faults, tuple(fixtures))
    return HardTrial(truth, pushes)


def with_pushes(world: World, pushes: tuple[DisturbanceSpec, ...]) -> World:
    """``world`` with ``pushes`` after its own disturbances."""
    data = world.model_dump(mode="json")
    data["disturbances"] = list(data.get("disturbances", [])) + [
        {
            "at_s": p.at_s,
            "object": p.object,
            "force_n": list(p.force_n),
            "duration_s": p.duration_s,
            "torque_nm": list(p.torque_nm),
            "while_held": p.while_held,
        }
        for p in pushes
    ]
    return world_from_data(data, world.source)


__all__ = ["HARD_STREAM", "HardTrial", "draw_hard", "draw_pushes", "with_pushes"]

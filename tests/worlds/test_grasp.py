"""Contact-only bimanual grasp: two impedance-controlled palms lift, hold, carry and place a parcel.

The palms follow scripted minimum-jerk pose targets; the parcel is held by squeeze and friction
alone (no constraints, no teleporting).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from skills.vocabulary import Arm
from worlds.control import PalmCommand
from worlds.palm_poses import lateral_grasp_palm_poses
from worlds.scene import Scene
from worlds.spec import SceneSpec

pytestmark = pytest.mark.sim

PARCEL = "parcel"
HALF_SPAN = 0.15  # the parcel's half extent along y, m
PALM_THICKNESS = 0.02
SQUEEZE = 0.015  # target this far inside the face, m
START = np.array([0.6, 0.0, 0.675])


def minimum_jerk(s: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Minimum-jerk profile 10 s^3 - 15 s^4 + 6 s^5 on [0, 1]."""
    s = np.clip(s, 0.0, 1.0)
    return np.asarray(s**3 * (10.0 - 15.0 * s + 6.0 * s**2))


@dataclass
class Log:
    """Samples taken every ``every`` physics steps during a segment."""

    time: list[float] = field(default_factory=list)
    parcel_in_palms: list[NDArray[np.float64]] = field(default_factory=list)
    tilt_deg: list[float] = field(default_factory=list)
    force: dict[Arm, list[float]] = field(default_factory=lambda: {Arm.LEFT: [], Arm.RIGHT: []})
    #: Both palms' upward force on the parcel (Scene.palm_load), summed, N.
    load: list[float] = field(default_factory=list)


def parcel_in_palms(scene: Scene) -> NDArray[np.float64]:
    """Parcel centre relative to the palms' midpoint, world frame, m, (3,)."""
    position, _ = scene.object_pose(PARCEL)
    palms = [scene.palm_state(arm).position for arm in (Arm.LEFT, Arm.RIGHT)]
    return position - 0.5 * (palms[0] + palms[1])


def tilt_deg(scene: Scene) -> float:
    """Angle between the parcel's z axis and the world z axis, degrees."""
    _, quaternion = scene.object_pose(PARCEL)
    z_axis = Rotation.from_quat(quaternion).apply([0.0, 0.0, 1.0])
    return float(np.degrees(np.arccos(np.clip(z_axis[2], -1.0, 1.0))))


def segment(
    scene: Scene,
    centre_from: NDArray[np.float64],
    centre_to: NDArray[np.float64],
    gap_from: float,
    gap_to: float,
    squeeze: float,
    duration: float,
    log: Log | None = None,
    every: int = 24,
) -> None:
    """Move the palm targets with a minimum-jerk profile; commands change at control rate."""
    per_command = scene.spec.physics_hz // scene.spec.control_hz
    steps = round(duration * scene.spec.physics_hz)
    for k in range(0, steps, per_command):
        s = float(minimum_jerk((k + per_command) / steps))
        centre = centre_from + (centre_to - centre_from) * s
        gap = gap_from + (gap_to - gap_from) * s
        poses = lateral_grasp_palm_poses(centre, HALF_SPAN, PALM_THICKNESS, gap)
        for arm, (position, quaternion) in poses.items():
            scene.set_palm_command(arm, PalmCommand(position, quaternion, squeeze_offset=squeeze))
        for _ in range(per_command):
            scene.step()
            if log is not None and scene.step_count % every == 0:
                log.time.append(scene.time)
                log.parcel_in_palms.append(parcel_in_palms(scene))
                log.tilt_deg.append(tilt_deg(scene))
                for arm in (Arm.LEFT, Arm.RIGHT):
                    log.force[arm].append(scene.palm_contact_force(arm, PARCEL))
                log.load.append(sum(scene.palm_load(arm, PARCEL) for arm in (Arm.LEFT, Arm.RIGHT)))


def start_scene(refresh_every: int | None = None) -> Scene:
    """Default scene, palms placed 8 cm outside the parcel's +-y faces, settled 0.2 s."""
    scene = Scene(SceneSpec(), refresh_every=refresh_every)
    scene.place_palms(lateral_grasp_palm_poses(START, HALF_SPAN, PALM_THICKNESS, gap=0.08))
    scene.step(48)
    return scene


def grasp(scene: Scene) -> None:
    """Approach from 8 cm outside, close to contact, squeeze."""
    segment(scene, START, START, 0.08, 0.0, 0.0, 1.0)
    segment(scene, START, START, 0.0, 0.0, SQUEEZE, 0.5)


@dataclass(frozen=True)
class PickAndPlace:
    """What the scripted pick and place measured."""

    before_lift: NDArray[np.float64]
    after_carry: NDArray[np.float64]
    height_after_lift: float
    lift: Log
    hold: Log
    carry: Log
    placed: NDArray[np.float64]
    place_target: NDArray[np.float64]
    released_force: tuple[float, float]
    released_load: float
    settled_speed: float
    final_tilt: float


@pytest.fixture(scope="module")
def run() -> PickAndPlace:
    """Grasp, lift 20 cm, hold 5 s, carry 20 cm along +y, put down, release."""
    with start_scene() as scene:
        grasp(scene)
        before_lift = parcel_in_palms(scene)
        up = START + np.array([0.0, 0.0, 0.2])
        side = up + np.array([0.0, 0.2, 0.0])
        down = side - np.array([0.0, 0.0, 0.2])
        lift, hold, carry = Log(), Log(), Log()
        segment(scene, START, up, 0.0, 0.0, SQUEEZE, 1.5, lift)
        height_after_lift = float(scene.object_pose(PARCEL)[0][2])
        segment(scene, up, up, 0.0, 0.0, SQUEEZE, 5.0, hold)
        segment(scene, up, side, 0.0, 0.0, SQUEEZE, 1.5, carry)
        after_carry = parcel_in_palms(scene)
        segment(scene, side, down, 0.0, 0.0, SQUEEZE, 1.5)
        segment(scene, down, down, 0.0, 0.08, 0.0, 1.0)
        placed, _ = scene.object_pose(PARCEL)
        released = (
            scene.palm_contact_force(Arm.LEFT, PARCEL),
            scene.palm_contact_force(Arm.RIGHT, PARCEL),
        )
        scene.step(60)
        return PickAndPlace(
            before_lift=before_lift,
            after_carry=after_carry,
            height_after_lift=height_after_lift,
            lift=lift,
            hold=hold,
            carry=carry,
            placed=placed,
            place_target=down,
            released_force=released,
            released_load=sum(scene.palm_load(arm, PARCEL) for arm in (Arm.LEFT, Arm.RIGHT)),
            settled_speed=float(np.linalg.norm(scene.object_velocity(PARCEL)[0])),
            final_tilt=tilt_deg(scene),
        )


def test_grasp_lifts_the_parcel_20_cm(run: PickAndPlace) -> None:
    # 20 cm lift less the palms' sag under the parcel's weight (5 N on a 1000 N/m spring).
    np.testing.assert_allclose(run.height_after_lift, START[2] + 0.2, atol=0.01)


def test_parcel_does_not_slip_in_the_palms(run: PickAndPlace) -> None:
    offsets = np.concatenate(
        [np.asarray(log.parcel_in_palms) for log in (run.lift, run.hold, run.carry)]
    )
    slip = np.linalg.norm(offsets - run.before_lift, axis=1)
    assert slip.max() < 0.01, f"slip {slip.max() * 1000:.2f} mm"
    assert np.linalg.norm(run.after_carry - run.before_lift) < 0.01


def test_parcel_stays_level(run: PickAndPlace) -> None:
    tilts = run.lift.tilt_deg + run.hold.tilt_deg + run.carry.tilt_deg
    assert max(tilts) < 5.0


def test_steady_squeeze_during_hold(run: PickAndPlace) -> None:
    for arm in (Arm.LEFT, Arm.RIGHT):
        force = np.asarray(run.hold.force[arm])
        assert np.all((force > 5.0) & (force < 60.0)), (
            f"{arm}: {force.min():.1f}..{force.max():.1f} N"
        )
        # Steady: varies by less than 2 N over the 5 s hold.
        assert np.ptp(force) < 2.0


def test_the_palms_loads_carry_the_parcels_weight(run: PickAndPlace) -> None:
    # Held still, the palms' upward forces (normal and friction) are what holds the parcel up:
    # its weight, 1 kg x 9.81 m/s^2 (the default scene's parcel).
    np.testing.assert_allclose(run.hold.load, 9.81, rtol=0.03)
    # Resting on the table, released, the palms carry nothing.
    assert run.released_load == 0.0


def test_parcel_is_placed_and_released(run: PickAndPlace) -> None:
    np.testing.assert_allclose(run.placed, run.place_target, atol=0.01)
    assert run.released_force == (0.0, 0.0)
    assert run.settled_speed < 1e-3
    assert run.final_tilt < 2.0


def test_same_seed_same_run() -> None:
    finals = []
    for _ in range(2):
        with start_scene() as scene:
            grasp(scene)
            segment(scene, START, START + np.array([0.0, 0.0, 0.1]), 0.0, 0.0, SQUEEZE, 0.5)
            finals.append(scene.state_vector())
    np.testing.assert_array_equal(finals[0], finals[1])


def test_exact_law_holds_the_parcel_too() -> None:
    """refresh_every=1 (Jacobian and gravity every physics step) gives the same grasp."""
    with start_scene(refresh_every=1) as scene:
        grasp(scene)
        reference = parcel_in_palms(scene)
        segment(scene, START, START + np.array([0.0, 0.0, 0.1]), 0.0, 0.0, SQUEEZE, 1.0)
        assert np.linalg.norm(parcel_in_palms(scene) - reference) < 0.005
        assert scene.palm_contact_force(Arm.LEFT, PARCEL) > 5.0

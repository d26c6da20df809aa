"""The compiled composition step gives the float step's numbers within 1e-9."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from skills import _kernels
from skills import quaternion as quat
from skills.composer import (
    COMMANDS,
    PHASES,
    ROW_SIZE,
    DualArmComposer,
    DualArmState,
    PalmCommands,
)
from skills.couplings import (
    DistanceQuery,
    GraspMaintenance,
    ObstacleSteering,
    PotentialFieldAvoidance,
    SphereObstacles,
    steering,
)
from skills.default_library import build_default_library
from skills.dmp import DMPParams
from skills.dual_arm import ARMS, GraspGeometry
from skills.labels import Action
from skills.pose_dmp import LearntForcing, PoseModel, PoseState, Weighted, fit_pose
from skills.types import Array
from tests.skills.conftest import pick_place_demo
from tests.skills.test_composer import (
    DT,
    OBSTACLE,
    Push,
    full_composition,
    perturbed,
    sphere,
    start_state,
)

TOLERANCE = 1e-9
#: And relative to size: a point inside an obstacle gets accelerations of 1e4 m/s^2 and more.
RELATIVE = 1e-12
FIELDS = ("positions", "orientations", "twists", "object_twist")

needs_numba = pytest.mark.skipif(not _kernels.COMPILED, reason="numba is not installed")


def compiled_twin(composer: DualArmComposer) -> DualArmComposer:
    """The same composition, compiled (its own plan)."""
    return replace(composer, compiled=True)


def assert_same(a: DualArmComposer, b: DualArmComposer, ca: PalmCommands, cb: PalmCommands) -> None:
    for sa, sb in zip(
        (a.state.object, a.state.left, a.state.right),
        (b.state.object, b.state.left, b.state.right),
        strict=True,
    ):
        for x, y in zip(sa[:6], sb[:6], strict=True):
            assert_allclose(y, x, rtol=RELATIVE, atol=TOLERANCE)
        assert sb.phase == pytest.approx(sa.phase, rel=0, abs=1e-15)
    for name in FIELDS:
        assert_allclose(getattr(cb, name), getattr(ca, name), rtol=RELATIVE, atol=TOLERANCE)


def run_both(composer: DualArmComposer, steps: int, seed: int | None = None) -> float:
    """Step the float and compiled twins side by side; closed loop on perturbed states when
    ``seed`` is given. Returns the largest absolute difference seen in the object's pose."""
    fast = compiled_twin(composer)
    rng = np.random.default_rng(seed) if seed is not None else None
    worst = 0.0
    for _ in range(steps):
        if rng is None:
            ca, cb = composer.step(DT), fast.step(DT)
        else:
            s = composer.state
            measured = DualArmState(*(perturbed(p, rng) for p in (s.object, s.left, s.right)))
            ca, cb = composer.step(DT, measured), fast.step(DT, measured)
        assert_same(composer, fast, ca, cb)
        worst = max(
            worst, float(np.abs(composer.state.object.position - fast.state.object.position).max())
        )
        fast.state = composer.state  # compare steps, not the drift of two rollouts
    return worst


@needs_numba
def test_a_whole_move_matches_the_float_path() -> None:
    # Every kind of term: learnt skills (weights 1 and 0.8), steering, an 8-point field,
    # and terms without a kernel (a saturated group, arrays-only terms on every space).
    composer = full_composition()
    run_both(composer, 150)
    assert composer.state.object.phase < 0.02  # the move ran to its end


@needs_numba
def test_closed_loop_on_measured_states_matches_the_float_path() -> None:
    composer = full_composition()
    for _ in range(40):  # mid-move, moving towards the obstacle
        composer.step(DT)
    run_both(composer, 20, seed=3)


@needs_numba
def test_free_rollouts_stay_together() -> None:
    # Not reset each step: two rollouts of a whole move stay within the tolerance.
    composer = full_composition()
    fast = compiled_twin(composer)
    for _ in range(150):
        composer.step(DT)
        fast.step(DT)
    for a, b in zip(composer.state.object[:6], fast.state.object[:6], strict=True):
        assert_allclose(b, a, rtol=0, atol=TOLERANCE)


def avoidance_only(
    centres: Array, radii: list[float], points: Array, query: DistanceQuery = sphere
) -> DualArmComposer:
    lib = build_default_library()
    steer = lib.first(Action.AVOID_OBSTACLE).params
    steering = ObstacleSteering(
        float(steer["gamma"]), float(steer["beta"]), float(steer["k"]), object_radius=0.1
    ).with_obstacles(centres, radii)
    g = GraspGeometry.lateral(0.30)
    absolute = [
        (steering, 1.3),
        (PotentialFieldAvoidance(query, points, gain=0.4, beta=1.5, influence=np.inf), 0.7),
    ]
    relative = {
        arm: [(GraspMaintenance(g.position(arm), g.orientation(arm), 0.0), 1.0)] for arm in ARMS
    }
    return DualArmComposer.start(
        start_state(), [0.75, -0.1, 0.7], quat.IDENTITY, 1.5, absolute, relative
    )


@needs_numba
def test_many_obstacles_and_field_options_match() -> None:
    # Three steering obstacles (one behind), a field with beta 1.5 and no influence limit.
    centres = np.array([OBSTACLE, [0.62, -0.02, 0.70], [0.45, 0.0, 0.675]])
    points = np.array([[0.05, 0.1, 0.05], [0.0, -0.1, 0.0], [0.1, 0.0, 0.1]])
    run_both(avoidance_only(centres, [0.04, 0.03, 0.05], points), 90)


@needs_numba
@pytest.mark.parametrize("count", [0, 1, 3])
def test_sphere_obstacles_queried_in_the_kernel_match(count: int) -> None:
    # The field's spheres are queried inside the kernel; the float path calls the same
    # SphereObstacles. The third sphere is crossed by a link point (a negative distance).
    centres = np.array([OBSTACLE, [0.62, -0.02, 0.70], [0.62, 0.05, 0.72]])[:count]
    radii = [0.04, 0.03, 0.05][:count]
    points = np.array([[0.05, 0.1, 0.05], [0.0, -0.1, 0.0], [0.1, 0.0, 0.1]])
    composer = avoidance_only(centres, radii, points, SphereObstacles(centres, radii))
    run_both(composer, 90)
    assert not compiled_twin(composer)._resolved().compiled.queries  # type: ignore[union-attr]


@needs_numba
def test_a_field_without_points_and_no_obstacles_match() -> None:
    run_both(avoidance_only(np.zeros((0, 3)), [], np.zeros((0, 3))), 30)


@needs_numba
def test_a_forced_base_model_matches() -> None:
    # The base's own forcing (a composer built on a learnt model) has its own kernel kind.
    model = build_default_library().first(Action.TRANSPORT).pose_model()
    s = start_state()
    target = model.target(
        s.object.position, s.object.orientation, [0.7, 0.1, 0.7], quat.IDENTITY, 2.0
    )
    still = DualArmComposer.start(s, [0.7, 0.1, 0.7], quat.IDENTITY, 2.0)
    composer = replace(
        still, base=model, target=target, absolute=(Weighted(Push([0, 0, 0.1], [0, 0, 0]), 1.0),)
    )
    assert np.any(target.effective_weights[:, :6])
    run_both(composer, 60)


@needs_numba
def test_a_state_replaced_by_the_caller_is_read_afresh() -> None:
    # The composer's own states carry the buffer they are views of; a state built from
    # them by replace must not: the compiled step would read the old values.
    composer = full_composition()
    fast = compiled_twin(composer)
    for _ in range(10):
        fast.step(DT)
    moved = replace(
        fast.state, object=fast.state.object._replace(position=fast.state.object.position + 0.01)
    )
    assert moved._values is None
    composer.state = fast.state
    assert_same(composer, fast, composer.step(DT, moved), fast.step(DT, moved))


@needs_numba
def test_reassigned_terms_are_packed_again() -> None:
    composer = compiled_twin(full_composition())
    composer.step(DT)
    composer.absolute = (Weighted(Push([0.0, 0.3, 0.0], [0.0, 0.0, 0.2]), 1.0),)
    float_twin = replace(composer, compiled=False)
    assert_same(float_twin, composer, float_twin.step(DT), composer.step(DT))


@needs_numba
def test_a_query_of_the_wrong_shape_is_named() -> None:
    def bad(points: Array) -> tuple[Array, Array]:
        return np.zeros(len(points)), np.zeros((len(points), 2))

    field = PotentialFieldAvoidance(bad, [[0.0, 0.1, 0.0]])
    composer = DualArmComposer.start(
        start_state(), [0.7, 0.0, 0.7], quat.IDENTITY, 1.0, [(field, 1.0)], compiled=True
    )
    with pytest.raises(
        ValueError, match=r"query: expected distances \(1,\) and closest points \(1, 3\)"
    ):
        composer.step(DT)


def test_without_numba_asking_for_it_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_kernels, "COMPILED", False)
    with pytest.raises(RuntimeError, match=r"needs numba.*\.\[fast\]"):
        DualArmComposer.start(start_state(), [0.7, 0.0, 0.7], quat.IDENTITY, 1.0, compiled=True)


def test_the_float_path_is_the_default() -> None:
    composer = DualArmComposer.start(start_state(), [0.7, 0.0, 0.7], quat.IDENTITY, 1.0)
    assert composer.compiled is False
    assert PoseModel.still().params == composer.base.params


def test_a_rollout_is_the_steps_one_after_another() -> None:
    composer = full_composition()
    stepped = replace(composer)
    rollout = composer.rollout(30, DT)
    assert len(rollout) == 30
    for i in range(30):
        cmd = stepped.step(DT)
        assert_array_equal(rollout.palm_positions[i], cmd.positions)
        assert_array_equal(rollout.palm_orientations[i], cmd.orientations)
        assert_array_equal(rollout.palm_twists[i], cmd.twists)
        assert_array_equal(rollout.commands(i).object_twist, cmd.object_twist)
        assert_array_equal(rollout.object_positions[i], stepped.state.object.position)
        assert_array_equal(rollout.object_orientations[i], stepped.state.object.orientation)
        for got, want in zip(rollout.state(i).right, stepped.state.right, strict=True):
            assert_array_equal(got, want)
    for got, want in zip(composer.state.object, stepped.state.object, strict=True):
        assert_array_equal(got, want)  # the composer ends at the last state


def test_a_rollout_of_no_steps_and_bad_counts() -> None:
    composer = full_composition()
    before = composer.state
    assert len(composer.rollout(0, DT)) == 0
    assert composer.state is before
    for bad in (-1, 2.5, True):
        with pytest.raises(ValueError, match="steps: expected an integer >= 0"):
            composer.rollout(bad, DT)  # type: ignore[arg-type]


@needs_numba
@pytest.mark.parametrize("in_kernel", [True, False])
def test_a_compiled_rollout_matches_the_float_rollout(in_kernel: bool) -> None:
    # All terms with kernels and spheres queried inside: one call for the whole rollout.
    # Otherwise (a Python query, terms without kernels) one call per step.
    centres, radii = np.array([OBSTACLE, [0.62, -0.02, 0.70]]), [0.04, 0.03]
    points = np.array([[0.05, 0.1, 0.05], [0.0, -0.1, 0.0], [0.1, 0.0, 0.1]])
    query = SphereObstacles(centres, radii) if in_kernel else sphere
    composer = avoidance_only(centres, radii, points, query)
    fast = compiled_twin(composer)
    want, got = composer.rollout(90, DT), fast.rollout(90, DT)
    assert_allclose(got.values, want.values, rtol=RELATIVE, atol=TOLERANCE)
    assert fast.state.object.phase == pytest.approx(composer.state.object.phase, abs=1e-15)
    assert_allclose(fast.state.object.position, composer.state.object.position, atol=TOLERANCE)


def test_the_kernels_write_the_rows_the_rollout_reads() -> None:
    assert (_kernels.PHASES, _kernels.COMMANDS, _kernels.SIZE) == (PHASES, COMMANDS, ROW_SIZE)
    assert _kernels.COLLINEAR == steering._COLLINEAR


def test_a_state_cut_from_a_buffer_reads_as_the_views_it_stands_for() -> None:
    composer = full_composition()
    composer.step(DT)
    lazy = composer.state
    assert "object" not in vars(lazy)  # nothing cut yet
    values = lazy._values
    assert values is not None
    eager = DualArmState(
        *(
            PoseState(
                values[b : b + 3],
                values[b + 3 : b + 6],
                values[b + 6 : b + 9],
                values[b + 9 : b + 13],
                values[b + 13 : b + 16],
                values[b + 16 : b + 19],
                float(values[PHASES + i]),
            )
            for i, b in enumerate((0, 19, 38))
        )
    )
    for got, want in zip(
        (lazy.object, lazy.left, lazy.right), (eager.object, eager.left, eager.right), strict=True
    ):
        for a, b in zip(got, want, strict=True):
            assert_array_equal(a, b)
    assert lazy.right.position.base is values  # views, not copies
    assert repr(lazy) == repr(eager)
    restored = pickle.loads(pickle.dumps(composer.step(DT) and composer.state))
    assert_array_equal(restored.left.velocity, composer.state.left.velocity)
    with pytest.raises(AttributeError, match="has no attribute 'middle'"):
        lazy.middle  # type: ignore[attr-defined]  # noqa: B018


@needs_numba
def test_other_gains_and_bases_of_two_sizes_match() -> None:
    # A forced base on 20 basis functions with its own gains, a learnt term on 50: the
    # kernel keeps one activation buffer for the larger and one table per basis.
    params = DMPParams(alpha=30.0, alpha_s=3.0, n_basis=20)
    base = fit_pose(pick_place_demo(), params)
    s = start_state()
    goal = ([0.7, 0.1, 0.7], quat.from_axis_angle([0.0, 0.0, 1.0], 0.3))
    learnt = build_default_library().first(Action.TRANSPORT).pose_model()
    still = DualArmComposer.start(s, *goal, 2.0, [(LearntForcing(learnt), 0.5)], params=params)
    target = base.target(s.object.position, s.object.orientation, *goal, 2.0)
    run_both(replace(still, base=base, target=target), 100)


@needs_numba
def test_stepping_on_from_its_own_states_never_cuts_them() -> None:
    # A compiled step reads a state the composer cut straight from its buffer; terms without
    # kernels (here a saturated group and arrays-only terms) get the state as views of it.
    fast = compiled_twin(full_composition())
    twin = full_composition()
    fast.step(DT)
    twin.step(DT)
    for _ in range(5):
        before = fast.state  # cut by the last step
        cmd = fast.step(DT)
        assert "object" not in vars(before)
        assert_allclose(cmd.twists, twin.step(DT).twists, rtol=RELATIVE, atol=TOLERANCE)

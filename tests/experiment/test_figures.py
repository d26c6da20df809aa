"""The trajectory figure draws any task to scale: views, footprints, headings, obstacles and
the demonstration each move actually ran."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest
from numpy.testing import assert_allclose
from py_trees.common import Status

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import Circle, Polygon

from experiment.figures import (
    SKILL_COLOURS,
    MoveTrace,
    OtherObject,
    convex_hull_2d,
    demonstrated_path,
    draw_move,
    fitted_title,
    headings,
    outline,
    side_view,
    top_view,
    trajectory_drawing,
    trajectory_figure,
)
from planner.move_result import move_results
from planner.testing import CONTROL_DT, FakeWorld, grasp_object, set_up_carry, tick_until
from skills import quaternion as quat
from skills.default_library import build_default_library
from skills.demonstration import Demonstration
from skills.library import SkillLibrary
from skills.pose_model import fit_pose
from skills.skill import Provenance, Skill, learnt_skill
from skills.vocabulary import Action, Space
from worlds.spec import ObstacleSpec, ShapeSpec

PARCEL = ShapeSpec.box([0.20, 0.30, 0.15])
YAW_90 = quat.from_axis_angle([0, 0, 1], np.pi / 2)


def wave_skill() -> Skill:
    """A taught transport that swings 8 cm sideways on the way and never lifts."""
    t = np.linspace(0.0, 2.0, 201)
    r = t / t[-1]
    s = r**3 * (10.0 - 15.0 * r + 6.0 * r**2)  # minimum jerk: from rest to rest
    positions = np.column_stack((0.3 * s, 0.08 * np.sin(np.pi * s), np.zeros_like(s)))
    orientations = np.tile(quat.IDENTITY, (len(t), 1))
    model = fit_pose(Demonstration.create(t, positions, orientations, name="wave"))
    return learnt_skill(
        "wave", Action.TRANSPORT, Space.ABSOLUTE, model, (), Provenance.now(("wave",), "test")
    )


def test_the_side_view_is_the_vertical_plane_of_the_moves_own_direction() -> None:
    start, goal = np.array([0.6, 0.15, 0.675]), np.array([0.6, -0.15, 0.675])
    view = side_view(start, goal)  # a move along -y
    assert_allclose(view.project(goal), [[0.30, 0.675]], atol=1e-12)
    # Orthographic: a point off the plane shows where its foot in the plane does.
    assert_allclose(view.project([0.7, 0.0, 0.8]), view.project([0.6, 0.0, 0.8]), atol=1e-12)
    # ... and says how far off it is: seen from -x, a point at larger x is farther.
    assert view.depth([0.7, 0.0, 0.8]) == pytest.approx(0.1)
    assert view.depth([0.6, -0.3, 0.9]) == pytest.approx(0.0)
    diagonal = side_view(np.zeros(3), np.array([0.1, 0.1, 0.0]))
    assert_allclose(diagonal.project([0.1, 0.1, 0.2]), [[np.hypot(0.1, 0.1), 0.2]], atol=1e-12)
    assert "heading 45 deg" in diagonal.name
    upright = side_view(np.zeros(3), np.array([0.0, 0.0, 0.2]))  # no travel across: along y
    assert_allclose(upright.axes[0], [0.0, 1.0, 0.0])
    # A goal where the object started, measured 2 mm off: its "heading -12 deg" was noise.
    still = side_view(np.array([0.55, 0.0, 0.675]), np.array([0.552, -0.0004, 0.675]))
    assert still.name == "side view, no horizontal travel (along y)"
    assert_allclose(still.axes[0], [0.0, 1.0, 0.0])


def test_a_one_move_figures_legend_stays_under_its_axis_labels(tmp_path: Path) -> None:
    # One column holds two legend entries a line: its three lines had covered "along the move".
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    library = build_default_library()
    start, goal = np.array([0.5, 0.0, 0.675]), np.array([0.6, 0.1, 0.675])
    trace = MoveTrace(
        "parcel move 1",
        start,
        goal,
        np.linspace(start, goal, 50),
        (),
        orientations=np.tile(YAW_90, (50, 1)),
        goal_orientation=YAW_90,
        shape=PARCEL,
        skill="pick_and_place",
        demonstrated=demonstrated_path(library.get("pick_and_place"), start, YAW_90, goal, YAW_90),
    )
    fig = trajectory_drawing([trace], "one move")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    (legend,) = fig.legends
    box = legend.get_window_extent(renderer)
    side = fig.axes[-1]  # the bottom panel, the side view
    assert side.get_title().endswith("heading 45 deg")
    assert side.xaxis.label.get_window_extent(renderer).y0 > box.y1
    assert min(t.get_window_extent(renderer).y0 for t in side.get_xticklabels()) > box.y1
    assert trajectory_figure([trace], tmp_path / "one.png", "one move").stat().st_size > 10_000


def test_footprints_are_to_scale_and_turned_with_the_object() -> None:
    def span(poly: np.ndarray) -> np.ndarray:
        return poly.max(axis=0) - poly.min(axis=0)

    top = top_view()  # (y, x)
    assert_allclose(span(outline(PARCEL, [0.5, 0.0, 0.7], quat.IDENTITY, top)), [0.30, 0.20])
    assert_allclose(span(outline(PARCEL, [0.5, 0.0, 0.7], YAW_90, top)), [0.20, 0.30])
    along_45 = side_view(np.zeros(3), np.array([1.0, 1.0, 0.0]))
    assert_allclose(
        span(outline(PARCEL, [0.5, 0.0, 0.7], quat.IDENTITY, along_45)),
        [(0.20 + 0.30) / np.sqrt(2.0), 0.15],
    )


def test_the_hull_is_qhulls_corners_counter_clockwise() -> None:
    spatial = pytest.importorskip("scipy.spatial")
    rng = np.random.default_rng(4)
    for n in (3, 8, 50, 400):
        points = rng.normal(size=(n, 2))
        corners = convex_hull_2d(points)
        assert sorted(corners) == sorted(spatial.ConvexHull(points).vertices)
        ring = points[corners]
        edges = np.roll(ring, -1, axis=0) - ring
        turns = (
            edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1]
            - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
        )
        assert np.all(turns > 0.0)  # every corner a left turn: convex, counter-clockwise
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [0.5, 0.5], [1, 1]], float)
    assert sorted(convex_hull_2d(square)) == [0, 1, 2, 3]  # edge and inner points left out
    assert list(convex_hull_2d(np.array([[0, 0], [1, 1], [2, 2.0]]))) == [0, 2]  # a segment


def test_the_heading_is_the_objects_x_axis() -> None:
    arrows = headings(np.array([quat.IDENTITY, YAW_90]), top_view())
    assert_allclose(arrows, [[0.0, 1.0], [1.0, 0.0]], atol=1e-12)  # (y, x) of its x-axis


def test_obstacles_are_drawn_in_their_own_shapes_and_sizes() -> None:
    trace = MoveTrace(
        "box move 1",
        np.array([0.5, 0.0, 0.675]),
        np.array([0.6, 0.0, 0.675]),
        np.zeros((0, 3)),
        (
            ObstacleSpec("ball", ShapeSpec.sphere(0.04), (0.55, -0.2, 0.8)),
            ObstacleSpec("post", ShapeSpec.box([0.06, 0.10, 0.20]), (0.8, 0.1, 0.7)),
        ),
    )
    fig, (top, side) = plt.subplots(1, 2)
    draw_move(top, trace, top_view())
    draw_move(side, trace, side_view(trace.start, trace.goal))
    for ax, box_span in ((top, [0.10, 0.06]), (side, [0.06, 0.20])):
        circles = [p for p in ax.patches if isinstance(p, Circle)]
        assert [c.get_radius() for c in circles] == [0.04]
        (box,) = [p for p in ax.patches if isinstance(p, Polygon)]
        xy = box.get_xy()
        assert_allclose(xy.max(axis=0) - xy.min(axis=0), box_span, atol=1e-12)
    plt.close(fig)


def test_the_demonstration_drawn_is_the_skill_the_move_ran() -> None:
    library = build_default_library()
    start, goal = np.array([0.55, 0.0, 0.675]), np.array([0.85, 0.0, 0.675])
    lift = demonstrated_path(
        library.get("pick_and_place"), start, quat.IDENTITY, goal, quat.IDENTITY
    )
    wave = demonstrated_path(wave_skill(), start, quat.IDENTITY, goal, quat.IDENTITY)
    assert lift is not None and wave is not None
    assert lift[:, 2].max() - start[2] == pytest.approx(0.12, abs=0.02)  # the demonstrated lift
    assert abs(lift[:, 1]).max() < 0.005
    assert abs(wave[:, 2] - start[2]).max() < 0.005  # the wave never lifts ...
    assert wave[:, 1].max() == pytest.approx(0.08, abs=0.01)  # ... but swings sideways
    assert_allclose(wave[-1], goal, atol=2e-3)


def test_a_move_records_the_taught_skill_its_transport_ran(fake_world: FakeWorld) -> None:
    library = SkillLibrary([wave_skill(), *build_default_library()])  # the first transport
    grasp_object(fake_world, library)
    leaf = set_up_carry(
        fake_world,
        library,
        leaf_name="move0",
    )
    assert tick_until(leaf, fake_world, CONTROL_DT, max_ticks=3000).final == Status.SUCCESS
    assert move_results()[("parcel", 0)].skill == "wave"


def test_the_figure_is_written_for_moves_of_several_objects(tmp_path: Path) -> None:
    library = build_default_library()
    skill = library.get("pick_and_place")
    traces = []
    for k, (name, y) in enumerate((("left", 0.2), ("left", 0.25), ("right", -0.2))):
        start, goal = np.array([0.5, y, 0.675]), np.array([0.6, y + 0.02, 0.675])
        path = np.linspace(start, goal, 50)
        traces.append(
            MoveTrace(
                f"{name} move {k + 1}",
                start,
                goal,
                path,
                (),
                orientations=np.tile(YAW_90, (50, 1)),
                goal_orientation=YAW_90,
                shape=PARCEL,
                skill="pick_and_place",
                demonstrated=demonstrated_path(skill, start, YAW_90, goal, YAW_90),
            )
        )
    out = trajectory_figure(traces, tmp_path / "trajectories.png", "two objects")
    assert out.stat().st_size > 10_000


def test_each_skill_is_drawn_in_its_own_colour() -> None:
    # Two moves, one carried with the shipped carry and one with a taught wave: two entries.
    start, goal = np.array([0.55, 0.0, 0.675]), np.array([0.85, 0.0, 0.675])
    skills = (build_default_library().get("pick_and_place"), wave_skill())
    fig, axes = plt.subplots(1, 2)
    for ax, skill, colour in zip(axes, skills, SKILL_COLOURS, strict=False):
        demo = demonstrated_path(skill, start, quat.IDENTITY, goal, quat.IDENTITY)
        trace = MoveTrace(
            "move", start, goal, np.empty((0, 3)), (), skill=skill.name, demonstrated=demo
        )
        draw_move(ax, trace, top_view(), colour)
    drawn = [
        line.get_color()
        for ax in axes
        for line in ax.get_lines()
        if line.get_label().startswith("demonstrated")
    ]
    plt.close(fig)
    assert drawn == list(SKILL_COLOURS[:2])


def test_a_long_title_is_wrapped_to_the_figures_width() -> None:
    assert fitted_title("parcel_pick_place: success", 13.2) == ("parcel_pick_place: success", 12.0)
    reason = "task.parcel.pick_and_place.move_centre.carry.grip_intact: not held: " * 3
    text, size = fitted_title(f"w: failure: tree failure: {reason}", 13.2)
    assert size == 9.0 and 1 < len(text.splitlines()) <= 3
    assert max(len(line) for line in text.splitlines()) <= int(13.2 * 13.5)
    text, _ = fitted_title("word " * 200, 4.4)
    assert len(text.splitlines()) == 3 and text.endswith("[...]")


def test_a_wrapped_title_stands_above_the_panels_titles() -> None:
    # A long failure reason wraps to three lines: the figure grows above its panels for them.
    start, goal = np.array([0.55, 0.0, 0.675]), np.array([0.65, 0.1, 0.675])
    trace = MoveTrace("parcel move 1", start, goal, np.linspace(start, goal, 20), (), shape=PARCEL)
    reason = "task.parcel.pick_and_place.move_centre.carry.grip_intact: not held: " * 4
    short = trajectory_drawing([trace], "w: success")
    fig = trajectory_drawing([trace], f"w: failure: {reason}")
    renderer = fig.canvas.get_renderer()
    title = fig._suptitle.get_window_extent(renderer)
    assert len(fig._suptitle.get_text().splitlines()) == 3
    for ax in fig.axes:
        assert ax.title.get_window_extent(renderer).y1 < title.y0
    # The panels keep their size: only the room above them grows.
    assert fig.get_size_inches()[1] > short.get_size_inches()[1]
    # (to a thousandth: the legend's room below, set once the panels are drawn, moves their
    # equal-aspect boxes by a hundredth of a pixel)
    assert_allclose(
        fig.axes[0].get_position().height * fig.get_size_inches()[1],
        short.axes[0].get_position().height * short.get_size_inches()[1],
        rtol=1e-3,
    )


def test_the_other_objects_are_drawn_where_they_lay() -> None:
    start, goal = np.array([0.55, 0.0, 0.675]), np.array([0.65, 0.0, 0.675])
    crate = OtherObject("crate", ShapeSpec.box([0.1, 0.1, 0.1]), np.array([0.6, 0.3, 0.65]),
                        YAW_90)  # fmt: skip
    trace = MoveTrace("parcel move 1", start, goal, np.empty((0, 3)), (), others=(crate,))
    fig, ax = plt.subplots()
    drawn = draw_move(ax, trace, top_view())
    patches = [p for p in ax.patches if p.get_label() == "other object"]
    texts = [t.get_text() for t in ax.texts]
    plt.close(fig)
    assert len(patches) == 1 and texts == ["crate"]
    # Its footprint, seen from above (y across, x up): 10 cm square about (0.3, 0.6).
    corners = patches[0].get_xy()
    assert_allclose(corners.min(axis=0), [0.25, 0.55], atol=1e-9)
    assert_allclose(corners.max(axis=0), [0.35, 0.65], atol=1e-9)
    assert any(np.allclose(d, corners[: len(d)]) for d in drawn if len(d) >= 4)


def test_a_side_view_marks_an_other_object_wholly_beside_the_move_as_an_obstacle_is() -> None:
    # Flattened onto the move's plane, a crate 30 cm beside it had been drawn over the carried
    # parcel as if the parcel were inside it.
    start, goal = np.array([0.55, 0.0, 0.675]), np.array([0.65, 0.0, 0.675])
    shape = ShapeSpec.box([0.2, 0.3, 0.15])
    beside = OtherObject("crate", ShapeSpec.box([0.1, 0.1, 0.1]), np.array([0.6, 0.3, 0.65]),
                         quat.IDENTITY)  # fmt: skip
    touching = OtherObject("tote", ShapeSpec.box([0.1, 0.1, 0.1]), np.array([0.8, 0.05, 0.65]),
                           quat.IDENTITY)  # fmt: skip
    trace = MoveTrace(
        "parcel move 1", start, goal, np.empty((0, 3)), (), others=(beside, touching),
        shape=shape,
    )  # fmt: skip
    fig, ax = plt.subplots()
    draw_move(ax, trace, side_view(start, goal))
    patches = [p for p in ax.patches if p.get_label() == "other object"]
    alphas = {t.get_text(): p.get_alpha() for p, t in zip(patches, ax.texts, strict=True)}
    plt.close(fig)
    # Seen from the move's right (heading 0): +y is farther.
    assert alphas == {"crate\n30 cm farther": 0.15, "tote": 0.35}

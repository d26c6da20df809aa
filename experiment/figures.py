"""What a run shows a person: the trajectory figure and the animation.

- :func:`trajectory_figure`: in the style of the paper's Fig. 3, per move of every object:
  the learnt transport skill the move actually ran, alone from the move's start to its goal
  (green, another colour for each other skill: its demonstration as the skill generalises
  it), the executed path of the object (blue) with its heading (arrows of its x-axis), its
  footprint to scale at the start (dashed) and the goal (solid), and the obstacles in their
  own shapes (red), in a top view and a side view along the move's own direction, both at
  equal axis scales; a title too long for one line (a failure's reason) wrapped.
- :class:`Animation`: frames from PyBullet's CPU renderer (TinyRenderer) written as a GIF.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from planner.atomic_file import atomic_path
from skills import quaternion as quat
from skills.pose_dmp import pose_rollout
from skills.skill import Skill, SkillKind
from skills.state import PoseState
from skills.types import Array
from worlds.bullet import pb
from worlds.fixture_spec import FixtureSpec
from worlds.spec import ObstacleSpec, Shape, ShapeSpec

#: Heading arrows drawn along each executed path.
HEADING_ARROWS = 8
#: Moves per row of the figure (a row is a top view above a side view).
COLUMNS = 4


@dataclass(frozen=True)
class MoveTrace:
    """One move as executed.

    Attributes
    ----------
    label : str
        What the move is, e.g. ``"parcel move 1"``.
    start, goal : ndarray, shape (3,)
        Object centre at the start and the goal, m.
    path : ndarray, shape (N, 3)
        Executed (measured) object centre positions, m.
    obstacles : tuple of ObstacleSpec
        The obstacles present during the move, with their shapes.
    start_orientation, goal_orientation : ndarray, shape (4,)
        Object orientation at the start and the goal, ``(x, y, z, w)``.
    orientations : ndarray, shape (N, 4)
        Executed (measured) object orientations along ``path``.
    shape : ShapeSpec or None
        The object's shape, for its footprint.
    skill : str or None
        The learnt transport skill the move ran.
    fixtures : tuple of FixtureSpec
        The open fixtures on the table (their walls drawn grey).
    others : tuple of OtherObject
        The task's other objects where they lay as the move started (where they lay when the
        run ended, for a move never started), drawn grey: what its arms had to keep off.
    demonstrated : ndarray, shape (K, 3), or None
        That skill alone from ``start`` to ``goal`` (:func:`demonstrated_path`); None when the
        move was never carried.
    """

    label: str
    start: Array
    goal: Array
    path: Array
    obstacles: tuple[ObstacleSpec, ...]
    start_orientation: Array = field(default_factory=lambda: quat.IDENTITY.copy())
    goal_orientation: Array = field(default_factory=lambda: quat.IDENTITY.copy())
    orientations: Array = field(default_factory=lambda: np.zeros((0, 4)))
    shape: ShapeSpec | None = None
    skill: str | None = None
    demonstrated: Array | None = None
    fixtures: tuple[FixtureSpec, ...] = ()
    others: tuple[OtherObject, ...] = ()


@dataclass(frozen=True)
class OtherObject:
    """One of the task's other objects as a move's figure draws it: its name, shape and pose
    (position (3,) m, quaternion (4,) scalar-last, world frame)."""

    name: str
    shape: ShapeSpec
    position: Array
    quaternion: Array


def demonstrated_path(
    skill: Skill,
    start: ArrayLike,
    start_orientation: ArrayLike,
    goal: ArrayLike,
    goal_orientation: ArrayLike,
    dt: float = 0.01,
) -> Array | None:
    """A learnt skill's own motion from ``start`` to ``goal``: its demonstration generalised.

    The skill's pose DMP rolled out alone (no coupling terms) over 1.5 times its demonstrated
    duration, so the path is what the demonstration means for this move, (K, 3), m. None for
    a skill that is not a learnt DMP.
    """
    if skill.kind is not SkillKind.LEARNT_DMP:
        return None
    model = skill.pose_model()
    target = model.target(start, start_orientation, goal, goal_orientation)
    return pose_rollout(model, target, PoseState.at_rest(start, start_orientation), dt).positions


def shape_points(shape: ShapeSpec) -> Array:
    """Points whose convex hull is the shape (not a sphere), body frame, (M, 3), m."""
    if shape.kind is Shape.BOX:
        half = np.asarray(shape.size) / 2.0
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        return corners * half
    if shape.kind is Shape.CYLINDER:
        a = np.linspace(0.0, 2.0 * np.pi, 48, endpoint=False)
        ring = np.column_stack((shape.radius * np.cos(a), shape.radius * np.sin(a)))
        h = shape.height / 2.0
        return np.vstack([np.column_stack((ring, np.full(len(a), z))) for z in (-h, h)])
    if shape.kind is Shape.SPHERE:
        a = np.linspace(0.0, 2.0 * np.pi, 48, endpoint=False)
        r = shape.radius
        return np.vstack(
            [
                np.column_stack((r * np.cos(a), r * np.sin(a), np.zeros_like(a))),
                np.column_stack((r * np.cos(a), np.zeros_like(a), r * np.sin(a))),
                np.column_stack((np.zeros_like(a), r * np.cos(a), r * np.sin(a))),
            ]
        )
    return shape.mesh_vertices()


@dataclass(frozen=True)
class View:
    """An orthographic view: world points to the plot's (horizontal, vertical) axes."""

    name: str
    axes: Array  # (2, 3): horizontal and vertical unit vectors, world frame
    origin: Array  # (3,): world point at the plot's (0, 0)
    labels: tuple[str, str]
    #: The horizontal axis grows to the left.
    mirrored: bool = False
    #: Draw the object's heading (its x-axis) along the path.
    heading: bool = False
    #: Mark obstacles off the plotted plane with their distance from it (a side view).
    marks_depth: bool = False

    def project(self, points: ArrayLike) -> Array:
        """(N, 3) world points to (N, 2) plot coordinates."""
        return (np.atleast_2d(np.asarray(points, dtype=float)) - self.origin) @ self.axes.T

    def depth(self, point: ArrayLike) -> float:
        """How far beyond the plotted plane a point is, seen by the viewer, m (negative:
        nearer the viewer, who looks along ``-cross(horizontal, vertical)``)."""
        toward_viewer = np.cross(self.axes[0], self.axes[1])
        return -float((np.asarray(point, dtype=float) - self.origin) @ toward_viewer)


def top_view() -> View:
    """From above, as the paper draws it: x up the page, +y (the robot's left) to the left."""
    return View(
        "top view",
        np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]),
        np.zeros(3),
        ("y (m)", "x (m)"),
        mirrored=True,
        heading=True,
    )


#: A move whose goal lies less than this far across the table from its start has no
#: horizontal heading to draw its side view along, m (a placement's own error is millimetres).
STILL_M = 0.01


def side_view(start: Array, goal: Array) -> View:
    """The vertical plane through the move's start and goal, seen from its right.

    Horizontal: distance along the move's horizontal direction from the start; a move with no
    horizontal travel (under :data:`STILL_M`) is seen along y.
    """
    d = np.array([goal[0] - start[0], goal[1] - start[1], 0.0])
    n = float(np.linalg.norm(d))
    along = "along the move (m)"
    if n < STILL_M:  # no horizontal travel: a heading would be the measurement's noise
        u, title = np.array([0.0, 1.0, 0.0]), "side view, no horizontal travel (along y)"
        along = "y from the start (m)"
    else:
        u = d / n
        title = f"side view, heading {round(float(np.degrees(np.arctan2(u[1], u[0])))) + 0:d} deg"
    return View(
        title,
        np.array([u, [0.0, 0.0, 1.0]]),
        np.array([start[0], start[1], 0.0]),
        (along, "z (m)"),
        marks_depth=True,
    )


def convex_hull_2d(points: ArrayLike) -> Array:
    """Indices of the corners of the convex hull of (N, 2) points, counter-clockwise from the
    lowest-leftmost, points on an edge left out (Andrew's monotone chain); a hull of
    collinear points is its two ends, of one point that point."""
    pts = np.asarray(points, dtype=float)
    order = np.lexsort((pts[:, 1], pts[:, 0]))
    distinct = [int(order[0])]
    for i in order[1:]:
        if not np.array_equal(pts[i], pts[distinct[-1]]):
            distinct.append(int(i))
    if len(distinct) < 3:
        return np.array(distinct, dtype=int)

    def chain(indices: list[int]) -> list[int]:
        out: list[int] = []
        for i in indices:
            while len(out) >= 2:
                (ax, ay), (bx, by) = pts[out[-2]], pts[out[-1]]
                cx, cy = pts[i]
                if (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) > 0.0:  # a left turn: keep b
                    break
                out.pop()
            out.append(i)
        return out

    lower, upper = chain(distinct), chain(distinct[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=int)


def outline(shape: ShapeSpec, position: ArrayLike, orientation: ArrayLike, view: View) -> Array:
    """The shape's silhouette in a view, a closed polygon (M, 2) (a sphere's: its circle)."""
    body = shape_points(shape)
    world = np.asarray(position, dtype=float) + quat.rotate(np.asarray(orientation, float), body)
    flat = view.project(world)
    return flat[convex_hull_2d(flat)]


def headings(orientations: Array, view: View) -> Array:
    """The object's x-axis per orientation, in the view's axes, (N, 2)."""
    x_axis = quat.rotate(orientations, np.array([1.0, 0.0, 0.0]))
    return np.atleast_2d(x_axis) @ view.axes.T


#: Colours of the demonstrated paths, one per skill in the order the moves name them.
SKILL_COLOURS = ("green", "tab:olive", "darkcyan", "tab:brown", "tab:pink")


def draw_move(ax: Any, tr: MoveTrace, view: View, demo_colour: str = "green") -> list[Array]:
    """Draw one move in one view (its skill's demonstration in ``demo_colour``); returns the
    plotted points (for the limits)."""
    from matplotlib.patches import Circle, Polygon

    drawn: list[Array] = []
    for fixture in tr.fixtures:
        centres, halves = fixture.walls()
        q = np.asarray(fixture.quaternion, dtype=float)
        r = quat.to_matrix(q)
        for centre, half in zip(centres, halves, strict=True):
            where = np.asarray(fixture.position, dtype=float) + r @ centre
            poly = outline(ShapeSpec.box(tuple(2.0 * half)), where, q, view)
            ax.add_patch(Polygon(poly, closed=True, color="0.55", alpha=0.7, label="fixture"))
            drawn.append(poly)
    for ob in tr.obstacles:
        # A side view flattens depth: an obstacle beside the move's plane is drawn pale and
        # says how far beside it is, so a path drawn across it is not read as a collision.
        off = view.depth(ob.position)
        beside = view.marks_depth and abs(off) > 0.5 * float(min(ob.shape.extents()))
        alpha = 0.35 if beside else 0.8
        c = view.project(ob.position)[0]
        if ob.shape.kind is Shape.SPHERE:
            ax.add_patch(
                Circle(tuple(c), ob.shape.radius, color="red", alpha=alpha, label="obstacle")
            )
            drawn.append(c + ob.shape.radius * np.array([[1, 1], [-1, -1]]))
        else:
            poly = outline(ob.shape, ob.position, quat.IDENTITY, view)
            ax.add_patch(Polygon(poly, closed=True, color="red", alpha=alpha, label="obstacle"))
            drawn.append(poly)
        if beside:
            side = "farther" if off > 0 else "nearer"
            ax.text(*c, f"{abs(off) * 100:.0f} cm\n{side}", ha="center", va="center", fontsize=6)
    carried = 0.5 * float(max(tr.shape.extents())) if tr.shape is not None else 0.0
    for other in tr.others:
        poly = outline(other.shape, other.position, other.quaternion, view)
        # As an obstacle: an object wholly beside the carried one's plane is drawn paler, with
        # how far beside, so the carried object is not read as inside it.
        off = view.depth(other.position)
        beside = view.marks_depth and abs(off) > 0.5 * float(max(other.shape.extents())) + carried
        ax.add_patch(
            Polygon(
                poly, closed=True, color="0.6", alpha=0.15 if beside else 0.35, label="other object"
            )
        )
        side = f"\n{abs(off) * 100:.0f} cm {'farther' if off > 0 else 'nearer'}" if beside else ""
        ax.text(*poly.mean(axis=0), other.name + side, ha="center", va="center", fontsize=6)
        drawn.append(poly)
    if tr.shape is not None:
        for where, q, style, what in (
            (tr.start, tr.start_orientation, dict(ls="--", lw=1.0, ec="0.45"), "at the start"),
            (tr.goal, tr.goal_orientation, dict(ls="-", lw=1.2, ec="black"), "at the goal"),
        ):
            poly = outline(tr.shape, where, q, view)
            ax.add_patch(Polygon(poly, closed=True, fill=False, label=f"object {what}", **style))
            drawn.append(poly)
    if tr.demonstrated is not None:
        demo = view.project(tr.demonstrated)
        ax.plot(*demo.T, color=demo_colour, lw=2.2, label=f"demonstrated: {tr.skill}")
        drawn.append(demo)
    if len(tr.path):
        path = view.project(tr.path)
        ax.plot(*path.T, color="tab:blue", lw=1.8, label="executed")
        drawn.append(path)
        if view.heading and len(tr.orientations) == len(tr.path):
            # Heading: the object's x-axis, from its executed orientations.
            picks = np.unique(np.linspace(0, len(path) - 1, HEADING_ARROWS).round().astype(int))
            length = 0.35 * float(tr.shape.extents()[0]) if tr.shape is not None else 0.05
            arrows = headings(tr.orientations[picks], view) * length
            ax.quiver(
                *path[picks].T,
                *arrows.T,
                angles="xy",
                scale_units="xy",
                scale=1.0,
                width=0.006,
                color="tab:purple",
                label="heading (object x-axis)",
            )
    start, goal = view.project(tr.start)[0], view.project(tr.goal)[0]
    ax.plot(*start, "ko", ms=4)
    ax.plot(*goal, "k+", ms=10, mew=2)
    drawn += [start[None], goal[None]]
    return drawn


#: The figure's margins, inches: left of the axes (tick labels and the vertical axis label),
#: right, above the top row (the title), below the bottom row (the horizontal axis label
#: and the legend), and between panels across and down.
MARGINS_IN = {"left": 0.75, "right": 0.2, "top": 0.75, "bottom": 0.95, "across": 0.8, "down": 0.8}
#: The bottom margin's share under the panels that is not the legend's (ticks, axis label and
#: the legend's gap to the figure's edge), and each line of the legend, in.
LEGEND_ABOVE_IN = 0.62
LEGEND_LINE_IN = 0.2
#: The legend's frame and padding, in (a one-move figure's three lines had covered its
#: bottom panel's axis label without it).
LEGEND_FRAME_IN = 0.25


def figure_style() -> Any:
    """The figure's style, a context to draw and save it in: the grid from the start, not
    ax.grid() after (that restyles every tick made so far)."""
    import matplotlib

    return matplotlib.rc_context({"axes.grid": True, "grid.alpha": 0.3})


#: The height of each line a long title wraps to beyond its first, inches (9 pt, spaced).
TITLE_LINE_IN = 0.16


def trajectory_figure(traces: Sequence[MoveTrace], path: Path, title: str) -> Path:
    """Write the top and side views of every move to ``path`` (PNG); see the module's doc."""
    fig = trajectory_drawing(traces, title)
    path.parent.mkdir(parents=True, exist_ok=True)
    # Drawn in the same style it was made in (ticks the canvas makes as it draws take it).
    with figure_style(), atomic_path(path) as temporary:
        fig.savefig(temporary, dpi=110, format="png")
    return path


def trajectory_drawing(traces: Sequence[MoveTrace], title: str) -> Any:
    """The figure :func:`trajectory_figure` writes (a matplotlib ``Figure`` on an Agg
    canvas), drawn but not saved."""
    with figure_style():
        return _drawing(traces, title)


def _drawing(traces: Sequence[MoveTrace], title: str) -> Any:
    # The object interface on an Agg canvas, not pyplot: no global figure to close.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    n = max(1, len(traces))
    cols = min(n, COLUMNS)
    rows = -(-n // cols)
    width = 4.4 * cols
    text, size = fitted_title(title, width)
    # A title wrapped to more lines takes room above the panels, not over their titles.
    m = {**MARGINS_IN, "top": MARGINS_IN["top"] + TITLE_LINE_IN * text.count("\n")}
    height = 7.8 * rows + m["top"] - MARGINS_IN["top"]
    panel_w = (width - m["left"] - m["right"] - (cols - 1) * m["across"]) / cols
    panel_h = (height - m["top"] - m["bottom"] - (2 * rows - 1) * m["down"]) / (2 * rows)
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    # Fixed margins, not tight_layout: that measures every label of every panel by drawing
    # them, which took as long as drawing the figure itself.
    axes = fig.subplots(
        2 * rows,
        cols,
        squeeze=False,
        gridspec_kw={
            "left": m["left"] / width,
            "right": 1.0 - m["right"] / width,
            "top": 1.0 - m["top"] / height,
            "bottom": m["bottom"] / height,
            "wspace": m["across"] / panel_w,
            "hspace": m["down"] / panel_h,
        },
    )
    top = top_view()
    tops: list[tuple[Any, list[Array]]] = []
    sides: list[tuple[Any, list[Array]]] = []
    # Each skill's demonstrations in a colour of its own (a move may name a taught one).
    skills = list(dict.fromkeys(tr.skill for tr in traces if tr.demonstrated is not None))
    colours = {k: SKILL_COLOURS[i % len(SKILL_COLOURS)] for i, k in enumerate(skills)}
    for k, tr in enumerate(traces):
        r, c = divmod(k, cols)
        ax_top, ax_side = axes[2 * r, c], axes[2 * r + 1, c]
        side = side_view(tr.start, tr.goal)
        colour = colours.get(tr.skill, SKILL_COLOURS[0])
        tops.append((ax_top, draw_move(ax_top, tr, top, colour)))
        sides.append((ax_side, draw_move(ax_side, tr, side, colour)))
        for ax, view in ((ax_top, top), (ax_side, side)):
            ax.set_xlabel(view.labels[0])
            ax.set_ylabel(view.labels[1])
            ax.set_title(f"{tr.label}: {view.name}", fontsize=8, y=1.0)
            if view.mirrored:
                ax.invert_xaxis()
        if tr.demonstrated is None:
            # Carried but never placed (a failed carry) is not the same as never carried.
            note = "not placed" if len(tr.path) else "never carried"
            ax_top.text(0.02, 0.02, note, transform=ax_top.transAxes, fontsize=8)
    for k in range(len(traces), rows * cols):
        r, c = divmod(k, cols)
        axes[2 * r, c].set_visible(False)
        axes[2 * r + 1, c].set_visible(False)
    # Top views share one frame, so moves compare; side views share their heights. Both are
    # drawn to scale (equal axes), so sizes and clearances read off the figure.
    _frame(tops, share=(True, True))
    _frame(sides, share=(False, True))
    # One legend for the figure: every kind of mark once (demonstrations by skill).
    legend: dict[str, Any] = {}
    for ax, _ in tops:
        handles, labels = ax.get_legend_handles_labels()
        legend.update({lab: h for h, lab in zip(handles, labels, strict=True) if lab not in legend})
    if legend:
        # as many entries across as the figure's width holds (about 2.2 in each)
        across = max(1, min(len(legend), 6, int(width / 2.2)))
        # A narrow figure's legend takes more lines: the figure grows below its panels, so
        # that the legend stays under the bottom panels' axis labels, not over them.
        needed = LEGEND_ABOVE_IN + LEGEND_FRAME_IN + LEGEND_LINE_IN * -(-len(legend) // across)
        if needed > m["bottom"]:
            height += needed - m["bottom"]
            fig.set_size_inches(width, height)
            grid = axes[0, 0].get_subplotspec().get_gridspec()
            grid.update(bottom=needed / height, top=1.0 - m["top"] / height)
        fig.legend(
            legend.values(),
            legend.keys(),
            loc="lower center",
            ncol=across,
            fontsize=8,
            bbox_to_anchor=(0.5, 0.08 / height),
        )
    fig.suptitle(text, y=1.0 - 0.25 / height, fontsize=size)
    return fig


def fitted_title(title: str, width_in: float) -> tuple[str, float]:
    """``title`` as it fits a figure ``width_in`` inches wide above its panels, and its font
    size: one line at 12 pt if it fits, else wrapped at 9 pt to three lines at most (a long
    failure reason, the last line cut with an ellipsis)."""
    import textwrap

    if len(title) <= int(width_in * 9.5):  # about 9.5 characters an inch at 12 pt
        return title, 12.0
    lines = textwrap.wrap(title, width=int(width_in * 13.5), break_long_words=True)
    if len(lines) > 3:
        lines = [*lines[:2], textwrap.shorten(" ".join(lines[2:]), int(width_in * 13.5))]
        if not lines[2].endswith("[...]"):
            lines[2] += " [...]"
    return "\n".join(lines), 9.0


def _frame(panels: list[tuple[Any, list[Array]]], share: tuple[bool, bool]) -> None:
    """Set limits around what each panel drew (shared over panels per axis) and equal scales."""
    if not panels:
        return
    bounds = []
    for _, drawn in panels:
        pts = np.concatenate([np.atleast_2d(d) for d in drawn if len(d)])
        bounds.append((pts.min(axis=0) - 0.03, pts.max(axis=0) + 0.03))
    lo_all = np.min([b[0] for b in bounds], axis=0)
    hi_all = np.max([b[1] for b in bounds], axis=0)
    for (ax, _), (lo, hi) in zip(panels, bounds, strict=True):
        for axis in (0, 1):
            a, b = (lo_all[axis], hi_all[axis]) if share[axis] else (lo[axis], hi[axis])
            if axis == 0:
                ax.set_xlim(*((b, a) if ax.xaxis_inverted() else (a, b)))
            else:
                ax.set_ylim(a, b)
        ax.set_aspect("equal")


class Animation:
    """Frames from PyBullet's CPU renderer, every ``period`` simulated seconds, as a GIF.

    Parameters
    ----------
    client : int
        PyBullet client id.
    target : sequence of float
        Point the camera looks at, m.
    size : (int, int)
        Width and height, pixels.
    period : float
        Simulated seconds between frames.
    distance : float
        Camera distance from a point ``distance / 16`` above ``target``, m; about 1.6 times
        the table's diagonal frames the robot and the table.
    heading_deg : float
        The robot's heading about z, degrees: the camera turns with it.
    """

    def __init__(
        self,
        client: int,
        target: Sequence[float],
        size: tuple[int, int] = (320, 240),
        period: float = 0.2,
        distance: float = 1.9,
        heading_deg: float = 0.0,
    ) -> None:
        self.client = client
        self.size = size
        self.period = period
        self.frames: list[np.ndarray] = []
        self._next = 0.0
        # From the table's far side, a little to the robot's left: both arms and the object.
        look_at = [float(target[0]), float(target[1]), float(target[2]) + distance / 16.0]
        self.view = pb.computeViewMatrixFromYawPitchRoll(
            cameraTargetPosition=look_at,
            distance=distance,
            yaw=110.0 + heading_deg,
            pitch=-24.0,
            roll=0.0,
            upAxisIndex=2,
        )
        self.projection = pb.computeProjectionMatrixFOV(
            fov=50.0, aspect=size[0] / size[1], nearVal=0.05, farVal=5.0
        )

    def maybe_capture(self, sim_time: float) -> None:
        """Capture a frame if ``period`` has passed since the last one."""
        if sim_time + 1e-9 < self._next:
            return
        self._next = sim_time + self.period
        w, h = self.size
        _, _, rgba, _, _ = pb.getCameraImage(
            w,
            h,
            self.view,
            self.projection,
            renderer=pb.ER_TINY_RENDERER,
            physicsClientId=self.client,
        )
        self.frames.append(np.reshape(np.asarray(rgba, dtype=np.uint8), (h, w, 4))[:, :, :3])

    def save_gif(self, path: Path) -> Path | None:
        """Write the frames as an animated GIF (None if there are none)."""
        if not self.frames:
            return None
        from PIL import Image

        images = [Image.fromarray(f) for f in self.frames]
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as temporary:
            images[0].save(
                temporary,
                format="GIF",
                save_all=True,
                append_images=images[1:],
                duration=int(self.period * 1000),
                loop=0,
                optimize=True,
            )
        return path

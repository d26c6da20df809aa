"""What a run shows a person: the trajectory figure and the animation.

- :func:`trajectory_figure`: in the style of the paper's Fig. 3, per move the demonstrated
  pick-and-place (green, carried to the move's start and goal as the skill generalises it),
  the executed path of the object (blue) and the obstacles (red), top and side views.
- :class:`Animation`: frames from PyBullet's CPU renderer (TinyRenderer) written as a GIF.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet as pb

from planner.port import ObstacleInfo
from skills.scaling import Scaling, scaling_matrix
from skills.types import Array


@dataclass(frozen=True)
class MoveTrace:
    """One move as executed.

    Attributes
    ----------
    index : int
    start, goal : ndarray, shape (3,)
        Object centre at the start and the goal, m.
    path : ndarray, shape (N, 3)
        Executed object centre positions, m.
    obstacles : tuple of ObstacleInfo
    """

    index: int
    start: Array
    goal: Array
    path: Array
    obstacles: tuple[ObstacleInfo, ...]


def demonstration_for(demo_positions: Array, start: Array, goal: Array) -> Array:
    """The demonstrated path carried to a new start and goal, turned about the vertical.

    The same mapping the pick-and-place skill's forcing uses (``Scaling.ROTATION_Z``), so the
    green path is what the demonstration means for this move.
    """
    ref = demo_positions[-1] - demo_positions[0]
    m = scaling_matrix(Scaling.ROTATION_Z, goal - start, ref)
    out = start + (demo_positions - demo_positions[0]) @ m.T
    # The end point follows the vertical difference the skill's attractor adds.
    blend = np.linspace(0.0, 1.0, len(out))[:, None]
    out[:, 2] += blend[:, 0] * ((goal - start)[2] - (ref[2]))
    return out


def trajectory_figure(
    traces: Sequence[MoveTrace], demo_positions: Array, path: Path, title: str
) -> Path:
    """Write the top and side views of every move to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    # One frame for every panel, around all the paths, goals and obstacles, so moves compare.
    pts = [demo_positions[:1]]
    for tr in traces:
        pts += [tr.path.reshape(-1, 3), tr.start[None], tr.goal[None]]
        pts += [demonstration_for(demo_positions, tr.start, tr.goal)]
        pts += [np.atleast_2d(ob.position) + ob.radius * np.eye(3) for ob in tr.obstacles]
        pts += [np.atleast_2d(ob.position) - ob.radius * np.eye(3) for ob in tr.obstacles]
    allp = np.concatenate([p for p in pts if len(p)])
    lo, hi = allp.min(axis=0) - 0.04, allp.max(axis=0) + 0.04
    limits = list(zip(lo, hi, strict=True))
    fig, axes = plt.subplots(
        2, max(1, len(traces)), figsize=(4.2 * max(1, len(traces)), 7.5), squeeze=False
    )
    for col, tr in enumerate(traces):
        top, side = axes[0, col], axes[1, col]
        demo = demonstration_for(demo_positions, tr.start, tr.goal)
        for ax, (i, j), name in ((top, (1, 0), "top view"), (side, (1, 2), "side view")):
            ax.plot(demo[:, i], demo[:, j], color="green", lw=2.2, label="demonstrated")
            if len(tr.path):
                ax.plot(tr.path[:, i], tr.path[:, j], color="tab:blue", lw=1.8, label="executed")
            for ob in tr.obstacles:
                ax.add_patch(
                    Circle((ob.position[i], ob.position[j]), ob.radius, color="red", alpha=0.8)
                )
            ax.plot(*tr.start[[i, j]], "ko", ms=4)
            ax.plot(*tr.goal[[i, j]], "k+", ms=10, mew=2)
            ax.set_xlim(*limits[i])
            ax.set_ylim(*limits[j])
            ax.set_aspect("equal")
            ax.invert_xaxis()
            ax.set_xlabel("y (m)")
            ax.set_ylabel("x (m)" if name == "top view" else "z (m)")
            ax.set_title(f"move {tr.index + 1}: {name}")
            ax.grid(alpha=0.3)
        if col == 0:
            top.legend(loc="best", fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


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
    """

    def __init__(
        self,
        client: int,
        target: Sequence[float],
        size: tuple[int, int] = (320, 240),
        period: float = 0.2,
        distance: float = 1.9,
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
            yaw=110.0,
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
        images[0].save(
            path,
            save_all=True,
            append_images=images[1:],
            duration=int(self.period * 1000),
            loop=0,
            optimize=True,
        )
        return path

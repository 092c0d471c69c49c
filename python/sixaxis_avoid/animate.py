"""A plan as an animation: the arm moving through the obstacles, as a GIF or MP4.

:func:`plan_frames` replays a plan's interpolated joint motion (each joint along its shortest
angular difference, as the planner checks it) and draws every frame, either with the
package's NumPy isometric renderer (``renderer="numpy"``, the default: no GPU, no display,
the same on every machine) or with MuJoCo's offscreen renderer on the exported MJCF scene
(``renderer="mujoco"``; headless it needs ``MUJOCO_GL=egl`` or ``osmesa``).
:func:`write_frames` writes them with imageio (the ``video`` extra; MP4 through
imageio-ffmpeg). :func:`animate_plan` does both.

Command line::

    python -m sixaxis_avoid.animate --scenario paper_simple --out paper_simple.gif
    python -m sixaxis_avoid.animate --plan plan.json --scenario paper_complex --out p.mp4
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid import _core
from sixaxis_avoid._checks import check_choice, check_positive_int, invalid
from sixaxis_avoid._deps import require
from sixaxis_avoid.verify import _plan_dict, interpolate, plan_argument_parser, plan_of_args

RENDERERS = ("numpy", "mujoco")


def _poses_and_path(plan: Any) -> tuple[np.ndarray, list[tuple[int, int, int]], int]:
    p = _plan_dict(plan)
    poses = np.asarray(p.get("poses_rad") or [], dtype=np.float64).reshape(-1, 6)
    if len(poses) == 0:
        raise invalid("plan", "no poses", "an animation needs a plan with poses (a success)")
    path = [tuple(int(v) for v in c) for c in p["path"]][: len(poses)]
    return poses, path, int(p.get("interpolation_steps", 50))


def plan_frames(
    plan: Any,
    scenario: Any = None,
    *,
    frames_per_move: int = 10,
    size: int = 400,
    renderer: str = "numpy",
    hold_frames: int = 6,
) -> list[np.ndarray]:
    """The frames (``uint8`` ``(H, W, 3)``) of a plan's motion: ``frames_per_move`` per move
    (evenly spaced over the move's interpolation), the last pose held ``hold_frames`` frames.
    ``scenario`` gives the arm and the scene (default: the paper's); the obstacles drawn are
    the plan's own (its cells and, when the plan lists them, its ``obstacle_boxes_mm``)."""
    frames_per_move = check_positive_int("frames_per_move", frames_per_move)
    check_choice("renderer", renderer, RENDERERS)
    poses, path, _ = _poses_and_path(plan)
    s = scenario if isinstance(scenario, _core.Scenario) else _core.Scenario(scenario)
    p = _plan_dict(plan)
    changes: dict[str, Any] = {"obstacles": [tuple(c) for c in p["obstacles"]]}
    if "obstacle_boxes_mm" in p:  # absent from plans written before the key existed
        changes["obstacle_boxes_mm"] = p["obstacle_boxes_mm"]
    s = s.replace(**changes)
    motion = [poses[0]]
    for k in range(len(poses) - 1):
        motion.extend(interpolate(poses[k], poses[k + 1], frames_per_move)[1:])
    moves_done = [0] + [1 + i // frames_per_move for i in range(len(motion) - 1)]
    draw = _numpy_drawer(s, size) if renderer == "numpy" else _mujoco_drawer(s, size)
    frames = [draw(q, path[: k + 1]) for q, k in zip(motion, moves_done)]
    return frames + [frames[-1]] * hold_frames


def _numpy_drawer(s: _core.Scenario, size: int):
    from sixaxis_avoid.render import IsoRenderer, obstacle_boxes_cells

    iso = IsoRenderer(
        s.bounds,
        s.obstacles,
        size=size,
        include_origin=True,
        boxes_cells=obstacle_boxes_cells(s),
    )
    arm = _core.Arm.from_scenario(s)

    def draw(q: np.ndarray, path: Sequence[tuple[int, int, int]]) -> np.ndarray:
        pts = arm.points_mm(q) / s.cell_mm
        return iso.frame(path, tuple(pts[-1]), s.target, pts)

    return draw


def _mujoco_drawer(s: _core.Scenario, size: int):
    if not os.environ.get("MUJOCO_GL") and not os.environ.get("DISPLAY"):
        os.environ["MUJOCO_GL"] = "egl"  # headless; must be set before MuJoCo makes a context
    mujoco = require("mujoco", 'renderer="mujoco"')
    model = mujoco.MjModel.from_xml_string(_core.export_scenario(s, "mjcf"))
    data = mujoco.MjData(model)
    try:
        r = mujoco.Renderer(model, height=size * 3 // 4, width=size)
    except Exception as e:
        raise invalid(
            "renderer",
            "mujoco",
            f"MuJoCo's offscreen renderer failed ({e}); set MUJOCO_GL=egl or osmesa, "
            'or use renderer="numpy"',
        ) from e
    cam = mujoco.MjvCamera()
    lo = np.multiply(s.bounds[0], s.cell_mm / 1000.0)
    hi = np.multiply(s.bounds[1], s.cell_mm / 1000.0)
    cam.lookat[:] = (lo + hi) / 2.0
    cam.distance = float(np.linalg.norm(hi - lo)) * 1.4
    cam.azimuth, cam.elevation = 135.0, -25.0

    def draw(q: np.ndarray, path: Sequence[tuple[int, int, int]]) -> np.ndarray:
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        r.update_scene(data, camera=cam)
        return r.render().copy()

    return draw


def write_frames(frames: Sequence[np.ndarray], path: str | os.PathLike[str], fps: int = 20) -> Path:
    """Write frames as a GIF (looping) or MP4 (by the file's suffix) with imageio; the file
    appears complete or not at all (a GIF through the core's write_atomic; an MP4 written to
    a temporary sibling, then renamed)."""
    iio = require("imageio.v3", "Writing an animation")
    out = Path(path)
    suffix = out.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise invalid("path", str(out), "must end in .gif or .mp4")
    if len(frames) == 0:
        raise invalid("frames", "[]", "an animation needs at least one frame")
    if suffix == ".gif":
        data = iio.imwrite(
            "<bytes>", np.stack(frames), extension=".gif", duration=1000.0 / fps, loop=0
        )
        _core.write_atomic(out, data)
        return out
    # imageio's FFMPEG writer needs a file: written beside the target, then renamed.
    tmp = out.with_name(f".{out.name}.tmp-{os.getpid()}{suffix}")
    try:
        require("imageio_ffmpeg", "Writing an MP4")
        iio.imwrite(tmp, np.stack(frames), fps=fps, plugin="FFMPEG", macro_block_size=1)
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    return out


def animate_plan(
    plan: Any,
    path: str | os.PathLike[str],
    scenario: Any = None,
    *,
    fps: int = 20,
    **frame_kwargs: Any,
) -> Path:
    """:func:`plan_frames` written by :func:`write_frames` to ``path`` (.gif or .mp4)."""
    return write_frames(plan_frames(plan, scenario, **frame_kwargs), path, fps=fps)


def main(argv: list[str] | None = None) -> int:
    ap = plan_argument_parser("python -m sixaxis_avoid.animate", __doc__)
    ap.add_argument("--out", required=True, help="the .gif or .mp4 to write")
    ap.add_argument("--fps", type=int, default=20)
    ap.add_argument("--frames-per-move", type=int, default=10)
    ap.add_argument("--size", type=int, default=400, help="image width, pixels")
    ap.add_argument("--renderer", choices=RENDERERS, default="numpy")
    args = ap.parse_args(argv)
    s = _core.Scenario(args.scenario)
    plan = plan_of_args(args, s)
    if _plan_dict(plan).get("success") is False:
        print(f"no plan to animate: {_plan_dict(plan).get('failure')}", file=sys.stderr)
        return 1
    out = animate_plan(
        plan,
        args.out,
        s,
        fps=args.fps,
        frames_per_move=args.frames_per_move,
        size=args.size,
        renderer=args.renderer,
    )
    print(f"{out} ({out.stat().st_size / 1e6:.2f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Draw the paper's figures from `sixaxis reproduce`'s JSON.

Per scenario: steps per episode with and without assisted learning (Figs. 5 and 8), the
terminal path among the obstacles, first and re-planned side by side (Figs. 4, 7 and 9),
and the arm's poses along the final path (Figs. 6 and 10). PNGs go to --out-dir and are copied to
--docs-dir.

    python scripts/reproduce_figures.py --results results/reproduce/reproduction.json
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--results", type=Path, default=Path("results/reproduce/reproduction.json"))
    p.add_argument("--out-dir", type=Path, default=Path("results/reproduce"))
    p.add_argument(
        "--docs-dir",
        type=Path,
        default=Path("docs/figures"),
        help="copies for the docs; '' to skip",
    )
    p.add_argument(
        "--smooth",
        type=int,
        default=50,
        help="moving-average window of the step curves, episodes",
    )
    p.add_argument("--dpi", type=int, default=110)
    return p.parse_args()


def moving_average(xs: np.ndarray, window: int) -> np.ndarray:
    if window <= 1 or len(xs) < window:
        return xs
    kernel = np.ones(window) / window
    return np.convolve(xs, kernel, mode="valid")


def draw_cubes(ax, cells, color, alpha=0.35, size=1.0):
    """Unit cubes centred on integer cells (axes in cells)."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    h = size / 2
    faces = []
    for x, y, z in cells:
        c = np.array(
            [[x + dx, y + dy, z + dz] for dx in (-h, h) for dy in (-h, h) for dz in (-h, h)]
        )
        idx = [
            [0, 1, 3, 2],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 3, 7, 5],
        ]
        faces.extend([c[i] for i in idx])
    if faces:
        ax.add_collection3d(
            Poly3DCollection(faces, facecolors=color, edgecolors="k", linewidths=0.2, alpha=alpha)
        )


def frame_scene(ax, s):
    lo, hi = np.array(s["bounds"]["min"]), np.array(s["bounds"]["max"])
    ax.set_xlim(lo[0] - 0.5, hi[0] + 0.5)
    ax.set_ylim(lo[1] - 0.5, hi[1] + 0.5)
    ax.set_zlim(lo[2] - 0.5, hi[2] + 0.5)
    ax.set_xlabel("x (cells)")
    ax.set_ylabel("y (cells)")
    ax.set_zlabel("z (cells)")
    ax.set_box_aspect(hi - lo + 1)
    draw_cubes(ax, s["obstacles"], "0.15")
    ax.scatter(*s["start"], color="red", s=60, label="start", depthshade=False)
    ax.scatter(
        *s["target"],
        color="gold",
        edgecolors="k",
        s=90,
        label="target",
        depthshade=False,
    )


def fig_steps(s, smooth, path, dpi):
    fig, ax = plt.subplots(figsize=(7, 4))
    for key, label, color in (
        ("unassisted", "without assisted learning", "tab:blue"),
        ("assisted", "with assisted learning", "black"),
    ):
        curve = np.asarray(s[key]["mean_steps_per_episode"], dtype=float)
        ax.plot(np.arange(len(curve)), curve, color=color, alpha=0.15, lw=0.5)
        sm = moving_average(curve, smooth)
        ax.plot(
            np.arange(len(sm)) + (len(curve) - len(sm)),
            sm,
            color=color,
            lw=1.4,
            label=label,
        )
    ax.set_yscale("log")
    ax.set_xlabel("episode")
    ax.set_ylabel("steps per episode (mean over seeds)")
    ax.set_title(f"{s['name']}: learning performance")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def draw_path(ax, p, color, label, ls="-"):
    p = np.asarray(p)
    ax.plot(p[:, 0], p[:, 1], p[:, 2], color=color, lw=2, ls=ls, label=label)


def fig_path(s, path, dpi):
    """The first learned path (paper Fig. 7) and, after a re-plan, the re-planned path with
    the recorded points (paper Fig. 9), side by side."""
    plan = s["plans"][0]["result"]
    rounds = plan["rounds"]
    first = rounds[0]["path"] if rounds and rounds[0]["path"] else None
    replanned = plan["replans"] > 0 and plan["path"]
    panels = 2 if replanned else 1
    fig = plt.figure(figsize=(6 * panels, 6))
    ax = fig.add_subplot(1, panels, 1, projection="3d")
    frame_scene(ax, s)
    if first:
        draw_path(ax, first, "tab:blue", f"first learned path ({len(first) - 1} steps)")
    blocked = rounds[0].get("blocked_at") if rounds else None
    if blocked:
        ax.scatter(
            *blocked[1], color="tab:red", marker="X", s=120, depthshade=False, label="dead end"
        )
    nd = rounds[0]["orientation_divisions"] if rounds else "?"
    fig_no = "Fig. 7" if replanned else "Fig. 4"
    ax.set_title(f"{s['name']}: first path, n_d = {nd} ({fig_no})")
    ax.legend(loc="upper left")
    if replanned:
        ax = fig.add_subplot(1, 2, 2, projection="3d")
        frame_scene(ax, s)
        draw_path(ax, plan["path"], "tab:green", f"re-planned path ({len(plan['path']) - 1} steps)")
        draw_cubes(ax, plan["added_obstacles"], "tab:red", alpha=0.5, size=0.6)
        for c in plan["added_obstacles"]:
            ax.scatter(*c, color="tab:red", marker="X", s=120, depthshade=False)
        status = "ok" if plan["success"] else "FAILED"
        nds = ", ".join(str(r["orientation_divisions"]) for r in rounds)
        ax.set_title(
            f"after {plan['replans']} re-plan(s), n_d = {nds}: {status} (Fig. 9)\n"
            "red: points recorded as obstacles"
        )
        ax.legend(loc="upper left")
    fig.suptitle(f"seed 0, mode {rounds[-1]['mode'] if rounds else '?'}")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def fig_poses(s, path, dpi):
    plan = s["plans"][0]
    points = plan.get("arm_points_mm") or []
    cell = plan["result"]["cell_mm"]
    fig = plt.figure(figsize=(6, 6))
    ax = fig.add_subplot(projection="3d")
    frame_scene(ax, s)
    cmap = plt.get_cmap("viridis")
    n = len(points)
    for i, pts in enumerate(points):
        p = np.asarray(pts) / cell
        ax.plot(p[:, 0], p[:, 1], p[:, 2], "-o", color=cmap(i / max(n - 1, 1)), lw=1.5, ms=2)
    if n:
        terminal = np.asarray([pts[-1] for pts in points]) / cell
        ax.plot(
            terminal[:, 0],
            terminal[:, 1],
            terminal[:, 2],
            color="tab:red",
            lw=1,
            ls=":",
        )
    fig_no = "Fig. 10" if plan["result"]["replans"] > 0 else "Fig. 6"
    ax.set_title(f"{s['name']}: the arm's motion, {n} poses (seed 0, {fig_no})")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def main() -> None:
    args = parse_args()
    data = json.loads(args.results.read_text())
    args.out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for s in data["scenarios"]:
        name = s["name"]
        for suffix, draw in (
            ("steps", lambda p, s=s: fig_steps(s, args.smooth, p, args.dpi)),
            ("path", lambda p, s=s: fig_path(s, p, args.dpi)),
            ("poses", lambda p, s=s: fig_poses(s, p, args.dpi)),
        ):
            out = args.out_dir / f"{name}_{suffix}.png"
            tmp = out.with_suffix(".tmp.png")
            draw(tmp)
            tmp.replace(out)
            written.append(out)
    if str(args.docs_dir):
        args.docs_dir.mkdir(parents=True, exist_ok=True)
        for f in written:
            shutil.copyfile(f, args.docs_dir / f.name)
    print(json.dumps({"figures": [str(f) for f in written]}))


if __name__ == "__main__":
    main()

"""Rendering of the grid world: an isometric view drawn with NumPy only.

The static scene (floor grid, bounds box, obstacles, cells the arm cannot reach) is drawn
once into a background image with shaded cube sprites in painter's order (a scenario's
``obstacle_boxes_mm`` as shaded boxes of the same style, in cells: mm / ``cell_mm``); each
frame then copies a cached layer holding the path so far (extended incrementally) and draws
the target, the terminal and optionally the arm's polyline on top. Dynamic elements are drawn
over the obstacles on purpose, so that the terminal is never hidden.

``human`` mode shows the same frames in a Matplotlib window; without a display (Linux with
neither ``DISPLAY`` nor ``WAYLAND_DISPLAY``) Matplotlib's non-interactive Agg backend is
used, so nothing opens and nothing fails. Matplotlib is optional (the ``render`` extra):
without it, ``human`` mode raises Gymnasium's ``DependencyNotInstalled`` naming the extra.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from sixaxis_avoid._deps import require

Cell = tuple[int, int, int]

BACKGROUND = (250, 250, 252)
FLOOR = (214, 218, 226)
BOX = (150, 156, 170)
OBSTACLE = (120, 126, 140)
UNREACHABLE = (236, 150, 150)
TARGET = (46, 170, 90)
TERMINAL = (214, 52, 52)
PATH = (240, 150, 30)
ARM = (40, 80, 170)
ARM_JOINT = (20, 40, 100)

_FACE_SHADE = {1: 1.0, 2: 0.78, 3: 0.62}  # top, +x face, +y face


class _Sprite:
    """A shaded cube of edge ``edge`` cells (or a box of edges ``(ex, ey, ez)`` cells),
    rasterised once: pixel offsets and colours."""

    def __init__(
        self,
        project_rel,
        edge: float | Sequence[float],
        colour: Sequence[int],
        alpha: float = 1.0,
    ):
        ex, ey, ez = (edge, edge, edge) if np.isscalar(edge) else edge
        a, b, h = ex / 2.0, ey / 2.0, ez / 2.0
        faces = {
            1: [(-a, -b, h), (a, -b, h), (a, b, h), (-a, b, h)],  # top (+z)
            2: [(a, -b, -h), (a, b, -h), (a, b, h), (a, -b, h)],  # +x
            3: [(-a, b, -h), (a, b, -h), (a, b, h), (-a, b, h)],  # +y
        }
        polys = {k: np.array([project_rel(*p) for p in v]) for k, v in faces.items()}
        allp = np.concatenate(list(polys.values()))
        lo = np.floor(allp.min(axis=0)).astype(int) - 1
        hi = np.ceil(allp.max(axis=0)).astype(int) + 1
        us = np.arange(lo[0], hi[0] + 1)
        vs = np.arange(lo[1], hi[1] + 1)
        gu, gv = np.meshgrid(us + 0.5, vs + 0.5)
        face_id = np.zeros(gu.shape, dtype=np.int8)
        for k, poly in polys.items():
            face_id[_inside_convex(poly, gu, gv)] = k
        # Borders: pixels whose 4-neighbour has another face id (silhouette included).
        pad = np.pad(face_id, 1)
        border = np.zeros(face_id.shape, dtype=bool)
        for dv, du in ((0, 1), (1, 0), (2, 1), (1, 2)):
            border |= pad[dv : dv + face_id.shape[0], du : du + face_id.shape[1]] != face_id
        border &= face_id > 0
        rows, cols = np.nonzero(face_id)
        base = np.asarray(colour, dtype=np.float64)
        shade = np.array([_FACE_SHADE[int(k)] for k in face_id[rows, cols]])
        rgb = base[None, :] * shade[:, None]
        rgb[border[rows, cols]] *= 0.55
        self.dv = rows + lo[1]
        self.du = cols + lo[0]
        self.rgb = np.clip(rgb, 0, 255)
        self.alpha = alpha

    def blit(self, img: np.ndarray, u: float, v: float) -> None:
        cu, cv = round(u), round(v)
        rr = self.dv + cv
        cc = self.du + cu
        ok = (rr >= 0) & (rr < img.shape[0]) & (cc >= 0) & (cc < img.shape[1])
        rr, cc = rr[ok], cc[ok]
        if self.alpha >= 1.0:
            img[rr, cc] = self.rgb[ok].astype(np.uint8)
        else:
            cur = img[rr, cc].astype(np.float64)
            img[rr, cc] = (cur * (1 - self.alpha) + self.rgb[ok] * self.alpha).astype(np.uint8)


def _inside_convex(poly: np.ndarray, gu: np.ndarray, gv: np.ndarray) -> np.ndarray:
    n = len(poly)
    pos = np.ones(gu.shape, dtype=bool)
    neg = np.ones(gu.shape, dtype=bool)
    for i in range(n):
        (u0, v0), (u1, v1) = poly[i], poly[(i + 1) % n]
        cross = (u1 - u0) * (gv - v0) - (v1 - v0) * (gu - u0)
        pos &= cross >= -1e-9
        neg &= cross <= 1e-9
    return pos | neg


def _disc(radius: float) -> tuple[np.ndarray, np.ndarray]:
    r = max(radius, 0.5)
    k = math.ceil(r)
    dv, du = np.mgrid[-k : k + 1, -k : k + 1]
    m = dv**2 + du**2 <= r * r + 0.25
    return dv[m], du[m]


def _stamp(img: np.ndarray, pu: np.ndarray, pv: np.ndarray, radius: float, colour) -> None:
    dv, du = _disc(radius)
    rr = (np.rint(pv)[:, None] + dv[None, :]).ravel().astype(np.intp)
    cc = (np.rint(pu)[:, None] + du[None, :]).ravel().astype(np.intp)
    ok = (rr >= 0) & (rr < img.shape[0]) & (cc >= 0) & (cc < img.shape[1])
    img[rr[ok], cc[ok]] = colour


def _line(img: np.ndarray, a, b, width: float, colour) -> None:
    (u0, v0), (u1, v1) = a, b
    n = max(2, math.ceil(math.hypot(u1 - u0, v1 - v0)) + 1)
    t = np.linspace(0.0, 1.0, n)
    _stamp(img, u0 + (u1 - u0) * t, v0 + (v1 - v0) * t, width / 2.0, colour)


class IsoRenderer:
    """Isometric renderer of one scenario's grid.

    ``frame(path, terminal, target, arm_points_cells)`` returns a new ``uint8`` array of
    shape ``(H, W, 3)``.
    """

    def __init__(
        self,
        bounds: tuple[Cell, Cell],
        obstacles: Sequence[Cell],
        unreachable: Sequence[Cell] = (),
        size: int = 512,
        include_origin: bool = False,
        boxes_cells: Sequence[tuple[Sequence[float], Sequence[float]]] = (),
    ):
        """``boxes_cells``: obstacles as axis-aligned boxes ``(lowest corner, highest corner)``
        in cell coordinates (see :func:`obstacle_boxes_cells`), drawn like the cubes."""
        lo = np.asarray(bounds[0], dtype=np.float64)
        hi = np.asarray(bounds[1], dtype=np.float64)
        self._lo, self._hi = lo, hi
        cos30 = math.cos(math.radians(30.0))
        corners = np.array(
            [
                [x, y, z]
                for x in (lo[0] - 0.5, hi[0] + 0.5)
                for y in (lo[1] - 0.5, hi[1] + 0.5)
                for z in (lo[2] - 0.5, hi[2] + 0.5)
            ]
        )
        if include_origin:
            corners = np.vstack([corners, [[0.0, 0.0, 0.0]]])

        def raw(p):
            return np.stack(
                [(p[..., 0] - p[..., 1]) * cos30, (p[..., 0] + p[..., 1]) * 0.5 - p[..., 2]],
                axis=-1,
            )

        pr = raw(corners)
        extent = pr.max(axis=0) - pr.min(axis=0)
        margin = 12
        self.scale = (size - 2 * margin) / float(max(extent))
        self.width = math.ceil(extent[0] * self.scale) + 2 * margin
        self.height = math.ceil(extent[1] * self.scale) + 2 * margin
        self._origin = -pr.min(axis=0) * self.scale + margin
        self._cos30 = cos30

        s = self.scale
        self._obstacle = _Sprite(self._project_rel, 1.0, OBSTACLE, alpha=0.9)
        self._unreachable = _Sprite(self._project_rel, 0.45, UNREACHABLE, alpha=0.9)
        self._target = _Sprite(self._project_rel, 0.7, TARGET)
        self._terminal = _Sprite(self._project_rel, 0.55, TERMINAL)
        self._path_width = max(2.0, 0.12 * s)
        self._arm_width = max(3.0, 0.16 * s)

        bg = np.empty((self.height, self.width, 3), dtype=np.uint8)
        bg[:] = BACKGROUND
        self._draw_floor(bg)
        items: list[tuple[Any, _Sprite]] = [(c, self._obstacle) for c in obstacles]
        items += [(c, self._unreachable) for c in unreachable]
        box_sprites: dict[tuple[float, ...], _Sprite] = {}
        for b_lo, b_hi in boxes_cells:
            b_lo = np.asarray(b_lo, dtype=np.float64)
            b_hi = np.asarray(b_hi, dtype=np.float64)
            edges = tuple(round(float(e), 9) for e in b_hi - b_lo)
            if edges not in box_sprites:
                box_sprites[edges] = _Sprite(self._project_rel, edges, OBSTACLE, alpha=0.9)
            items.append((tuple(float(v) for v in (b_lo + b_hi) / 2.0), box_sprites[edges]))
        items.sort(key=lambda it: (it[0][0] + it[0][1] + it[0][2], it[0][2]))
        for c, sprite in items:
            u, v = self.project(c)
            sprite.blit(bg, u, v)
        self._draw_box_front(bg)
        self.background = bg
        self._path_layer = bg.copy()
        self._path_drawn: list[Cell] = []

    # Projection -------------------------------------------------------------------------
    def _project_rel(self, x: float, y: float, z: float) -> tuple[float, float]:
        s = self.scale
        return ((x - y) * self._cos30 * s, ((x + y) * 0.5 - z) * s)

    def project(self, p) -> tuple[float, float]:
        """Pixel (u, v) of a point in cell coordinates."""
        du, dv = self._project_rel(float(p[0]), float(p[1]), float(p[2]))
        return du + self._origin[0], dv + self._origin[1]

    # Static scene -----------------------------------------------------------------------
    def _draw_floor(self, img: np.ndarray) -> None:
        lo, hi = self._lo, self._hi
        z = lo[2] - 0.5
        for x in np.arange(lo[0] - 0.5, hi[0] + 1.0):
            _line(
                img, self.project((x, lo[1] - 0.5, z)), self.project((x, hi[1] + 0.5, z)), 1, FLOOR
            )
        for y in np.arange(lo[1] - 0.5, hi[1] + 1.0):
            _line(
                img, self.project((lo[0] - 0.5, y, z)), self.project((hi[0] + 0.5, y, z)), 1, FLOOR
            )
        # The three back edges of the bounds box.
        x0, y0, z0 = lo - 0.5
        x1, y1, z1 = hi + 0.5
        for a, b in (
            ((x0, y0, z0), (x0, y0, z1)),
            ((x0, y0, z1), (x1, y0, z1)),
            ((x0, y0, z1), (x0, y1, z1)),
        ):
            _line(img, self.project(a), self.project(b), 1, BOX)
        for a, b in (((x1, y0, z0), (x1, y0, z1)), ((x0, y1, z0), (x0, y1, z1))):
            _line(img, self.project(a), self.project(b), 1, BOX)

    def _draw_box_front(self, img: np.ndarray) -> None:
        x0, y0, z0 = self._lo - 0.5
        x1, y1, z1 = self._hi + 0.5
        edges = (
            ((x1, y1, z0), (x1, y1, z1)),
            ((x1, y1, z1), (x0, y1, z1)),
            ((x1, y1, z1), (x1, y0, z1)),
            ((x1, y0, z0), (x1, y1, z0)),
            ((x0, y1, z0), (x1, y1, z0)),
        )
        for a, b in edges:
            _line(img, self.project(a), self.project(b), 1, BOX)

    # Frames -----------------------------------------------------------------------------
    def _update_path(self, path: Sequence[Cell]) -> None:
        n = len(self._path_drawn)
        if (
            n > len(path)
            or (n and tuple(path[n - 1]) != self._path_drawn[-1])
            or (n and tuple(path[0]) != self._path_drawn[0])
        ):
            self._path_layer = self.background.copy()
            self._path_drawn = []
            n = 0
        if len(path) == 0:
            return
        pts = [self.project(c) for c in path[max(n - 1, 0) :]]
        if len(pts) == 1:
            _stamp(
                self._path_layer,
                np.array([pts[0][0]]),
                np.array([pts[0][1]]),
                self._path_width,
                PATH,
            )
        for a, b in zip(pts[:-1], pts[1:]):
            _line(self._path_layer, a, b, self._path_width, PATH)
        self._path_drawn.extend(tuple(int(v) for v in c) for c in path[n:])

    def frame(
        self,
        path: Sequence[Cell],
        terminal: Cell,
        target: Cell,
        arm_points_cells: np.ndarray | None = None,
    ) -> np.ndarray:
        """One frame: background, path so far, target, terminal, and the arm if given."""
        self._update_path(path)
        img = self._path_layer.copy()
        self._target.blit(img, *self.project(target))
        self._terminal.blit(img, *self.project(terminal))
        if arm_points_cells is not None:
            pts = [self.project(p) for p in np.asarray(arm_points_cells, dtype=np.float64)]
            for a, b in zip(pts[:-1], pts[1:]):
                _line(img, a, b, self._arm_width, ARM)
            pu = np.array([p[0] for p in pts])
            pv = np.array([p[1] for p in pts])
            _stamp(img, pu, pv, self._arm_width * 0.75, ARM_JOINT)
        return img


def obstacle_boxes_cells(scenario: Any) -> list[tuple[np.ndarray, np.ndarray]]:
    """A scenario's ``obstacle_boxes_mm`` as ``(lowest corner, highest corner)`` pairs in
    cell coordinates (mm / ``cell_mm``; the centre of cell ``c`` is at ``c``)."""
    cell_mm = float(scenario.cell_mm)
    return [
        (
            np.asarray(b["min_mm"], dtype=np.float64) / cell_mm,
            np.asarray(b["max_mm"], dtype=np.float64) / cell_mm,
        )
        for b in scenario.obstacle_boxes_mm
    ]


class SceneRenderer:
    """Frames of one scenario: the :class:`IsoRenderer` scene, and with ``render_arm`` the
    arm's polyline in the first clear IK pose at the terminal's cell (none if no clear pose)."""

    def __init__(
        self,
        scenario: Any,
        unreachable: Sequence[Cell] = (),
        size: int = 512,
        render_arm: bool = False,
    ):
        self.scenario = scenario
        self.render_arm = render_arm
        self.iso = IsoRenderer(
            scenario.bounds,
            scenario.obstacles,
            unreachable,
            size=size,
            include_origin=render_arm,
            boxes_cells=obstacle_boxes_cells(scenario),
        )

    def frame(self, path: Sequence[Cell], terminal: Cell, target: Cell) -> np.ndarray:
        """One frame, ``uint8`` ``(H, W, 3)``."""
        arm = None
        if self.render_arm:
            from sixaxis_avoid import _arm, _core

            q = _arm.clear_pose(self.scenario, terminal)
            if q is not None:
                arm = _core.Arm.from_scenario(self.scenario).points_mm(q) / self.scenario.cell_mm
        return self.iso.frame(path, terminal, target, arm)


def has_display() -> bool:
    """Whether a window can be opened (Linux: DISPLAY or WAYLAND_DISPLAY is set)."""
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


class HumanWindow:
    """A Matplotlib window that shows frames; headless, it draws on Agg and shows nothing."""

    def __init__(self, title: str, fps: float):
        matplotlib = require("matplotlib", 'render_mode="human"')

        if not has_display():
            import importlib

            if "matplotlib.pyplot" in sys.modules:
                importlib.import_module("matplotlib.pyplot").switch_backend("Agg")
            else:
                matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        self._plt = plt
        self._interactive = matplotlib.get_backend().lower() not in (
            "agg",
            "pdf",
            "svg",
            "ps",
            "cairo",
            "template",
        )
        self._fps = fps
        self._fig, self._ax = plt.subplots(num=title)
        self._ax.set_axis_off()
        self._im = None
        self._title = title

    def show(self, frame: np.ndarray, caption: str = "") -> None:
        if self._im is None:
            self._im = self._ax.imshow(frame)
            self._fig.tight_layout()
        else:
            self._im.set_data(frame)
        self._ax.set_title(caption, fontsize=9)
        if self._interactive:
            self._plt.pause(1.0 / self._fps)
        else:
            self._fig.canvas.draw()

    def close(self) -> None:
        self._plt.close(self._fig)

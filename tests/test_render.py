"""rgb_array and human rendering (headless)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid
from sixaxis_avoid import render as R


def test_rgb_array_frames():
    env = gym.make("SixAxisAvoid-v0", render_mode="rgb_array")
    env.reset(seed=0)
    f0 = env.render()
    assert f0.dtype == np.uint8 and f0.ndim == 3 and f0.shape[2] == 3
    assert max(f0.shape[:2]) == 512
    terminal = np.all(f0 == np.array(R.TERMINAL, dtype=np.uint8), axis=-1).sum()
    target = np.all(f0 == np.array(R.TARGET, dtype=np.uint8), axis=-1).sum()
    assert terminal > 20 and target > 20
    for a in (5, 5, 3, 2):
        env.step(a)
    f1 = env.render()
    assert f1.shape == f0.shape
    assert np.all(f1 == np.array(R.PATH, dtype=np.uint8), axis=-1).sum() > 50  # the path so far
    env.reset()
    f2 = env.render()
    assert np.all(f2 == np.array(R.PATH, dtype=np.uint8), axis=-1).sum() < 50  # path cleared


def test_rgb_array_frames_follow_the_steps():
    # Frame time is a benchmark figure (~0.4 ms), not asserted here.
    env = gym.make("SixAxisAvoid-v0", render_mode="rgb_array")
    env.reset(seed=0)
    first = env.render()
    rng = np.random.default_rng(0)
    frames = []
    for a in rng.integers(0, 6, size=100):
        env.step(a)
        frames.append(env.render())
    assert all(f.shape == first.shape and f.dtype == np.uint8 for f in frames)
    assert any(not np.array_equal(f, first) for f in frames)


def test_render_arm_draws_the_arm_at_start():
    env = gym.make("SixAxisAvoid-v0", render_mode="rgb_array", render_arm=True)
    env.reset(seed=0)
    f = env.render()
    assert np.all(f == np.array(R.ARM, dtype=np.uint8), axis=-1).sum() > 100
    plain = gym.make("SixAxisAvoid-v0", render_mode="rgb_array")
    plain.reset(seed=0)
    assert np.all(plain.render() == np.array(R.ARM, dtype=np.uint8), axis=-1).sum() == 0


def test_human_mode_headless(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    env = gym.make("SixAxisAvoid-v0", render_mode="human")
    env.reset(seed=0)
    env.step(5)
    assert env.render() is None
    env.close()


def test_render_without_mode_warns():
    env = gym.make("SixAxisAvoid-v0").unwrapped
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


def test_render_arm_follows_the_terminal():
    env = gym.make("SixAxisAvoid-v0", render_mode="rgb_array", render_arm=True)
    env.reset(seed=0)
    f0 = env.render()
    env.step(5)  # to (0, -2, 3): a clear pose exists there
    f1 = env.render()
    arm = np.array(R.ARM, dtype=np.uint8)
    assert np.all(f1 == arm, axis=-1).sum() > 100
    assert not np.array_equal(np.all(f0 == arm, axis=-1), np.all(f1 == arm, axis=-1))


def _differing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.any(a != b, axis=-1)


def test_obstacle_boxes_are_drawn_in_cells():
    """A scenario's ``obstacle_boxes_mm`` become boxes of mm / cell_mm cells, drawn where
    the box projects and nowhere else."""
    s = sixaxis_avoid.Scenario("paper_simple").regrid(50)
    cubes = sixaxis_avoid.Scenario("paper_simple").obstacles
    boxes = R.obstacle_boxes_cells(s)
    assert len(boxes) == len(cubes) == 19
    assert all(np.allclose(hi - lo, 2.0) for lo, hi in boxes)  # 100 mm cubes in 50 mm cells
    centres = sorted(tuple(float(v) for v in (lo + hi) / 2) for lo, hi in boxes)
    assert centres == sorted(tuple(2.0 * v for v in c) for c in cubes)

    lo, hi = (-1.0, -1.0, -1.0), (2.0, 1.0, 3.0)
    empty = R.IsoRenderer(((-4, -4, -4), (4, 4, 4)), [], size=256)
    boxed = R.IsoRenderer(((-4, -4, -4), (4, 4, 4)), [], size=256, boxes_cells=[(lo, hi)])
    changed = _differing(empty.background, boxed.background)
    corners = np.array(
        [boxed.project((x, y, z)) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (-1, 3)]
    )
    rows, cols = np.nonzero(changed)
    assert rows.size > 0
    assert cols.min() >= corners[:, 0].min() - 2 and cols.max() <= corners[:, 0].max() + 2
    assert rows.min() >= corners[:, 1].min() - 2 and rows.max() <= corners[:, 1].max() + 2
    # The box's silhouette (a hexagon) covers most of its projected bounding rectangle.
    rect = (np.ptp(corners[:, 0]) + 1) * (np.ptp(corners[:, 1]) + 1)
    assert rows.size > 0.6 * rect
    # Drawn like a cube: the same as a unit cube's sprite for a unit box on a cell.
    cube = R.IsoRenderer(((-4, -4, -4), (4, 4, 4)), [(1, 0, 2)], size=256)
    unit = R.IsoRenderer(
        ((-4, -4, -4), (4, 4, 4)), [], size=256, boxes_cells=[((0.5, -0.5, 1.5), (1.5, 0.5, 2.5))]
    )
    np.testing.assert_array_equal(cube.background, unit.background)


def test_env_renders_the_boxes_of_a_physical_world():
    s = sixaxis_avoid.Scenario("paper_simple").regrid(50)
    free = s.replace(obstacle_boxes_mm=[])
    assert free.obstacle_boxes_mm == [] and len(s.obstacle_boxes_mm) == 19
    frames = []
    for scenario in (s, free):
        env = gym.make("SixAxisAvoid-v0", scenario=scenario, render_mode="rgb_array")
        env.reset(seed=0)
        frames.append(env.render())
        env.close()
    with_boxes, without = frames
    assert with_boxes.shape == without.shape
    changed = _differing(with_boxes, without)
    assert changed.sum() > 0.05 * changed.size  # 19 cubes of 100 mm fill a good part of the view
    # Obstacle pixels are the obstacles' grey-blue shades, darker than the empty scene there.
    assert with_boxes[changed].astype(float).mean() < without[changed].astype(float).mean() - 40
    # The terminal is drawn over the boxes, never hidden.
    terminal = np.array(R.TERMINAL, dtype=np.uint8)
    drawn = [np.all(f == terminal, axis=-1).sum() for f in (with_boxes, without)]
    assert drawn[0] == drawn[1] > 20

"""rgb_array and human rendering (headless)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid  # noqa: F401
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

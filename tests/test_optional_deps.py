"""Optional dependencies: a missing one raises DependencyNotInstalled naming the extra, and
Gymnasium's check_env passes, or on a plain install fails only with that actionable error.

A missing module is simulated with ``sys.modules[name] = None`` (then ``import name`` raises
ImportError), so these tests run on a machine that has everything installed.
"""

from __future__ import annotations

import importlib
import sys

import gymnasium as gym
import pytest
import sixaxis_avoid
from gymnasium.error import DependencyNotInstalled
from gymnasium.utils.env_checker import check_env


def hide(monkeypatch, *names: str) -> None:
    for name in names:
        for mod in [m for m in sys.modules if m == name or m.startswith(name + ".")]:
            monkeypatch.delitem(sys.modules, mod)
        monkeypatch.setitem(sys.modules, name, None)


def test_human_mode_without_matplotlib_names_the_render_extra(monkeypatch):
    hide(monkeypatch, "matplotlib")
    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[render\]") as e:
        gym.make(sixaxis_avoid.ENV_ID, render_mode="human")
    assert "matplotlib" in str(e.value) and 'render_mode="human"' in str(e.value)
    # rgb_array is NumPy only: it works without Matplotlib.
    env = gym.make(sixaxis_avoid.ENV_ID, render_mode="rgb_array")
    env.reset(seed=0)
    assert env.render().ndim == 3


def test_check_env_passes_with_the_render_extra():
    check_env(gym.make(sixaxis_avoid.ENV_ID).unwrapped)
    check_env(gym.make(sixaxis_avoid.GOAL_ENV_ID).unwrapped)


def test_check_env_on_a_plain_install_fails_only_with_the_extra_to_install(monkeypatch):
    hide(monkeypatch, "matplotlib")
    # check_env builds the env once per declared render mode; "human" needs Matplotlib.
    with pytest.raises(DependencyNotInstalled, match=r'pip install "sixaxis-avoid\[render\]"'):
        check_env(gym.make(sixaxis_avoid.ENV_ID).unwrapped)
    # Everything else passes.
    check_env(gym.make(sixaxis_avoid.ENV_ID).unwrapped, skip_render_check=True)


def test_sb3_module_without_stable_baselines3_names_the_sb3_extra(monkeypatch):
    hide(monkeypatch, "stable_baselines3")
    monkeypatch.delitem(sys.modules, "sixaxis_avoid.sb3", raising=False)
    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[sb3\]"):
        importlib.import_module("sixaxis_avoid.sb3")


def test_animation_without_imageio_names_the_video_extra(monkeypatch, tmp_path):
    hide(monkeypatch, "imageio")
    from sixaxis_avoid import animate

    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[video\]"):
        animate.write_frames([], tmp_path / "x.gif", fps=10)


def test_verification_without_mujoco_names_the_extra(monkeypatch):
    hide(monkeypatch, "mujoco")
    from sixaxis_avoid import verify

    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[mujoco\]"):
        verify.verify_plan(sixaxis_avoid.plan("paper_simple", seed=0))

"""Exception hierarchy, the core-error mapping, and clear errors for bad keywords and scenarios."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid as sa
from sixaxis_avoid import _core

VARIANT_TO_CLASS = {
    "InvalidScenario": sa.ScenarioError,
    "ScenarioParse": sa.ScenarioParseError,
    "ScenarioNotFound": sa.ScenarioNotFoundError,
    "InvalidArgument": sa.InvalidArgumentError,
    "QTableMismatch": sa.QTableMismatchError,
    "Io": sa.SixAxisIOError,
    "Panic": sa.InternalError,
}


@pytest.mark.parametrize(("variant", "cls"), sorted(VARIANT_TO_CLASS.items()))
def test_each_core_error_variant_maps_to_its_class(variant, cls):
    with pytest.raises(cls) as info:
        _core._raise_core_error(variant)
    e = info.value
    assert type(e) is cls
    # Bad input is a ValueError; a panic (a bug) is not, so `except ValueError` misses it.
    is_bug = cls is sa.InternalError
    assert isinstance(e, sa.SixAxisError) is not is_bug
    assert isinstance(e, ValueError) is not is_bug
    assert str(e)


def test_hierarchy_extra_bases():
    assert issubclass(sa.SixAxisError, ValueError)
    assert issubclass(sa.ScenarioParseError, sa.ScenarioError)
    assert issubclass(sa.ScenarioNotFoundError, sa.ScenarioError)
    assert issubclass(sa.ScenarioNotFoundError, LookupError)
    assert issubclass(sa.SixAxisIOError, OSError)
    assert issubclass(sa.InternalError, RuntimeError)
    assert not issubclass(sa.InternalError, ValueError)
    for cls in VARIANT_TO_CLASS.values():
        assert cls.__module__ == "sixaxis_avoid"


def test_io_error_carries_errno_and_filename():
    with pytest.raises(sa.SixAxisIOError) as info:
        sa.Scenario("/nonexistent/dir/scenario.json")
    assert info.value.errno == 2
    assert info.value.filename == "/nonexistent/dir/scenario.json"


def test_invalid_scenario_attributes(paper_simple):
    with pytest.raises(sa.ScenarioError) as info:
        paper_simple.replace(start=(0, 1, 0))
    assert info.value.field == "start"
    assert "[0, 1, 0]" in info.value.value
    assert "obstacle" in info.value.reason


def test_natural_triggers(paper_simple, tmp_path):
    with pytest.raises(sa.ScenarioNotFoundError, match="nope"):
        sa.Scenario("nope")
    with pytest.raises(sa.ScenarioParseError, match="bogus"):
        sa.Scenario.from_dict({**paper_simple.to_dict(), "bogus": 1})
    with pytest.raises(sa.InvalidArgumentError, match="episodes"):
        sa.train(paper_simple, episodes=0)
    with pytest.raises(sa.QTableMismatchError):
        sa.train(paper_simple, episodes=1, initial_q=np.zeros((3, 6)))
    with pytest.raises(sa.SixAxisIOError):
        sa.load_q(tmp_path / "missing.qtable", paper_simple)


# Bad keywords of the env: each raises a ValueError naming the keyword and the value.
BAD_KWARGS = [
    ({"obs_type": "pixels"}, "obs_type", "pixels"),
    ({"reward_scale": -1.0}, "reward_scale", "-1.0"),
    ({"reward_scale": math.nan}, "reward_scale", "nan"),
    ({"reward_scale": "big"}, "reward_scale", "big"),
    ({"render_mode": "ansi"}, "render_mode", "ansi"),
    ({"random_target": "yes"}, "random_target", "yes"),
    ({"arm_aware": 1}, "arm_aware", "1"),
    ({"assist": "on"}, "assist", "on"),
    ({"random_target": True, "obs_type": "index"}, "random_target", "True"),
    ({"scenario": 42}, "scenario", "42"),
]


@pytest.mark.parametrize(("kwargs", "name", "value"), BAD_KWARGS)
@pytest.mark.parametrize("mode", ["single", "vector"])
def test_bad_keyword_raises_clear_error(kwargs, name, value, mode):
    if mode == "vector" and name == "render_mode":
        kwargs = {"render_mode": "ansi"}
    with pytest.raises(ValueError, match=name) as info:
        if mode == "single":
            gym.make("SixAxisAvoid-v0", **kwargs)
        else:
            gym.make_vec(
                "SixAxisAvoid-v0", num_envs=2, vectorization_mode="vector_entry_point", **kwargs
            )
    assert isinstance(info.value, sa.InvalidArgumentError)
    assert value in str(info.value)


def test_bad_num_envs_and_max_steps():
    with pytest.raises(sa.InvalidArgumentError, match="num_envs"):
        gym.make_vec("SixAxisAvoid-v0", num_envs=0, vectorization_mode="vector_entry_point")
    with pytest.raises(sa.InvalidArgumentError, match="max_episode_steps"):
        gym.make_vec(
            "SixAxisAvoid-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            max_episode_steps=0,
        )


def _bad(paper_simple, **changes):
    d = paper_simple.to_dict()
    d.update(changes)
    return d


@pytest.mark.parametrize(
    ("make_dict", "cls", "words"),
    [
        (lambda s: _bad(s, colour="red"), sa.ScenarioParseError, ["colour"]),
        (
            lambda s: _bad(s, terminal_safe_distance=math.nan),
            sa.ScenarioError,
            ["terminal_safe_distance", "NaN"],
        ),
        (
            lambda s: _bad(s, arm_safe_distance=math.inf),
            sa.ScenarioError,
            ["arm_safe_distance", "inf"],
        ),
        (lambda s: _bad(s, start=[0, 1, 0]), sa.ScenarioError, ["start", "[0, 1, 0]", "obstacle"]),
        (lambda s: _bad(s, target=[0, 1, 1]), sa.ScenarioError, ["target", "[0, 1, 1]"]),
        (lambda s: _bad(s, target=[9, 9, 9]), sa.ScenarioError, ["target", "outside bounds"]),
        (
            lambda s: {**s.to_dict(), "rewards": {**s.rewards, "step_penalty": -5.0}},
            sa.ScenarioError,
            ["rewards.step_penalty", "-5"],
        ),
        (
            lambda s: {**s.to_dict(), "learning": {**s.learning, "gamma": math.nan}},
            sa.ScenarioError,
            ["learning.gamma", "NaN"],
        ),
    ],
)
@pytest.mark.parametrize("how", ["from_dict", "gym.make", "make_vec"])
def test_bad_scenario_raises_clear_error(paper_simple, make_dict, cls, words, how):
    d = make_dict(paper_simple)
    with pytest.raises(cls) as info:
        if how == "from_dict":
            sa.Scenario.from_dict(d)
        elif how == "gym.make":
            gym.make("SixAxisAvoid-v0", scenario=d)
        else:
            gym.make_vec("SixAxisAvoid-v0", num_envs=2, scenario=d)
    assert isinstance(info.value, ValueError)
    for w in words:
        assert w in str(info.value)


def test_nonexistent_scenario_name():
    with pytest.raises(sa.ScenarioNotFoundError) as info:
        gym.make("SixAxisAvoid-v0", scenario="no_such_scenario")
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, LookupError)
    assert "no_such_scenario" in str(info.value)
    assert "paper_simple" in str(info.value)  # lists the known names


def test_bad_action():
    env = gym.make("SixAxisAvoid-v0").unwrapped
    env.reset(seed=0)
    for a in (6, -1, "x", 2.5):
        with pytest.raises(sa.InvalidArgumentError, match="action"):
            env.step(a)
    venv = gym.make_vec("SixAxisAvoid-v0", num_envs=3)
    venv.reset(seed=0)
    with pytest.raises(sa.InvalidArgumentError, match="actions"):
        venv.step(np.array([0, 1, 6]))
    with pytest.raises(sa.InvalidArgumentError, match="actions"):
        venv.step(np.array([0.0, 1.0, 2.0]))
    with pytest.raises(sa.InvalidArgumentError, match="actions"):
        venv.step(np.array([0, 1]))


def test_arm_bad_joints():
    arm = sa.Arm()
    with pytest.raises(sa.InvalidArgumentError, match="joints_rad"):
        arm.fk([0.0] * 5)
    with pytest.raises(sa.InvalidArgumentError, match="joints_rad"):
        arm.fk([0.0, 0.0, 0.0, 0.0, 0.0, math.nan])

"""The single Gymnasium env: checkers, spaces, dynamics, determinism, goal-conditioned API."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid as sa
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

# Every registered variant and observation type (arm-aware ids are added when the build
# has a pose planner).
VARIANTS = [
    ("SixAxisAvoid-v0", {"obs_type": "vector"}),
    ("SixAxisAvoid-v0", {"obs_type": "vector", "random_target": True}),
    ("SixAxisAvoid-v0", {"obs_type": "index"}),
    ("SixAxisAvoid-v0", {"obs_type": "goal"}),
    ("SixAxisAvoid-v0", {"obs_type": "goal", "random_target": True}),
    ("SixAxisAvoid-v0", {"assist": False, "reward_scale": 1e-4}),
]
if hasattr(sa._core, "unreachable_cells"):
    VARIANTS += [
        ("SixAxisAvoidArm-v0", {"obs_type": "vector"}),
        ("SixAxisAvoidArm-v0", {"obs_type": "index"}),
        ("SixAxisAvoidArm-v0", {"obs_type": "goal", "random_target": True}),
    ]

ACTIONS = {(1, 0, 0): 0, (-1, 0, 0): 1, (0, 1, 0): 2, (0, -1, 0): 3, (0, 0, 1): 4, (0, 0, -1): 5}


def _ids(v):
    return v[0] + "-" + "-".join(f"{k}={val}" for k, val in v[1].items())


@pytest.mark.parametrize(("env_id", "kwargs"), VARIANTS, ids=[_ids(v) for v in VARIANTS])
def test_gymnasium_and_sb3_checkers(env_id, kwargs):
    env = gym.make(env_id, render_mode="rgb_array", **kwargs)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no checker warning either
        gym_check_env(env.unwrapped)  # render check included (also makes "human" headless)
    sb3_check_env(env.unwrapped, warn=True)
    env.close()


def test_registration_and_spaces(paper_simple):
    spec = gym.spec("SixAxisAvoid-v0")
    assert spec.max_episode_steps == paper_simple.max_steps_per_episode == 1000
    assert spec.vector_entry_point is not None
    env = gym.make("SixAxisAvoid-v0")
    assert isinstance(env, gym.wrappers.TimeLimit)
    assert env.action_space == gym.spaces.Discrete(6)
    assert env.observation_space.shape == (13,)
    assert env.observation_space.dtype == np.float32
    assert env.unwrapped.scenario == paper_simple
    idx = gym.make("SixAxisAvoid-v0", obs_type="index")
    assert idx.observation_space == gym.spaces.Discrete(7 * 9 * 8)


def test_shortest_path_reaches_target_with_paper_rewards(paper_simple):
    env = gym.make("SixAxisAvoid-v0")
    _, info = env.reset(seed=0)
    assert info["cell"] == (0, -2, 4)
    path = sa.shortest_path(paper_simple)
    assert path[0] == (0, -2, 4) and path[-1] == (0, 3, 0)
    r = paper_simple.rewards
    d_o = float(np.linalg.norm(np.subtract((0, 3, 0), (0, -2, 4))))
    for i, (a, b) in enumerate(zip(path[:-1], path[1:])):
        _, reward, terminated, truncated, info = env.step(ACTIONS[tuple(np.subtract(b, a))])
        d_t = float(np.linalg.norm(np.subtract((0, 3, 0), b)))
        last = i == len(path) - 2
        base = r["target_reward"] if last else -r["step_penalty"]
        assert reward == pytest.approx(base + r["distance_reward"] * (d_o - d_t))
        assert info["cell"] == b and not info["collided"]
        assert terminated == last and not truncated
    assert info["is_success"] and info["distance_to_target"] == 0.0


def test_collision_stays_and_detour_penalties(paper_simple):
    env = gym.make("SixAxisAvoid-v0", scenario=paper_simple).unwrapped
    env.reset(seed=0)
    r = paper_simple.rewards
    # Start (0,-2,4) is on the top layer (z max 5): +z twice -> second move hits the wall.
    env.step(4)
    *_, i1 = env.step(4)
    assert i1["collided"] and i1["cell"] == (0, -2, 5)
    *_, i2 = env.step(4)  # collides again: eq. 9 repeat penalty
    assert i2["collided"] and i2["detour_penalty"] == -r["repeat_collision_penalty"]
    *_, i3 = env.step(5)  # opposite of the colliding action: reverse penalty
    assert not i3["collided"] and i3["detour_penalty"] == -r["reverse_after_collision_penalty"]
    env_off = gym.make("SixAxisAvoid-v0", scenario=paper_simple, assist=False).unwrapped
    env_off.reset(seed=0)
    rewards = [env_off.step(a)[1] for a in (4, 4, 4, 5)]
    assert rewards == [
        -r["step_penalty"],
        -r["collision_penalty"],
        -r["collision_penalty"],
        -r["step_penalty"],
    ]


def test_observation_layout(paper_simple):
    env = gym.make("SixAxisAvoid-v0").unwrapped
    obs, _ = env.reset(seed=0)
    lo, hi = (np.array(b, dtype=np.float32) for b in paper_simple.bounds)
    norm = lambda c: 2 * (np.array(c, dtype=np.float32) - lo) / (hi - lo) - 1  # noqa: E731
    np.testing.assert_allclose(obs[0:3], norm((0, -2, 4)), atol=1e-6)
    np.testing.assert_allclose(obs[3:6], norm((0, 3, 0)), atol=1e-6)
    assert obs[12] == 0.0
    env.step(4)
    obs, *_ = env.step(4)  # into the wall at z = 5
    assert obs[12] == 1.0 and obs[6 + 4] == 1.0  # collided flag, +z blocked
    # Moving -y from (0,0,1)... the neighbour flags follow move collisions:
    core_flags = [1.0 if env.state_of(tuple(np.add(env.cell, d))) is None else 0.0 for d in ACTIONS]
    assert list(obs[6:12]) == core_flags  # at the top face only +z leaves the box


def _rollout(env, seed, actions):
    obs, info = env.reset(seed=seed)
    out = [(obs, 0.0, False, False, info)]
    for a in actions:
        out.append(env.step(a))
        if out[-1][2] or out[-1][3]:
            out.append(env.reset())
    return out


def _same(a, b):
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and np.array_equal(a, b)
    return a == b


@pytest.mark.parametrize("obs_type", ["vector", "index", "goal"])
def test_seeded_determinism(obs_type, near_target):
    kwargs = {"obs_type": obs_type, "scenario": near_target, "max_episode_steps": 12}
    if obs_type != "index":
        kwargs["random_target"] = True
    actions = np.random.default_rng(0).integers(0, 6, size=300)
    a = _rollout(gym.make("SixAxisAvoid-v0", **kwargs), 7, actions)
    b = _rollout(gym.make("SixAxisAvoid-v0", **kwargs), 7, actions)
    assert _same(a, b)
    if obs_type != "index":
        c = _rollout(gym.make("SixAxisAvoid-v0", **kwargs), 8, actions)
        assert not _same(a, c)


def test_random_target_draws_are_seeded_and_spread(paper_simple):
    env = gym.make("SixAxisAvoid-v0", random_target=True).unwrapped
    draws = []
    for _ in range(2):
        env.reset(seed=123)
        seq = [env.target_cell]
        for _ in range(30):
            env.reset()
            seq.append(env.target_cell)
        draws.append(seq)
    assert draws[0] == draws[1]
    assert len(set(draws[0])) > 10
    blocked = set(paper_simple.obstacles)
    assert not blocked & set(draws[0])
    assert paper_simple.start not in draws[0]


@pytest.mark.parametrize("random_target", [False, True])
def test_compute_reward_matches_step_rewards(near_target, random_target):
    env = gym.make(
        "SixAxisAvoid-v0", obs_type="goal", random_target=random_target, scenario=near_target
    ).unwrapped
    env.reset(seed=3)
    rng = np.random.default_rng(1)
    ach, des, infos, rewards = [], [], [], []
    for a in rng.integers(0, 6, size=400):
        nobs, reward, term, _, info = env.step(int(a))
        ach.append(nobs["achieved_goal"])
        des.append(nobs["desired_goal"])
        infos.append(info)
        rewards.append(reward)
        assert env.compute_reward(nobs["achieved_goal"], nobs["desired_goal"], info) == reward
        if term:
            env.reset()
    assert any(i["collided"] for i in infos)
    assert random_target or any(i["is_success"] for i in infos)
    batch = env.compute_reward(np.array(ach), np.array(des), np.array(infos, dtype=object))
    assert batch.shape == (400,)
    np.testing.assert_array_equal(batch, np.array(rewards))
    # Relabelled: the achieved goal as the desired one is a success unless it collided.
    relabel = env.compute_reward(np.array(ach), np.array(ach), infos)
    r = near_target.rewards
    collided = np.array([i["collided"] for i in infos])
    detour = np.array([i["detour_penalty"] for i in infos])
    # target reward + r_e * d_o (d_t = 0) + eq. 9's part
    assert np.all(relabel[~collided] - detour[~collided] >= r["target_reward"])
    assert np.all(relabel[collided] - detour[collided] < 0)


def test_reward_scale(paper_simple):
    a = gym.make("SixAxisAvoid-v0")
    b = gym.make("SixAxisAvoid-v0", reward_scale=1e-4)
    a.reset(seed=0)
    b.reset(seed=0)
    for act in [5, 5, 4, 4, 4, 2, 2]:
        ra, rb = a.step(act)[1], b.step(act)[1]
        assert rb == pytest.approx(ra * 1e-4, rel=1e-12)


def test_truncation_by_time_limit(near_target):
    env = sa.make(scenario=near_target)
    assert env.spec.max_episode_steps == 12
    env.reset(seed=0)
    for i in range(12):
        _, _, term, trunc, _ = env.step(4)  # +z: wall, never the target below
        assert not term
        assert trunc == (i == 11)


def test_scenario_keyword_forms(paper_simple, tmp_path):
    p = tmp_path / "s.json"
    p.write_text(paper_simple.to_json())
    for form in (None, "paper_simple", str(p), p, paper_simple.to_dict(), paper_simple):
        env = gym.make("SixAxisAvoid-v0", scenario=form)
        assert env.unwrapped.scenario == paper_simple
    env = gym.make("SixAxisAvoid-v0", scenario="paper_complex")
    assert env.unwrapped.scenario.name == "paper_complex"


def test_arm_aware_blocks_cells_no_clear_pose_reaches(paper_simple):
    unreachable = sa.unreachable_cells(paper_simple)
    blocked = set(paper_simple.obstacles) | set(unreachable)
    lo, hi = paper_simple.bounds
    # A free neighbour of an unreachable cell, and the action from it into that cell.
    u, n, action = next(
        (u, n, act)
        for u in unreachable
        for d, act in ACTIONS.items()
        for n in [tuple(int(v) for v in np.subtract(u, d))]
        if all(lo[k] <= n[k] <= hi[k] for k in range(3))
        and n not in blocked
        and n != paper_simple.start
    )
    scenario = paper_simple.replace(target=n)
    path = sa.shortest_path(scenario, extra_obstacles=unreachable)
    env = gym.make("SixAxisAvoidArm-v0", scenario=paper_simple).unwrapped
    plain = gym.make("SixAxisAvoid-v0", scenario=paper_simple).unwrapped
    assert env.arm_aware and set(env.blocked_cells) == blocked
    env.reset(seed=0)
    plain.reset(seed=0)
    for a, b in zip(path[:-1], path[1:]):
        act = ACTIONS[tuple(np.subtract(b, a))]
        assert not env.step(act)[4]["collided"]
        plain.step(act)
    assert env.cell == n
    *_, info = env.step(action)
    assert info["collided"] and env.cell == n  # no clear arm pose there: a collision
    *_, info = plain.step(action)
    assert not info["collided"] and plain.cell == u  # the terminal alone may go there

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
    ("SixAxisAvoidGoal-v0", {}),
    ("SixAxisAvoidGoal-v0", {"random_target": True}),
    ("SixAxisAvoid-v0", {"assist": False, "reward_scale": 1e-4}),
]
if hasattr(sa._core, "unreachable_cells"):
    VARIANTS += [
        ("SixAxisAvoidArm-v0", {"obs_type": "vector"}),
        ("SixAxisAvoidArm-v0", {"obs_type": "index"}),
        ("SixAxisAvoidGoal-v0", {"arm_aware": True, "random_target": True}),
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


@pytest.mark.parametrize(
    ("env_id", "obs_kw"),
    [
        (sa.ENV_ID, {"obs_type": "vector"}),
        (sa.ENV_ID, {"obs_type": "index"}),
        (sa.GOAL_ENV_ID, {}),
    ],
)
def test_seeded_determinism(env_id, obs_kw, near_target):
    kwargs = {**obs_kw, "scenario": near_target, "max_episode_steps": 12}
    index = obs_kw.get("obs_type") == "index"
    if not index:
        kwargs["random_target"] = True
    actions = np.random.default_rng(0).integers(0, 6, size=300)
    a = _rollout(gym.make(env_id, **kwargs), 7, actions)
    b = _rollout(gym.make(env_id, **kwargs), 7, actions)
    assert _same(a, b)
    if not index:
        c = _rollout(gym.make(env_id, **kwargs), 8, actions)
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
    env = gym.make(sa.GOAL_ENV_ID, random_target=random_target, scenario=near_target).unwrapped
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


def _goal_rollout(env, seed, steps):
    """Random actions: per step the goals, info and reward ``step`` returned."""
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    ach, des, infos, rewards = [], [], [], []
    for a in rng.integers(0, 6, size=steps):
        obs, reward, term, _, info = env.step(int(a))
        ach.append(obs["achieved_goal"])
        des.append(obs["desired_goal"])
        infos.append(info)
        rewards.append(reward)
        if term:
            env.reset()
    return np.array(ach), np.array(des), infos, np.array(rewards)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"random_target": True},
        {"random_target": True, "assist": False, "reward_scale": 1e-4},
        {"random_target": True, "assist": None, "reward_scale": 0.37},
        {"arm_aware": True, "random_target": True, "reward_scale": 3.0},
    ],
)
def test_compute_reward_is_the_step_reward_bit_for_bit(paper_simple, kwargs):
    """Random rollouts: the core's relabelled reward of a step's own goals is its reward,
    to the bit, one pair at a time and batched (flat and with two leading axes)."""
    env = gym.make(sa.GOAL_ENV_ID, scenario=paper_simple, **kwargs).unwrapped
    ach, des, infos, rewards = _goal_rollout(env, 5, 600)
    assert any(i["collided"] for i in infos)
    if kwargs.get("assist", True) is not False:  # eq. 9 on: some detour terms to carry over
        assert any(i["detour_penalty"] < 0 for i in infos)
    single = np.array([env.compute_reward(a, d, i) for a, d, i in zip(ach, des, infos)])
    assert isinstance(env.compute_reward(ach[0], des[0], infos[0]), float)
    batch = env.compute_reward(ach, des, infos)
    grid = env.compute_reward(
        ach.reshape(20, 30, 3),
        des.reshape(20, 30, 3),
        np.array(infos, dtype=object).reshape(20, 30),
    )
    for got in (single, batch, grid.reshape(-1)):
        assert got.dtype == np.float64
        np.testing.assert_array_equal(got.view(np.uint64), rewards.view(np.uint64))
    # The native vector env's compute_reward is the same function of the same model.
    venv = gym.make_vec(sa.GOAL_ENV_ID, num_envs=2, scenario=paper_simple, **kwargs)
    np.testing.assert_array_equal(venv.compute_reward(ach, des, infos), rewards)


def test_compute_reward_bad_shapes_name_the_argument(near_target):
    env = gym.make(sa.GOAL_ENV_ID, scenario=near_target).unwrapped
    obs, info = env.reset(seed=0)
    g = obs["achieved_goal"]
    cases = [
        ((np.zeros((4, 2)), np.zeros((4, 2)), info), "achieved_goal"),
        ((np.float32(0.5), g, info), "achieved_goal"),
        ((g, np.zeros((2, 3)), info), "desired_goal"),
        ((np.zeros((4, 3)), np.zeros((4, 3)), [info] * 3), "info"),
        ((g, g, 7), "info"),
        ((np.full(3, 2.0), g, info), "achieved_goal"),  # outside the goal space [-1, 1]
        ((g, np.full(3, np.nan), info), "desired_goal"),
        ((["a", "b", "c"], g, info), "achieved_goal"),
    ]
    for args, name in cases:
        with pytest.raises(sa.InvalidArgumentError, match=name) as e:
            env.compute_reward(*args)
        assert isinstance(e.value, ValueError)


def test_goal_env_is_its_own_id(paper_simple):
    from sixaxis_avoid.env import SixAxisAvoidEnv, SixAxisAvoidGoalEnv

    spec = gym.spec(sa.GOAL_ENV_ID)
    assert sa.GOAL_ENV_ID == "SixAxisAvoidGoal-v0"
    assert spec.max_episode_steps == paper_simple.max_steps_per_episode
    env = gym.make(sa.GOAL_ENV_ID)
    assert type(env.unwrapped) is SixAxisAvoidGoalEnv
    assert isinstance(env.observation_space, gym.spaces.Dict)
    assert set(env.observation_space) == {"observation", "achieved_goal", "desired_goal"}
    # The plain ids are plain: no compute_reward, and obs_type="goal" names the goal id.
    plain = gym.make(sa.ENV_ID).unwrapped
    assert type(plain) is SixAxisAvoidEnv and not hasattr(plain, "compute_reward")
    for env_id in (sa.ENV_ID, sa.ARM_ENV_ID):
        with pytest.raises(sa.InvalidArgumentError, match="SixAxisAvoidGoal-v0") as e:
            gym.make(env_id, obs_type="goal")
        assert isinstance(e.value, ValueError) and e.value.name == "obs_type"
        with pytest.raises(sa.InvalidArgumentError, match="SixAxisAvoidGoal-v0"):
            gym.make_vec(env_id, num_envs=2, obs_type="goal")
    with pytest.raises(TypeError, match="obs_type"):
        gym.make(sa.GOAL_ENV_ID, obs_type="vector")
    # The goal dict is cut out of the vector observation by the core's layout.
    obs, _ = env.reset(seed=0)
    vec = obs["observation"]
    np.testing.assert_array_equal(obs["achieved_goal"], vec[slice(*sa._core.VECTOR_OBS_TERMINAL)])
    np.testing.assert_array_equal(obs["desired_goal"], vec[slice(*sa._core.VECTOR_OBS_TARGET)])
    np.testing.assert_array_equal(
        env.unwrapped.goal_to_cell(obs["desired_goal"]), paper_simple.target
    )
    np.testing.assert_array_equal(
        env.unwrapped.goal_to_cell(np.stack([obs["achieved_goal"]] * 2)), [paper_simple.start] * 2
    )


def test_core_compute_reward_checks_its_arrays():
    core = sa._core.EnvCore()
    g = np.zeros((2, 3))
    ok = (g, g, np.zeros(2, dtype=bool), np.zeros(2))
    assert core.compute_reward(*ok).shape == (2,)
    bad = [
        ((np.zeros((2, 2)), g, ok[2], ok[3]), "achieved_goal"),
        ((g, np.zeros((3, 3)), ok[2], ok[3]), "desired_goal"),
        ((g, g.astype(np.float32), ok[2], ok[3]), "desired_goal"),
        ((g, g, np.zeros(3, dtype=bool), ok[3]), "collided"),
        ((g, g, ok[2], np.zeros(1)), "detour_penalty"),
        ((g, g, ok[2], np.array([0.0, np.inf])), "detour_penalty"),
    ]
    for args, name in bad:
        with pytest.raises(sa.InvalidArgumentError, match=name):
            core.compute_reward(*args)

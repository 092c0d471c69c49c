"""sixaxis_avoid.sb3.SixAxisVecEnv: step for step equal to SB3's DummyVecEnv, and trainable."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid
from sixaxis_avoid.sb3 import SixAxisVecEnv
from stable_baselines3 import A2C, PPO
from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor


def dummy(n: int, env_id: str = sixaxis_avoid.ENV_ID, **kw) -> DummyVecEnv:
    steps = kw.pop("max_episode_steps", None)
    return DummyVecEnv([lambda: gym.make(env_id, max_episode_steps=steps, **kw)] * n)


def assert_obs_equal(a, b):
    if isinstance(a, dict):
        assert set(a) == set(b)
        for k in a:
            np.testing.assert_array_equal(a[k], b[k])
    else:
        np.testing.assert_array_equal(a, b)
        assert np.asarray(a).dtype == np.asarray(b).dtype


def assert_infos_equal(ours, theirs):
    assert len(ours) == len(theirs)
    for a, b in zip(ours, theirs):
        assert set(a) == set(b), (sorted(a), sorted(b))
        for k in a:
            if k == "terminal_observation":
                assert_obs_equal(a[k], b[k])
            else:
                assert a[k] == b[k], (k, a[k], b[k])
                assert type(a[k]) is type(b[k]), (k, type(a[k]), type(b[k]))


def toward_target(venv: SixAxisVecEnv, rng: np.random.Generator) -> np.ndarray:
    """Mostly a step along an axis towards each env's target, else a random action: episodes
    end both ways (target reached, step cap)."""
    cells = np.array(venv.get_attr("cell"))
    targets = np.array(venv.get_attr("target_cell"))
    actions = rng.integers(0, 6, size=len(cells))
    for i, (c, t) in enumerate(zip(cells, targets)):
        axes = np.flatnonzero(c != t)
        if len(axes) and rng.random() < 0.3:
            ax = rng.choice(axes)
            actions[i] = 2 * ax + (0 if t[ax] > c[ax] else 1)
    return actions


@pytest.mark.parametrize(
    "kw",
    [
        {"obs_type": "vector", "random_target": True},
        {"obs_type": "index"},
        {"env_id": sixaxis_avoid.GOAL_ENV_ID, "random_target": True, "reward_scale": 1e-3},
        {"obs_type": "vector", "assist": False},
    ],
)
def test_step_for_step_equal_to_dummy_vec_env(near_target, kw):
    n, seed = 5, 7
    kw = {"scenario": near_target, "max_episode_steps": 12, **kw}
    ours = SixAxisVecEnv(n, seed=seed, **kw)
    theirs = dummy(n, **kw)
    theirs.seed(seed)
    assert ours.observation_space == theirs.observation_space
    assert ours.action_space == theirs.action_space
    assert_obs_equal(ours.reset(), theirs.reset())
    assert_infos_equal(ours.reset_infos, theirs.reset_infos)
    rng = np.random.default_rng(3)
    ended = {"terminated": 0, "truncated": 0}
    for _ in range(300):
        actions = toward_target(ours, rng)
        o1, r1, d1, i1 = ours.step(actions)
        o2, r2, d2, i2 = theirs.step(actions)
        assert_obs_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        assert r1.dtype == r2.dtype == np.float32
        np.testing.assert_array_equal(d1, d2)
        assert_infos_equal(i1, i2)
        assert_infos_equal(ours.reset_infos, theirs.reset_infos)
        for info in i1:
            if "terminal_observation" in info:
                ended["truncated" if info["TimeLimit.truncated"] else "terminated"] += 1
    assert ended["terminated"] >= 10 and ended["truncated"] >= 10, ended


def test_seed_semantics(near_target):
    kw = {"scenario": near_target, "random_target": True}
    a = SixAxisVecEnv(4, seed=3, **kw)
    b = SixAxisVecEnv(4, **kw)
    assert b.seed(3) == [3, 4, 5, 6]
    np.testing.assert_array_equal(a.reset(), b.reset())
    # Env i is seeded with seed + i: env 0 of seed 4 is env 1 of seed 3.
    c = SixAxisVecEnv(1, seed=4, **kw)
    a.seed(3)
    np.testing.assert_array_equal(c.reset()[0], a.reset()[1])
    # Targets differ between envs (random_target), so the seeds really differ.
    assert len({tuple(t) for t in a.get_attr("target_cell")}) > 1
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="seed"):
        a.seed("3")


def test_attributes_and_methods(paper_simple):
    env = SixAxisVecEnv(
        3, seed=0, env_id=sixaxis_avoid.GOAL_ENV_ID, scenario=paper_simple, reward_scale=1e-4
    )
    env.reset()
    assert env.get_attr("scenario") == [paper_simple] * 3
    assert env.get_attr("reward_scale", indices=[1]) == [1e-4]
    assert env.get_attr("cell") == [tuple(paper_simple.start)] * 3
    assert env.has_attr("target_cell") and not env.has_attr("no_such_thing")
    env.set_attr("my_flag", 5, indices=[0, 2])
    assert env.get_attr("my_flag", indices=[0, 2]) == [5, 5]
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="reward_scale"):
        env.set_attr("reward_scale", 1.0)
    obs, *_ = env.step(np.array([5, 0, 0]))
    moved = env.get_attr("cell")
    assert env.get_attr("elapsed_steps") == [1, 1, 1]
    assert env.get_attr("cell")[0] == tuple(np.add(paper_simple.start, (0, 0, -1)))
    ((o0, info0),) = env.env_method("reset", indices=0)
    assert env.get_attr("elapsed_steps") == [0, 1, 1]
    np.testing.assert_array_equal(o0["observation"], env.reset()["observation"][0])
    assert env.get_attr("elapsed_steps") == [0, 0, 0]
    assert info0["cell"] == tuple(paper_simple.start)
    # HER calls compute_reward through env_method; it equals the single env's.
    single = gym.make(sixaxis_avoid.GOAL_ENV_ID, scenario=paper_simple, reward_scale=1e-4)
    ag, dg = obs["achieved_goal"], obs["desired_goal"]
    infos = [{"collided": False}] * 3
    want = single.unwrapped.compute_reward(ag, dg, infos)
    (got,) = env.env_method("compute_reward", ag, dg, infos, indices=[0])
    np.testing.assert_array_equal(got, want)
    (cells,) = env.env_method("goal_to_cell", ag, indices=[1])
    assert [tuple(c) for c in cells.tolist()] == moved
    assert env.env_method("cell_of", 0, indices=[2]) == [single.unwrapped.cell_of(0)]
    assert env.get_attr("blocked_cells", indices=[0]) == [single.unwrapped.blocked_cells]
    assert env.get_attr("num_states", indices=[0]) == [single.unwrapped.num_states]
    assert env.env_is_wrapped(VecMonitor) == [False, False, False]
    with pytest.raises(AttributeError, match="no method 'fly'"):
        env.env_method("fly")


def test_rgb_array_render(near_target):
    env = SixAxisVecEnv(4, seed=0, scenario=near_target, render_mode="rgb_array", render_size=128)
    env.reset()
    env.step(np.array([5, 5, 0, 1]))
    frames = env.get_images()
    assert len(frames) == 4 and all(f.dtype == np.uint8 and f.ndim == 3 for f in frames)
    assert not np.array_equal(frames[0], frames[2])  # env 0 moved, env 2 collided/moved elsewhere
    tiled = env.render()
    assert tiled.shape[0] >= 2 * frames[0].shape[0] - 1
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="render_mode"):
        SixAxisVecEnv(2, render_mode="human")


def test_bad_arguments():
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="num_envs"):
        SixAxisVecEnv(0)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="obs_type"):
        SixAxisVecEnv(2, obs_type="pixels")
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="SixAxisAvoidGoal-v0"):
        SixAxisVecEnv(2, obs_type="goal")
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="env_id"):
        SixAxisVecEnv(2, env_id="CartPole-v1")
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="render_size"):
        SixAxisVecEnv(2, render_size=8)
    env = SixAxisVecEnv(2)
    env.reset()
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="actions"):
        env.step(np.array([0.5, 1.0]))
    with pytest.raises(sixaxis_avoid.SixAxisError, match="actions"):
        env.step(np.array([0, 6]))


@pytest.mark.parametrize("algo", [PPO, A2C])
def test_ppo_and_a2c_train_on_it(algo):
    venv = VecMonitor(SixAxisVecEnv(4, seed=0, reward_scale=1e-4, max_episode_steps=20))
    kw = {"n_steps": 32, "batch_size": 64, "n_epochs": 2} if algo is PPO else {"n_steps": 8}
    model = algo("MlpPolicy", venv, seed=0, device="cpu", policy_kwargs={"net_arch": [32]}, **kw)
    model.learn(total_timesteps=256)
    assert model.num_timesteps >= 256
    assert len(model.ep_info_buffer) >= 4  # episodes ended (step cap 20) and were counted
    obs = venv.reset()
    actions, _ = model.predict(obs, deterministic=True)
    assert actions.shape == (4,) and ((0 <= actions) & (actions < 6)).all()


def test_only_the_vector_envs_public_api_is_used():
    """sb3.py reaches no private attribute of the vector env (nor builds a hidden env)."""
    import ast
    import inspect

    import sixaxis_avoid.sb3 as sb3

    tree = ast.parse(inspect.getsource(sb3))
    private = {
        node.attr
        for node in ast.walk(tree)
        if isinstance(node, ast.Attribute)
        and isinstance(node.value, ast.Attribute)
        and node.value.attr == "venv"
        and node.attr.startswith("_")
    }
    assert private == set()
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    assert not names & {"SixAxisAvoidEnv", "SixAxisAvoidGoalEnv", "_core"}


def test_arm_aware_id(paper_simple):
    ours = SixAxisVecEnv(2, seed=1, env_id=sixaxis_avoid.ARM_ENV_ID, max_episode_steps=8)
    theirs = dummy(2, sixaxis_avoid.ARM_ENV_ID, max_episode_steps=8)
    theirs.seed(1)
    assert ours.get_attr("arm_aware") == [True, True]
    assert ours.get_attr("blocked_cells")[0] == theirs.get_attr("blocked_cells")[0]
    assert_obs_equal(ours.reset(), theirs.reset())
    for a in ([0, 1], [2, 3], [4, 5], [5, 5]):
        o1, r1, _, i1 = ours.step(np.array(a))
        o2, r2, _, i2 = theirs.step(np.array(a))
        assert_obs_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        assert_infos_equal(i1, i2)


def along_path(venv, rng: np.random.Generator, path) -> np.ndarray:
    """Mostly the next move of ``path`` (the BFS optimum from the start) where an env is on
    it, else :func:`toward_target`'s action: fixed-target episodes end at the target too."""
    actions = toward_target(venv, rng)
    index = {tuple(c): k for k, c in enumerate(path)}
    for i, cell in enumerate(venv.get_attr("cell")):
        k = index.get(tuple(cell))
        if k is not None and k + 1 < len(path) and rng.random() < 0.9:
            step = np.subtract(path[k + 1], cell)
            ax = int(np.flatnonzero(step)[0])
            actions[i] = 2 * ax + (0 if step[ax] > 0 else 1)
    return actions


@pytest.mark.parametrize(
    "suite_name, task_id, replan",
    [
        ("v2", "paper_simple", False),  # a fixed target
        ("v2", "goal-paper_simple", False),  # random targets, goal observations
        ("v2", "paper_simple-50mm", False),  # a re-gridded world (cell_mm)
        ("v2", "replan_clutter", True),  # an Algorithm 2 re-plan round's world
        ("v1", "gen-hard-0", False),  # suite v1's larger generated grid
    ],
)
def test_benchmark_envs_step_for_step_equal_to_dummy_vec_env(suite_name, task_id, replan):
    """The SB3 learners' native VecEnv (RunContext.make_vec_env) against the DummyVecEnv of
    RunContext.make_env envs they trained on before, on each kind of benchmark task: the
    same observations, rewards, dones and infos, and the same step counts, episodes and
    first success recorded for the run."""
    from sixaxis_avoid.benchmark import load_suite
    from sixaxis_avoid.benchmark.learners import RunContext

    task = load_suite(suite_name).task(task_id)
    world = task.scenario
    if replan:  # the world of a re-plan round: the task's scenario and one more obstacle
        path = sixaxis_avoid.shortest_path(world)
        world = world.replace(obstacles=[*map(list, world.obstacles), list(path[len(path) // 2])])
    path = sixaxis_avoid.shortest_path(world)
    kw = {"reward_scale": 1e-4, "assist": True, "max_episode_steps": 2 * len(path)}
    n, seed = 4, 11

    def ctx():
        return RunContext(task, seed, 10**6, {}, [], None, world if replan else None)

    c1, c2 = ctx(), ctx()
    ours = c1.make_vec_env(n, **kw)
    theirs = DummyVecEnv([lambda: c2.make_env(**kw)] * n)
    assert isinstance(ours.unwrapped, SixAxisVecEnv)
    ours.seed(seed)
    theirs.seed(seed)
    assert ours.observation_space == theirs.observation_space
    assert_obs_equal(ours.reset(), theirs.reset())
    assert_infos_equal(ours.unwrapped.reset_infos, theirs.reset_infos)
    rng = np.random.default_rng(5)
    ended = {"terminated": 0, "truncated": 0}
    for _ in range(400):
        actions = toward_target(ours, rng) if task.is_goal else along_path(ours, rng, path)
        o1, r1, d1, i1 = ours.step(actions)
        o2, r2, d2, i2 = theirs.step(actions)
        assert_obs_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        np.testing.assert_array_equal(d1, d2)
        assert_infos_equal(i1, i2)
        assert_infos_equal(ours.unwrapped.reset_infos, theirs.reset_infos)
        for info in i1:
            if "terminal_observation" in info:
                ended["truncated" if info["TimeLimit.truncated"] else "terminated"] += 1
    assert ended["truncated"] >= 10 and ended["terminated"] >= 1, ended
    assert c1.env_steps == c2.env_steps == 400 * n
    assert c1.episodes == c2.episodes == sum(ended.values())
    assert c1.first_success is not None
    assert {k: c1.first_success[k] for k in ("env_steps", "episode")} == {
        k: c2.first_success[k] for k in ("env_steps", "episode")
    }

"""The native (Rust-batched) vector env against N single envs and Gymnasium's SyncVectorEnv."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from sixaxis_avoid.vector import SixAxisAvoidVectorEnv

N = 6
CAP = 12


def _native(scenario, env_id="SixAxisAvoid-v0", **kw):
    return gym.make_vec(
        env_id,
        num_envs=N,
        vectorization_mode="vector_entry_point",
        scenario=scenario,
        max_episode_steps=CAP,
        **kw,
    )


def test_make_vec_gives_native_env(paper_simple):
    env = gym.make_vec("SixAxisAvoid-v0", num_envs=4)
    assert isinstance(env, SixAxisAvoidVectorEnv)
    assert isinstance(env, gym.vector.VectorEnv)
    assert env.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    assert env.max_episode_steps == 1000
    assert env.single_action_space == gym.spaces.Discrete(6)
    assert env.action_space == gym.spaces.MultiDiscrete([6] * 4)
    assert env.observation_space.shape == (4, 13)
    obs, info = env.reset(seed=0)
    assert obs.shape == (4, 13) and obs.dtype == np.float32
    assert obs in env.observation_space
    obs, rew, term, trunc, info = env.step(env.action_space.sample())
    assert rew.dtype == np.float64 and term.dtype == np.bool_ and trunc.dtype == np.bool_
    assert info["cell"].shape == (4, 3) and info["_cell"].all()


@pytest.mark.parametrize(
    ("env_id", "kw"),
    [
        ("SixAxisAvoid-v0", {"obs_type": "vector", "random_target": False}),
        ("SixAxisAvoid-v0", {"obs_type": "vector", "random_target": True}),
        ("SixAxisAvoid-v0", {"obs_type": "index", "random_target": False}),
        ("SixAxisAvoidGoal-v0", {"random_target": True}),
    ],
)
def test_native_matches_single_envs_step_for_step(near_target, env_id, kw):
    random_target = kw["random_target"]
    native = _native(near_target, env_id, **kw)
    singles = [
        gym.make(env_id, scenario=near_target, max_episode_steps=CAP, **kw) for _ in range(N)
    ]
    rng = np.random.default_rng(5)

    def stack(xs):
        if isinstance(xs[0], dict):
            return {k: np.stack([x[k] for x in xs]) for k in xs[0]}
        return np.array(xs)

    obs, info = native.reset(seed=11)
    ref = [e.reset(seed=11 + i) for i, e in enumerate(singles)]
    np.testing.assert_equal(obs, stack([r[0] for r in ref]))
    done = np.zeros(N, dtype=bool)
    n_term = n_trunc = 0
    for _ in range(200):
        actions = rng.integers(0, 6, size=N)
        obs, rew, term, trunc, info = native.step(actions)
        exp = []
        for i, e in enumerate(singles):
            if done[i]:  # next-step autoreset: reset instead of stepping
                o, inf = e.reset()
                exp.append((o, 0.0, False, False, inf))
            else:
                exp.append(e.step(int(actions[i])))
        np.testing.assert_equal(obs, stack([x[0] for x in exp]))
        np.testing.assert_array_equal(rew, [x[1] for x in exp])
        np.testing.assert_array_equal(term, [x[2] for x in exp])
        np.testing.assert_array_equal(trunc, [x[3] for x in exp])
        for key in ("collided", "distance_to_target", "is_success"):
            np.testing.assert_array_equal(info[key], [x[4][key] for x in exp])
        np.testing.assert_array_equal(info["cell"], [x[4]["cell"] for x in exp])
        done = term | trunc
        n_term += term.sum()
        n_trunc += trunc.sum()
    assert n_trunc > 0
    assert random_target or n_term > 0


def test_native_matches_sync_vector_env(near_target):
    native = _native(near_target, random_target=True)
    sync = gym.make_vec(
        "SixAxisAvoid-v0",
        num_envs=N,
        vectorization_mode="sync",
        scenario=near_target,
        max_episode_steps=CAP,
        random_target=True,
    )
    assert sync.metadata["autoreset_mode"] == native.metadata["autoreset_mode"]
    a, _ = native.reset(seed=3)
    b, _ = sync.reset(seed=3)
    np.testing.assert_array_equal(a, b)
    rng = np.random.default_rng(0)
    for _ in range(150):
        act = rng.integers(0, 6, size=N)
        x, y = native.step(act), sync.step(act)
        for k in range(4):
            np.testing.assert_array_equal(x[k], y[k])
        for key in ("collided", "distance_to_target", "is_success"):
            np.testing.assert_array_equal(x[4][key], y[4][key])
    # Reseeding reproduces the start of the run.
    a2, _ = native.reset(seed=3)
    np.testing.assert_array_equal(a, a2)


def test_copy_false_reuses_buffers(near_target):
    env = _native(near_target, copy=False)
    obs0, _ = env.reset(seed=0)
    obs1, rew1, *_ = env.step(np.zeros(N, dtype=np.int64))
    assert obs1 is obs0  # the same preallocated array, rewritten in place
    _, rew2, *_ = env.step(np.zeros(N, dtype=np.int64))
    assert rew2 is rew1
    env_copy = _native(near_target)
    o0, _ = env_copy.reset(seed=0)
    o1, *_ = env_copy.step(np.zeros(N, dtype=np.int64))
    assert o1 is not o0


def test_reset_mask(near_target):
    env = _native(near_target)
    env.reset(seed=0)
    before, *_ = env.step(np.full(N, 4))  # everyone moves +z
    mask = np.zeros(N, dtype=bool)
    mask[[0, 3]] = True
    obs, _ = env.reset(options={"reset_mask": mask})
    start = gym.make("SixAxisAvoid-v0", scenario=near_target).reset(seed=0)[0]
    np.testing.assert_array_equal(obs[mask], np.stack([start, start]))
    np.testing.assert_array_equal(obs[~mask], before[~mask])


def test_action_dtypes_accepted(near_target):
    """Every integer dtype (and a plain list) is the same action: the same step results."""
    results = []
    for actions in [np.full(N, 3, dtype=dt) for dt in (np.int8, np.uint8, np.int32, np.int64)]:
        env = _native(near_target)
        env.reset(seed=0)
        results.append(env.step(actions)[:4])
    env = _native(near_target)
    first, _ = env.reset(seed=0)
    results.append(env.step([3] * N)[:4])
    for obs, rew, term, trunc in results:
        np.testing.assert_array_equal(obs, results[0][0])
        np.testing.assert_array_equal(rew, results[0][1])
        np.testing.assert_array_equal(term, results[0][2])
        np.testing.assert_array_equal(trunc, results[0][3])
    assert not np.array_equal(results[0][0], first), "action 3 (-y) moved the terminal"


def test_native_vector_env_long_batch_stays_in_bounds():
    # Speed is measured by scripts/bench_env.py (docs/PERFORMANCE.md), not asserted here.
    env = gym.make_vec("SixAxisAvoid-v0", num_envs=256, copy=False)
    obs, _ = env.reset(seed=0)
    actions = np.random.default_rng(0).integers(0, 6, size=(50, 256))
    for a in actions:
        obs, rew, term, trunc, _ = env.step(a)
        assert obs.shape == (256, 13) and np.isfinite(rew).all()
        assert env.single_observation_space.contains(obs[0])
        assert not (term & trunc).any()


def test_arm_id_vector(paper_simple):
    """The arm-aware id's native vector env steps like its single env, action for action."""
    env = gym.make_vec("SixAxisAvoidArm-v0", num_envs=2)
    assert isinstance(env.unwrapped, SixAxisAvoidVectorEnv)
    obs, _ = env.reset(seed=0)
    singles = [gym.make("SixAxisAvoidArm-v0") for _ in range(2)]
    for i, single in enumerate(singles):
        o, _ = single.reset(seed=0)
        np.testing.assert_array_equal(obs[i], o)
    for actions in ([0, 1], [4, 5], [2, 3]):
        obs, rew, term, trunc, _ = env.step(np.array(actions))
        for i, single in enumerate(singles):
            o, r, te, tr, _ = single.step(actions[i])
            np.testing.assert_array_equal(obs[i], o)
            assert (rew[i], term[i], trunc[i]) == (r, te, tr)


def test_public_configuration_and_state(near_target):
    """What the SB3 VecEnv reads: configuration, per-env state and the single env's
    stateless methods, as public members equal to the single env's."""
    from sixaxis_avoid.vector import SixAxisAvoidGoalVectorEnv

    env = _native(near_target, "SixAxisAvoidGoal-v0", random_target=True, reward_scale=0.5)
    assert isinstance(env, SixAxisAvoidGoalVectorEnv)
    single = gym.make("SixAxisAvoidGoal-v0", scenario=near_target, random_target=True).unwrapped
    assert (env.reward_scale, env.random_target, env.arm_aware) == (0.5, True, False)
    assert env.num_states == single.num_states
    assert env.blocked_cells == single.blocked_cells and env.extra_obstacles == []
    obs, info = env.reset(seed=4)
    singles_obs = [
        gym.make("SixAxisAvoidGoal-v0", scenario=near_target, random_target=True).reset(seed=4 + i)[
            0
        ]
        for i in range(N)
    ]
    # current_targets: each env's own target (the desired goals), not the candidates.
    np.testing.assert_array_equal(env.goal_to_cell(obs["desired_goal"]), env.current_targets)
    np.testing.assert_array_equal(
        env.current_targets, [single.goal_to_cell(o["desired_goal"]) for o in singles_obs]
    )
    assert len({tuple(t) for t in env.current_targets.tolist()}) > 1
    np.testing.assert_array_equal(env.cells, info["cell"])
    assert env.elapsed_steps.tolist() == [0] * N
    env.step(np.zeros(N, dtype=np.int64))
    assert env.elapsed_steps.tolist() == [1] * N
    assert env.cell_of(0) == single.cell_of(0) and env.state_of(env.cell_of(7)) == 7
    # The candidates of random targets: the free cells other than the start.
    candidates = set(single._core.target_candidates)
    assert {tuple(t) for t in env.current_targets.tolist()} <= candidates
    assert tuple(near_target.start) not in candidates
    assert not candidates & set(single.blocked_cells)

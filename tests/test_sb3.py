"""A short Stable-Baselines3 run on the env completes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid  # noqa: F401
from stable_baselines3 import DQN


def test_dqn_2000_steps():
    env = gym.make("SixAxisAvoid-v0", reward_scale=1e-4)
    model = DQN(
        "MlpPolicy",
        env,
        learning_starts=200,
        train_freq=4,
        buffer_size=5000,
        seed=0,
        device="cpu",
        policy_kwargs={"net_arch": [64, 64]},
    )
    model.learn(total_timesteps=2000)
    obs, _ = env.reset(seed=0)
    action, _ = model.predict(obs, deterministic=True)
    assert 0 <= int(action) < 6
    assert np.isfinite(model.q_net(model.q_net.obs_to_tensor(obs)[0]).detach().numpy()).all()


@pytest.mark.parametrize("copy_info", [True, False])
def test_dqn_with_her_on_goal_obs(copy_info):
    from stable_baselines3 import HerReplayBuffer

    env = gym.make(
        "SixAxisAvoidGoal-v0",
        random_target=True,
        reward_scale=1e-4,
        max_episode_steps=50,
    )
    model = DQN(
        "MultiInputPolicy",
        env,
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs={
            "n_sampled_goal": 4,
            "goal_selection_strategy": "future",
            "copy_info_dict": copy_info,
        },
        learning_starts=100,
        buffer_size=2000,
        seed=0,
        device="cpu",
        policy_kwargs={"net_arch": [32]},
    )
    model.learn(total_timesteps=400)  # HER relabels through env.compute_reward
    assert model.replay_buffer.size() > 0
    # Relabelled goals get the reward of their goal: reaching it pays (r), any other move
    # costs (p outweighs eq. 10's progress term), whatever the episode's own target was.
    # (With copied infos a collision that stays on the relabelled goal cell is a collision.)
    batch = model.replay_buffer.sample(512)
    achieved = batch.next_observations["achieved_goal"].numpy()
    desired = batch.observations["desired_goal"].numpy()
    rewards = batch.rewards.numpy().ravel()
    reached = np.all(achieved == desired, axis=-1)
    assert reached.any() and not reached.all()
    assert (rewards[~reached] < 0).all()
    assert (rewards[reached] > 0).all() if not copy_info else (rewards[reached] > 0).any()

"""A short Stable-Baselines3 run on the env completes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
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

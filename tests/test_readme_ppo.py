"""The README's PPO example learns SixAxisAvoid-v0 to the target (slow: minutes of training).

Run with ``bash scripts/test_slow.sh`` (or ``python -m pytest -m slow``); scripts/test.sh
leaves it out.
"""

from __future__ import annotations

import pytest


@pytest.mark.slow
def test_readme_ppo_example_reaches_the_target_on_the_shortest_path():
    # --- the README example, verbatim ---
    import sixaxis_avoid
    from sixaxis_avoid.sb3 import SixAxisVecEnv
    from stable_baselines3 import PPO

    venv = SixAxisVecEnv(8, seed=0, reward_scale=1e-4, max_episode_steps=200)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=256,
        ent_coef=0.01,
        seed=0,
        learning_rate=lambda progress: 3e-4 * progress,  # decays to 0
        device="cpu",
    )
    model.learn(total_timesteps=200_000)

    env = sixaxis_avoid.make(reward_scale=1e-4, max_episode_steps=200)
    obs, info = env.reset(seed=0)
    done, moves = False, 0
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        done, moves = terminated or truncated, moves + 1
    print(f"target reached: {info['is_success']} in {moves} moves")
    # --- end of the example ---
    assert info["is_success"]
    # The shortest path of paper_simple has 9 moves (BFS).
    assert moves == len(sixaxis_avoid.shortest_path("paper_simple")) - 1 == 9

"""The JAX twin (sixaxis_avoid.jax) against the native vector env, step for step, on every
task of the benchmark's quick and v1 suites.

How the two are driven alike:

- Both get the same random actions. The native vector env resets an env at the step after
  its episode ended (next-step autoreset: action ignored, reward 0); the JAX env resets in
  the same step (gymnax). So each env's Rust steps are compacted by dropping those reset
  steps, and the JAX env steps the remaining actions: compared step ``j`` of env ``i`` is
  the ``j``-th Rust step of env ``i`` that moved the terminal.
- Targets: on the goal task (``random_target``) every reset draws a target. The Rust
  env's draws (``current_targets`` after each reset) are fed to the JAX env through
  ``EnvParams.reset_target``, per step, so its autoreset starts the same episode.
- Compared: the cell after the move, the collision flag, the reward (the Rust float64
  rounded to float32 against the JAX float32, exactly), termination, truncation, and the
  observation (after an episode's last step the JAX env returns the new episode's first
  observation, which the Rust env returns at its reset step).

The envs are configured as the benchmark's deep learners use them (reward_scale 1e-4,
assist on, max_episode_steps 200: ``sixaxis_avoid.benchmark.learners.ENV_DEFAULTS``),
goal tasks with ``random_target=True`` (``Context.make_env``), plus other keyword values
on paper_simple.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from sixaxis_avoid import _core
from sixaxis_avoid.benchmark.learners import ENV_DEFAULTS
from sixaxis_avoid.benchmark.tasks import load_suite
from sixaxis_avoid.jax import make
from sixaxis_avoid.jax.env import params_of
from sixaxis_avoid.vector import SixAxisAvoidVectorEnv

N_ENVS = 128
RUST_STEPS = 900
MIN_COMPARED = 100_000


def suite_tasks():
    seen, out = set(), []
    for name in ("quick", "v1"):
        for t in load_suite(name).tasks:
            if t.id not in seen:
                seen.add(t.id)
                out.append(t)
    return out


TASKS = suite_tasks()


def rust_rollout(scenario, n, steps, seed, **kw):
    env = SixAxisAvoidVectorEnv(num_envs=n, scenario=scenario, copy=False, **kw)
    obs0, _ = env.reset(seed=seed)
    rec = {"obs0": obs0.copy(), "target0": env.current_targets.copy()}
    actions = np.random.default_rng(seed).integers(0, 6, size=(steps, n))
    keys = ("obs", "reward", "terminated", "truncated", "collided", "cell", "target")
    out = {k: [] for k in keys}
    for a in actions:
        obs, r, te, tr, info = env.step(a)
        out["obs"].append(obs.copy())
        out["reward"].append(r.copy())
        out["terminated"].append(te.copy())
        out["truncated"].append(tr.copy())
        out["collided"].append(info["collided"].copy())
        out["cell"].append(info["cell"].copy())
        out["target"].append(env.current_targets.copy())
    rec.update({k: np.stack(v) for k, v in out.items()})
    rec["actions"] = actions
    return rec


def compact(rec, target_index):
    """Per env: the Rust steps that moved (not autoreset steps), padded to one length, with
    the target each episode's reset drew."""
    n = rec["actions"].shape[1]
    done = rec["terminated"] | rec["truncated"]
    is_reset = np.zeros_like(done)
    is_reset[1:] = done[:-1]
    rows = [np.flatnonzero(~is_reset[:, i]) for i in range(n)]
    m = max(len(r) for r in rows)
    idx = np.zeros((n, m), np.int64)
    valid = np.zeros((n, m), bool)
    reset_target = np.full((n, m), -1, np.int32)
    for i, r in enumerate(rows):
        idx[i, : len(r)] = r
        valid[i, : len(r)] = True
        # Targets of episodes 1, 2, ...: drawn at the Rust reset steps.
        later = [target_index[tuple(c)] for c in rec["target"][is_reset[:, i], i]]
        ep = np.cumsum(done[r, i])  # episodes ended up to and including each step
        for j in np.flatnonzero(done[r, i]):
            k = ep[j] - 1  # this reset starts episode k + 1
            if k < len(later):
                reset_target[i, j] = later[k]
    t0 = np.array([target_index[tuple(c)] for c in rec["target0"]], np.int32)
    actions = np.where(valid, rec["actions"][idx, np.arange(n)[:, None]], 0)
    return idx, valid, reset_target, t0, actions.astype(np.int32)


@partial(jax.jit, static_argnums=0)
def jax_rollout(env, params, t0, actions, reset_target, key):
    def one(t, acts, rts, k):
        obs0, st = env.reset_env(k, params._replace(reset_target=t))

        def body(st, x):
            a, rt, kk = x
            obs, st, r, d, info = env.step(kk, st, a, params._replace(reset_target=rt))
            return st, (obs, r, d, info)

        keys = jax.random.split(k, acts.shape[0])
        _, out = jax.lax.scan(body, st, (acts, rts, keys))
        return obs0, out

    keys = jax.random.split(key, t0.shape[0])
    return jax.vmap(one)(t0, actions, reset_target, keys)


def compare(scenario, seed=0, **kw):
    """Step both envs; assert equality; return counts."""
    env, params = make(scenario, **kw)
    cells = np.asarray(params.target_cells)
    target_index = {tuple(int(v) for v in c): i for i, c in enumerate(cells)}
    rec = rust_rollout(scenario, N_ENVS, RUST_STEPS, seed, **kw)
    idx, valid, reset_target, t0, actions = compact(rec, target_index)
    obs0, (obs, reward, done, info) = jax_rollout(
        env,
        params,
        jnp.asarray(t0),
        jnp.asarray(actions),
        jnp.asarray(reset_target),
        jax.random.key(seed),
    )
    np.testing.assert_array_equal(np.asarray(obs0), rec["obs0"])
    cols = np.arange(N_ENVS)[:, None]

    def rust(key):
        return rec[key][idx, cols][valid]

    np.testing.assert_array_equal(np.asarray(info["cell"])[valid], rust("cell"))
    np.testing.assert_array_equal(np.asarray(info["collided"])[valid], rust("collided"))
    np.testing.assert_array_equal(np.asarray(reward)[valid], rust("reward").astype(np.float32))
    np.testing.assert_array_equal(np.asarray(info["terminated"])[valid], rust("terminated"))
    np.testing.assert_array_equal(np.asarray(info["truncated"])[valid], rust("truncated"))
    done = np.asarray(done)
    np.testing.assert_array_equal(done[valid], rust("terminated") | rust("truncated"))
    # Observations: after a move, the Rust step's; after an episode's last move, the Rust
    # reset step's (the next one), where there is one.
    nxt = np.minimum(idx + done, RUST_STEPS - 1)
    has = valid & (idx + done < RUST_STEPS)
    np.testing.assert_array_equal(np.asarray(obs)[has], rec["obs"][nxt, cols][has])
    return {
        "compared": int(valid.sum()),
        "obs_compared": int(has.sum()),
        "terminated": int(rust("terminated").sum()),
        "truncated": int(rust("truncated").sum()),
        "collided": int(rust("collided").sum()),
        "targets": len({int(t) for t in reset_target[reset_target >= 0]} | set(t0.tolist())),
    }


LEARNER_KW = {k: ENV_DEFAULTS[k] for k in ("reward_scale", "assist", "max_episode_steps")}


@pytest.mark.parametrize("task", TASKS, ids=[t.id for t in TASKS])
def test_jax_twin_matches_the_native_vector_env(task):
    kw = dict(LEARNER_KW, random_target=task.is_goal)
    counts = compare(task.scenario, **kw)
    assert counts["compared"] >= MIN_COMPARED, counts
    assert counts["obs_compared"] >= MIN_COMPARED, counts
    for what in ("terminated", "truncated", "collided"):
        assert counts[what] > 0, counts
    if task.is_goal:
        # Many targets, fed from the Rust env's draws.
        assert counts["targets"] > 100, counts


def test_suites_cover_every_task_kind():
    assert {t.kind for t in TASKS} == {"scenario", "generated", "goal"}
    assert len(TASKS) == 7


@pytest.mark.parametrize(
    "kw",
    [
        {"assist": False, "reward_scale": 1.0, "arm_aware": True, "max_episode_steps": 50},
        {"random_target": True, "assist": None, "max_episode_steps": 30},
    ],
    ids=["arm_aware-no-assist", "goal-scenario-assist"],
)
def test_jax_twin_matches_with_other_keywords(kw):
    counts = compare("paper_simple", seed=3, **kw)
    assert counts["compared"] >= MIN_COMPARED, counts
    # Short episodes: the random policy reaches the target now and then.
    assert counts["terminated"] > 0 and counts["truncated"] > 0, counts


def test_rust_rewards_are_what_the_tables_hold():
    """The float64 rewards of the Rust env take exactly the table's float32 values."""
    t = _core.env_tables("paper_simple", reward_scale=1e-4)
    params = params_of(t)
    rec = rust_rollout("paper_simple", 4, 300, 1, reward_scale=1e-4)
    got = set(rec["reward"].astype(np.float32).ravel().tolist()) - {0.0}
    assert got <= set(np.asarray(params.rewards).ravel().tolist())

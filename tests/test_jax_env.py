"""The JAX twin's interface: env_tables' arrays, gymnax-style reset/step, autoreset,
truncation, chosen reset targets, keyword errors, and the missing-extra error."""

from __future__ import annotations

import importlib
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from gymnasium.error import DependencyNotInstalled
from sixaxis_avoid import InvalidArgumentError, Scenario, _core
from sixaxis_avoid.jax import make


def test_env_tables_shapes_and_layout():
    t = _core.env_tables("paper_simple", random_target=True)
    s, n = t["next_state"].shape[0], t["target_cells"].shape[0]
    assert s == 7 * 9 * 8 and t["next_state"].shape == (s, 6)
    assert t["rewards"].shape == t["terminates"].shape == (n, s, 4)
    assert t["rewards"].dtype == np.float32 and t["next_state"].dtype == np.int32
    assert t["reward_case"].shape == (7, 6, 2) and t["next_memory"].shape == (6, 2)
    assert int(t["no_memory"]) == 6 and bool(t["random_target"])
    start = int(t["start_state"])
    assert tuple(t["cells"][start]) == tuple(Scenario("paper_simple").start)
    # Each observation part lives in its own columns (terminal 0..3, target 3..6,
    # flags 6..12, collided 12).
    assert not t["obs_state"][:, 3:6].any() and not t["obs_state"][:, 12].any()
    assert not t["obs_target"][:, [*range(3), *range(6, 13)]].any()
    assert t["obs_memory"][:6, 12].all() and not t["obs_memory"][6].any()
    # A collision keeps the terminal in place, and eq. 9's memory is the colliding action.
    rows = np.arange(s)[:, None]
    assert (t["collided"] == (t["next_state"] == rows)).all()
    assert (t["next_memory"][:, 0] == 6).all() and (t["next_memory"][:, 1] == range(6)).all()
    fixed = _core.env_tables("paper_simple", max_episode_steps=17)
    assert fixed["rewards"].shape == (1, s, 4) and int(fixed["max_episode_steps"]) == 17


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"reward_scale": -1.0}, "reward_scale"),
        ({"max_episode_steps": 0}, "max_episode_steps"),
        ({"random_target": "yes"}, "random_target"),
        ({"assist": 1}, "assist"),
    ],
)
def test_bad_keywords_name_the_keyword(kw, name):
    with pytest.raises(InvalidArgumentError, match=name):
        make("paper_simple", **kw)


def test_unknown_keyword_is_a_type_error():
    with pytest.raises(TypeError, match="obs_type"):
        _core.env_tables("paper_simple", obs_type="vector")


def test_reset_step_and_same_step_autoreset():
    env, params = make("paper_simple", max_episode_steps=3)
    obs0, st = env.reset(jax.random.key(0), params)
    assert obs0.shape == (13,) and obs0.dtype == jnp.float32
    assert env.observation_space(params).shape == (13,)
    assert env.action_space(params).n == env.num_actions == 6
    step = jax.jit(env.step)
    # +x from the start (0, -2, 4) stays inside and free: no collision, no reward case 3.
    for k in range(3):
        obs, st, reward, done, info = step(jax.random.key(k), st, 0, params)
        assert reward.dtype == jnp.float32 and not bool(info["collided"])
        assert bool(done) == (k == 2)
    assert bool(info["truncated"]) and not bool(info["terminated"])
    # Truncated: the returned state is a new episode at the start, its obs the first one.
    assert int(st.time) == 0 and int(st.state) == int(params.start_state)
    np.testing.assert_array_equal(obs, obs0)
    assert tuple(np.asarray(info["cell"])) == (3, -2, 4)


def test_shortest_path_terminates_with_discount_zero():
    import sixaxis_avoid as sa

    env, params = make("paper_simple")
    path = sa.shortest_path(sa.Scenario("paper_simple"))
    moves = {(1, 0, 0): 0, (-1, 0, 0): 1, (0, 1, 0): 2, (0, -1, 0): 3, (0, 0, 1): 4, (0, 0, -1): 5}
    _, st = env.reset(jax.random.key(0), params)
    for a, b in zip(path, path[1:]):
        action = moves[tuple(int(y) - int(x) for x, y in zip(a, b))]
        _, st, reward, done, info = env.step_env(jax.random.key(1), st, action, params)
    assert bool(done) and bool(info["terminated"]) and float(info["discount"]) == 0.0
    assert float(reward) > 0


def test_random_targets_are_drawn_or_chosen():
    env, params = make("paper_simple", random_target=True)
    keys = jax.random.split(jax.random.key(0), 256)
    _, states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    drawn = np.asarray(states.target)
    assert len(set(drawn.tolist())) > 100 and drawn.max() < env.num_targets
    _, st = env.reset(keys[0], params._replace(reset_target=jnp.int32(7)))
    obs = env.get_obs(st, params)
    np.testing.assert_array_equal(np.asarray(obs[3:6]), np.asarray(params.obs_target[7, 3:6]))


def test_missing_jax_names_the_jax_extra(monkeypatch):
    for mod in [m for m in sys.modules if m == "jax" or m.startswith("jax.")]:
        monkeypatch.delitem(sys.modules, mod)
    for mod in [m for m in sys.modules if m.startswith("sixaxis_avoid.jax")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.setitem(sys.modules, "jax", None)
    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[jax\]"):
        importlib.import_module("sixaxis_avoid.jax")

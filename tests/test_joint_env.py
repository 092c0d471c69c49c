"""SixAxisAvoidJoint-v0 and SixAxisAvoidJointGoal-v0: the checkers, determinism, the
observation's FK, the safety invariant over long rollouts, refusals, keyword errors, HER
rewards, the vector envs and the rollout as a plan (docs/JOINT.md)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid
from gymnasium.utils.env_checker import check_env
from sixaxis_avoid import _core
from sixaxis_avoid.joint import rollout_plan

IDS = (sixaxis_avoid.JOINT_ENV_ID, sixaxis_avoid.JOINT_GOAL_ENV_ID)


def drifting_actions(rng: np.random.Generator, n: int, steps: int, hold: int = 40) -> np.ndarray:
    """``(steps, n, 6)`` actions around a drift held ``hold`` steps, so that rollouts leave
    beta_0 and meet obstacles and limits (a pure random walk stays near the start)."""
    drift = rng.uniform(-1, 1, (steps // hold + 1, n, 6)).repeat(hold, axis=0)[:steps]
    return np.clip(drift + rng.uniform(-0.3, 0.3, (steps, n, 6)), -1, 1)


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_and_sb3_checkers(env_id):
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    check_env(gym.make(env_id).unwrapped, skip_render_check=True)
    sb3_check_env(gym.make(env_id).unwrapped, warn=True)


def test_seeded_determinism_and_vector_equals_single():
    rng = np.random.default_rng(0)
    acts = drifting_actions(rng, 3, 120)
    runs = []
    for _ in range(2):
        env = gym.make(sixaxis_avoid.JOINT_ENV_ID, max_episode_steps=50)
        obs, _ = env.reset(seed=7)
        trace = [obs]
        for a in acts[:, 0]:
            obs, r, te, tr, info = env.step(a.astype(np.float32))
            trace.append(np.append(obs, [r, te, tr, info["clearance"]]))
            if te or tr:
                obs, _ = env.reset()
                trace.append(obs)
        runs.append(np.concatenate(trace))
    np.testing.assert_array_equal(runs[0], runs[1])
    # The native vector env: three lanes are three single envs with next-step autoreset.
    venv = gym.make_vec(sixaxis_avoid.JOINT_ENV_ID, num_envs=3, max_episode_steps=50)
    vobs, _ = venv.reset(seed=7)
    singles = [gym.make(sixaxis_avoid.JOINT_ENV_ID, max_episode_steps=50) for _ in range(3)]
    sobs = [e.reset(seed=7)[0] for e in singles]
    done = [False] * 3
    for a in acts:
        vobs, vr, vte, vtr, vinfo = venv.step(a)
        for i, e in enumerate(singles):
            if done[i]:
                sobs[i], _ = e.reset()
                done[i] = False
                assert (vr[i], vte[i], vtr[i]) == (0.0, False, False)
            else:
                sobs[i], r, te, tr, info = e.step(a[i])
                assert (r, te, tr) == (vr[i], vte[i], vtr[i])
                assert info["refused"] == vinfo["refused"][i]
                done[i] = te or tr
            np.testing.assert_array_equal(sobs[i], vobs[i])


def test_observation_terminal_is_the_cores_fk():
    env = gym.make(sixaxis_avoid.JOINT_ENV_ID)
    obs, _ = env.reset(seed=0)
    u = env.unwrapped
    lay = u.obs_layout
    arm = _core.Arm.from_scenario(u.scenario)
    rng = np.random.default_rng(1)
    for a in drifting_actions(rng, 1, 200)[:, 0]:
        obs, *_ = env.step(a)
        fk = np.asarray(arm.fk(u.joints)[0])
        np.testing.assert_allclose(obs[slice(*lay["terminal"])], fk / u.reach_mm, atol=1e-6)
        np.testing.assert_array_equal(u.terminal_mm, fk)
        q = u.joints
        np.testing.assert_allclose(obs[slice(*lay["sin"])], np.sin(q), atol=1e-6)
        np.testing.assert_allclose(obs[slice(*lay["cos"])], np.cos(q), atol=1e-6)
    np.testing.assert_allclose(
        obs[slice(*lay["target"])], np.asarray(u.target_mm) / u.reach_mm, atol=1e-7
    )
    # The target is the target cell's centre.
    np.testing.assert_array_equal(u.target_mm, np.array(u.scenario.target) * u.scenario.cell_mm)


@pytest.mark.parametrize("world", ["paper_simple", "generated:3"])
def test_accepted_steps_never_enter_the_safe_distance(world):
    """20 000 steps (4 lanes x 5 000) of drifting random actions: every accepted step keeps,
    at an interpolation twice as fine as the env's, every link capsule's exact gap (the
    core's clearance) >= (1 - substep_fraction / 2) x the safe distance (docs/JOINT.md), the
    poses the env checked (every second one) > the safe distance, and the joint limits."""
    s = sixaxis_avoid.generate_scenario(3) if world.startswith("generated") else world
    n, steps = 4, 5000
    venv = gym.make_vec(sixaxis_avoid.JOINT_ENV_ID, num_envs=n, scenario=s, max_episode_steps=400)
    core = venv.unwrapped._core
    safe = core.safe_distance_mm
    floor = (1 - 0.5 / 2) * safe
    lo, hi = np.array(core.joint_limits_rad).T
    venv.reset(seed=0)
    joints = venv.unwrapped.joints
    was_done = np.zeros(n, dtype=bool)
    accepted = refused = 0
    acts = drifting_actions(np.random.default_rng(hash(world) % 2**32), n, steps)
    smallest = np.inf
    for a in acts:
        _, _, te, tr, info = venv.step(a)
        now = venv.unwrapped.joints
        for i in range(n):
            if was_done[i]:
                continue
            if info["refused"][i]:
                refused += 1
                np.testing.assert_array_equal(now[i], joints[i])
                continue
            accepted += 1
            q0, q1 = joints[i], now[i]
            assert np.all(q1 >= lo) and np.all(q1 <= hi)
            m = 2 * core.substeps(q0.tolist(), q1.tolist())
            for k in range(1, m + 1):
                gap = min(core.link_gaps_mm((q0 + (q1 - q0) * k / m).tolist()))
                smallest = min(smallest, gap)
                assert gap >= floor, (world, k, gap)
                if k % 2 == 0:
                    assert gap > safe, (world, k, gap)
        joints, was_done = now, te | tr
    assert accepted > 3000 and refused > 500, (accepted, refused)
    # The rollouts came close: the invariant was tested where it matters.
    assert smallest < 2 * safe, smallest


def test_refused_step_leaves_the_state_unchanged():
    env = gym.make(sixaxis_avoid.JOINT_ENV_ID)
    obs, _ = env.reset(seed=0)
    u = env.unwrapped
    r_idx = u.obs_layout["refused"]
    a = np.array([0, 1, 0, 0, 0, 0], dtype=np.float32)
    seen = 0
    for _ in range(200):
        q, t = u.joints, u.terminal_mm
        new, r, _, _, info = env.step(a)
        if info["refused"]:
            seen += 1
            np.testing.assert_array_equal(u.joints, q)
            np.testing.assert_array_equal(u.terminal_mm, t)
            np.testing.assert_array_equal(new[:r_idx], obs[:r_idx])
            assert new[r_idx] == 1.0 and r < 0
            assert info["detour_penalty"] == (0.0 if seen == 1 else -2.0)
        obs = new
    assert seen > 10


def test_bad_keywords_and_actions_name_the_keyword_and_value():
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"`max_joint_step_deg` = -1"):
        gym.make(sixaxis_avoid.JOINT_ENV_ID, max_joint_step_deg=-1)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"`assist` = 'yes'"):
        gym.make(sixaxis_avoid.JOINT_GOAL_ENV_ID, assist="yes")
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"`target_tolerance_mm` = 0"):
        gym.make_vec(sixaxis_avoid.JOINT_ENV_ID, num_envs=2, target_tolerance_mm=0)
    with pytest.raises(TypeError, match="max_joint_step"):
        gym.make(sixaxis_avoid.JOINT_ENV_ID, max_joint_step=1.0)
    with pytest.raises(sixaxis_avoid.ScenarioError, match=r"arm.beta0_deg.*safe distance 60 mm"):
        # beta_0 keeps only 50 mm from paper_simple's cubes.
        gym.make(sixaxis_avoid.JOINT_ENV_ID, safe_distance_mm=60)
    env = gym.make(sixaxis_avoid.JOINT_ENV_ID)
    env.reset(seed=0)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"`action` = 1.5 at joint 3"):
        env.step(np.array([0, 0, 0, 1.5, 0, 0]))
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="`action`"):
        env.step([0.0, 0.0])
    venv = gym.make_vec(sixaxis_avoid.JOINT_ENV_ID, num_envs=2)
    venv.reset(seed=0)
    bad = np.zeros((2, 6))
    bad[1, 0] = np.nan
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"`actions\[1\]` = NaN"):
        venv.step(bad)


def test_options_joint_lists_every_keyword_with_the_envs_default():
    """``options("joint")`` is the one declaration: every keyword the model reads is a row
    whose default is the model's actual default, the envs' own keywords have their
    signature defaults, the registrations' step cap is the declared one, and a bad value of
    any row is an error naming the keyword and the value."""
    import inspect
    import re

    from sixaxis_avoid.joint import SixAxisAvoidJointVectorEnv, check_joint_keywords

    rows = {o["key"]: o for o in sixaxis_avoid.options("joint")}
    model = _core.JointEnvCore().options  # built without keywords: the model's defaults
    env_only = {"num_envs", "copy", "render_mode"}
    assert set(rows) == set(model) | env_only
    for key, value in model.items():
        assert rows[key]["default"] == value, key
        assert type(rows[key]["default"]) is type(value), key
    assert model["max_joint_step_deg"] == 2.0 and model["max_episode_steps"] == 500
    params = inspect.signature(SixAxisAvoidJointVectorEnv.__init__).parameters
    for key in env_only:
        assert rows[key]["default"] == params[key].default, key
    for env_id in IDS:
        assert gym.spec(env_id).max_episode_steps == rows["max_episode_steps"]["default"]
    # Every row is a keyword the envs accept; passing each default changes nothing.
    given = {k: o["default"] for k, o in rows.items() if k not in env_only}
    env = gym.make(sixaxis_avoid.JOINT_ENV_ID, **given)
    assert env.unwrapped._core.options == model
    venv = gym.make_vec(sixaxis_avoid.JOINT_ENV_ID, num_envs=2, **given)
    assert venv.unwrapped._core.options == model
    for key, o in rows.items():
        bad: object = {"bool": "yes", "choice": "nope"}.get(o["kind"], int(o.get("min", 0)) - 1)
        want = rf"`{key}` = {re.escape(repr(bad))}"
        with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=want):
            check_joint_keywords(**{key: bad})
        if key == "max_episode_steps":  # gym.make gives it to Gymnasium's TimeLimit
            with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=want):
                gym.make_vec(sixaxis_avoid.JOINT_ENV_ID, num_envs=2, **{key: bad})
        elif key not in env_only:
            with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=want):
                gym.make(sixaxis_avoid.JOINT_ENV_ID, **{key: bad})


def test_docstring_states_the_tables_defaults():
    """The env's docstring (Gymnasium's layout) takes every default from the one table:
    each model keyword is listed with its default, the reward terms quote theirs, and no
    placeholder is left; a placeholder naming no keyword is an error."""
    import re

    from sixaxis_avoid.joint import SixAxisAvoidJointEnv, documented

    doc = SixAxisAvoidJointEnv.__doc__
    for section in ("Description", "Action Space", "Observation Space", "Rewards",
                    "Starting State", "Episode End", "Arguments", "Version History"):  # fmt: skip
        assert f"## {section}\n" in doc, section
    model = _core.JointEnvCore().options
    for key, value in model.items():
        shown = repr(value) if value is None or isinstance(value, bool) else f"{value:g}"
        assert re.search(rf"- ``{key}`` \(([^,()]+, )?default {re.escape(shown)}\): ", doc), key
    assert "``-step_penalty`` (0.02)" in doc and "(500 in the registration" in doc
    assert "{" not in doc.replace("``{", "")
    with pytest.raises(RuntimeError, match=r"\{step_penalti\}"):
        documented("a typo: {step_penalti}")


def test_goal_compute_reward_is_the_steps_reward():
    env = gym.make(sixaxis_avoid.JOINT_GOAL_ENV_ID)
    env.reset(seed=0)
    u = env.unwrapped
    rows = []
    for a in drifting_actions(np.random.default_rng(2), 1, 300)[:, 0]:
        new, r, te, tr, info = env.step(a)
        assert u.compute_reward(new["achieved_goal"], new["desired_goal"], info) == r
        rows.append((new["achieved_goal"], new["desired_goal"], info, r))
        if te or tr:
            env.reset()
    achieved = np.array([row[0] for row in rows])
    desired = np.array([row[1] for row in rows])
    rewards = u.compute_reward(achieved, desired, [row[2] for row in rows])
    np.testing.assert_array_equal(rewards, [row[3] for row in rows])
    assert any(row[2]["refused"] for row in rows)
    # Relabelled: the achieved goal as the target is a success (target_reward + progress).
    relabelled = u.compute_reward(achieved, achieved, [row[2] for row in rows])
    accepted = np.array([not row[2]["refused"] for row in rows])
    assert np.all(relabelled[accepted] >= 10.0 - 1e-9)


def test_rollout_becomes_a_plan_that_verify_accepts():
    """A rollout (a hand-made policy: reach the target through joint-space gradient steps
    on the terminal distance) is a plan that MuJoCo's checker replays without contact."""
    from sixaxis_avoid.verify import verify_plan

    env = gym.make(sixaxis_avoid.JOINT_ENV_ID)
    u = env.unwrapped
    arm = _core.Arm.from_scenario(u.scenario)
    rng = np.random.default_rng(4)

    def policy(obs):
        # Greedy: the best of 16 random actions by the distance their end pose gives.
        q = u.joints
        cands = rng.uniform(-1, 1, (16, 6))
        ends = arm.fk_batch(q + np.radians(2.0) * cands)
        d = np.linalg.norm(np.asarray(ends)[:, :3] - u.target_mm, axis=1)
        return cands[int(np.argmin(d))]

    plan = rollout_plan(env, policy, max_steps=150, seed=0)
    assert len(plan["poses_rad"]) == 1 + plan["steps"] - plan["refused_steps"]
    assert plan["interpolation_steps"] >= 1
    radius = 1.0
    report = verify_plan(plan, u.scenario, link_radius_mm=radius)
    assert report.contacts == 0
    # Every replayed pose keeps the env's guaranteed gap (minus the replay's own radius).
    assert report.min_distance_mm >= 0.75 * u.safe_distance_mm - radius - 0.5, report
    from sixaxis_avoid.animate import plan_frames

    frames = plan_frames(plan, u.scenario, frames_per_move=1, size=64, hold_frames=0)
    assert len(frames) == len(plan["poses_rad"])


def test_sb3_vecenv_over_the_joint_batch():
    from sixaxis_avoid.sb3 import SixAxisVecEnv

    venv = SixAxisVecEnv(3, seed=0, env_id=sixaxis_avoid.JOINT_GOAL_ENV_ID, max_episode_steps=4)
    obs = venv.reset()
    assert obs["observation"].shape == (3, 27)
    for _ in range(4):
        obs, _, dones, infos = venv.step(np.zeros((3, 6), dtype=np.float32))
    # The cap ended every episode; SB3's rule: reset at once, the last observation in info.
    assert dones.all() and infos[0]["TimeLimit.truncated"]
    assert "terminal_observation" in infos[0]
    assert {"is_success", "clearance", "refused", "previous_achieved_goal"} <= set(infos[0])
    got = venv.env_method(
        "compute_reward", obs["achieved_goal"], obs["desired_goal"], infos, indices=[0]
    )[0]
    assert got.shape == (3,)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="render_mode"):
        SixAxisVecEnv(2, env_id=sixaxis_avoid.JOINT_ENV_ID, render_mode="rgb_array")


def test_baseline_script_trains_on_the_native_vec_env(tmp_path):
    """scripts/bench_joint.py baseline with --n-envs trains SB3 SAC on the native VecEnv:
    the run counts every lane's env steps, updates gradient-steps times per vector step
    after learning starts, records the evaluated episode's final and closest distance to
    the target, and writes its JSON (docs/JOINT.md, "Baselines")."""
    import importlib.util
    import json
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "scripts" / "bench_joint.py"
    spec = importlib.util.spec_from_file_location("bench_joint", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "sac.json"
    argv = ["--timesteps", "128", "--seeds", "0", "--n-envs", "8", "--learning-starts", "64",
            "--gradient-steps", "2", "--net", "16,16", "--batch-size", "16",
            "--max-episode-steps", "20", "--json", str(out)]  # fmt: skip
    assert mod.baseline(argv) == 0
    rec = json.loads(out.read_text())
    (run,) = rec["runs"]
    assert run["env_steps"] == 128
    # 16 vector steps of 8 envs; updates from the vector step past 64 env steps: 8 x 2.
    assert run["updates"] == 2 * (128 - 64) // 8
    # The evaluated episode's last and closest terminal-target distances (mm).
    (final,), (closest,) = run["final_distance_mm"], run["closest_distance_mm"]
    assert 0 <= closest <= final
    assert rec["algorithm2_terminal_path_mm"] == 900.0

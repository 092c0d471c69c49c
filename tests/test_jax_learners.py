"""Smoke test of the rejax learners on the JAX twin (the study itself is not run in CI):
a tiny PPO run of two vmapped seeds gives the JSON record the docs read."""

from __future__ import annotations

import importlib
import io
import json
import sys
import time

import jax
import numpy as np
import pytest
from _helpers import assert_same_trials
from gymnasium.error import DependencyNotInstalled
from sixaxis_avoid.benchmark import (
    jax_learners,
    jax_runs,
    jax_state,
    jax_tune,
    learners,
    report,
    report_pending,
    runner,
)
from sixaxis_avoid.benchmark.tasks import load_suite

TINY_DQN = {
    "net_arch": [16, 16], "batch_size": 16, "buffer_size": 1000, "learning_starts": 100,
    "train_freq": 4, "gradient_steps": 1, "max_episode_steps": 50,
    "target_update_interval": 100,
}  # fmt: skip
TINY_PPO = {
    "net_arch": [16, 16], "n_envs": 4, "n_steps": 16, "batch_size": 32, "n_epochs": 1,
    "max_episode_steps": 50,
}  # fmt: skip


def test_tiny_ppo_run_records_its_flags_speed_and_evaluations(tmp_path):
    out = tmp_path / "ppo.json"
    rec = jax_learners.main(
        [
            "--seeds", "2", "--budget", "2048", "--evaluations", "2",
            "--set", "n_envs=4", "--set", "n_steps=16", "--set", "batch_size=32",
            "--set", "n_epochs=1", "--set", "net_arch=[16,16]", "--set", "max_episode_steps=50",
            "--sb3-steps", "512", "--out", str(out),
        ]
    )  # fmt: skip
    assert json.loads(out.read_text()) == rec
    assert rec["seeds"] == [0, 1] and rec["task"] == "paper_simple"
    assert rec["values"]["net_arch"] == [16, 16] and rec["rejax_config"]["num_steps"] == 16
    assert rec["rejax_config"]["agent_kwargs"]["hidden_layer_sizes"] == [16, 16]
    assert rec["rejax_config"]["num_minibatches"] == 2  # 4 x 16 / 32
    # Evaluations at 1024 and 2048 env steps (whole iterations of 64), per seed.
    assert rec["eval_env_steps"] == [1024, 2048]
    for key in ("success", "spl"):
        assert len(rec[key]) == 2 and all(len(r) == 2 for r in rec[key])
        assert all(0.0 <= v <= 1.0 for r in rec[key] for v in r)
    # SPL is at most the success, and positive only where the target was reached.
    for s_row, p_row in zip(rec["success"], rec["spl"]):
        assert all(p <= s and (p > 0) == (s > 0) for s, p in zip(s_row, p_row))
    assert rec["env_steps_per_s"] > 0 and rec["compile_s"] > 0
    # The SB3 PPO of the same values, timed.
    assert rec["sb3"]["env_steps"] == 512 and rec["sb3"]["env_steps_per_s"] > 0
    assert rec["sb3"]["updates_per_env_step"] == rec["updates_per_env_step"] == 2 / 64
    assert rec["speedup_vs_sb3"] == rec["env_steps_per_s"] / rec["sb3"]["env_steps_per_s"]


def test_training_and_checkpoints_end_on_whole_iterations_within_the_budget():
    # Iterations of 4 x 16 = 64 env steps on a budget of 2000: 31 iterations (1984 steps),
    # not 32 (2048); the checkpoint at 1000 after 15 (960).
    rec = jax_learners.main(
        [
            "--seeds", "1", "--budget", "2000", "--evaluations", "2",
            "--set", "n_envs=4", "--set", "n_steps=16", "--set", "batch_size=32",
            "--set", "n_epochs=1", "--set", "net_arch=[16,16]", "--set", "max_episode_steps=50",
        ]
    )  # fmt: skip
    assert rec["eval_env_steps"] == [960, 1984]


def test_missing_rejax_names_the_jax_learners_extra(monkeypatch):
    for mod in [m for m in sys.modules if m == "rejax" or m.startswith("rejax.")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.setitem(sys.modules, "rejax", None)
    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[jax-learners\]"):
        jax_learners.main(["--seeds", "1", "--budget", "64"])


def test_gymnax_interface_module_names_its_extra(monkeypatch):
    for mod in [m for m in sys.modules if m == "gymnax" or m.startswith("gymnax.")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.delitem(sys.modules, "sixaxis_avoid.jax.gymnax_compat", raising=False)
    monkeypatch.setitem(sys.modules, "gymnax", None)
    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[jax-learners\]"):
        importlib.import_module("sixaxis_avoid.jax.gymnax_compat")


def test_dqn_vmapped_over_candidates_equals_each_candidate_alone():
    # Two candidates differing in traced knobs (learning rate and its schedule, gamma,
    # exploration, target-update interval) train in one call; the second, trained alone on
    # the same seeds, gives the same evaluations and the same final Q-network.
    task = load_suite("v1").task("paper_simple")
    c1 = {**TINY_DQN, "learning_rate": 1e-3}
    c2 = {
        **TINY_DQN, "learning_rate": 3e-3, "lr_schedule": "linear", "gamma": 0.9,
        "exploration_fraction": 0.3, "target_update_interval": 200, "max_episode_steps": 40,
    }  # fmt: skip
    comp = jax_learners.compiled_group("dqn", task, jax_learners.check_values("dqn", c1),
                                       1200, [400, 1200])  # fmt: skip
    both = comp.run([jax_learners.check_values("dqn", c) for c in (c1, c2)], [0, 1])
    alone = comp.run([jax_learners.check_values("dqn", c2)], [0, 1])
    assert both["env_steps"] == alone["env_steps"] == [400, 1200]
    for key in ("success", "spl", "reached", "moves", "first_success_env_steps", "episodes"):
        assert both["out"][key].shape[:2] == (2, 2)
        np.testing.assert_array_equal(both["out"][key][1], alone["out"][key][0])
    for a, b in zip(jax.tree_util.tree_leaves(both["params"]),
                    jax.tree_util.tree_leaves(alone["params"])):  # fmt: skip
        np.testing.assert_allclose(np.asarray(a)[1], np.asarray(b)[0], rtol=1e-5, atol=1e-6)
    # The two candidates did train differently (the check above could not pass by accident).
    leaf = jax.tree_util.tree_leaves(both["params"])[0]
    assert not np.allclose(np.asarray(leaf)[0], np.asarray(leaf)[1])
    # DQN trained and was evaluated: scores in [0, 1], SPL positive only where reached.
    spl, success = both["out"]["spl"], both["out"]["success"]
    assert ((0 <= spl) & (spl <= success) & (success <= 1)).all()
    assert ((spl > 0) == (success > 0)).all()
    assert (both["out"]["episodes"] > 0).all()


def test_bad_values_name_the_field_and_value():
    with pytest.raises(jax_learners.JaxLearnerError, match=r"lr_schedule: 'cosine'"):
        jax_learners.check_values("ppo", {"lr_schedule": "cosine"})
    with pytest.raises(jax_learners.JaxLearnerError, match=r"batch_size: 48 does not divide"):
        jax_learners.check_values("ppo", {"batch_size": 48})
    with pytest.raises(jax_learners.JaxLearnerError, match=r"unknown hyperparameter 'n_envs'"):
        jax_learners.check_values("dqn", {"n_envs": 4})
    with pytest.raises(jax_learners.JaxLearnerError, match=r"gamma: 1.5"):
        jax_learners.check_values("dqn", {"gamma": 1.5})
    with pytest.raises(jax_learners.JaxLearnerError, match=r"replay_sample: 'prioritised'"):
        jax_learners.check_values("dqn", {"replay_sample": "prioritised"})


def test_dqn_draw_with_replacement_samples_stored_transitions_only():
    # SB3's draw: uniform with replacement over the transitions stored so far, never an
    # unwritten slot; rejax's draw stays the default (the committed 30k studies used it).
    assert jax_learners.DQN_DEFAULTS["replay_sample"] == "without_replacement"
    dqn = jax_learners.rejax_classes()["dqn"]
    task = load_suite("v1").task("paper_simple")
    values = jax_learners.check_values("dqn", {**TINY_DQN, "replay_sample": "with_replacement"})
    comp = jax_learners.compiled_group("dqn", task, values, 400, [400])
    assert comp.base.replay_with_replacement and isinstance(comp.base, dqn)
    ts = comp.base.init_state(jax.random.PRNGKey(0))
    buf = ts.replay_buffer
    assert type(buf).__name__ == "UniformReplayBuffer" and buf.size == 1000
    # 7 transitions stored (rewards 1..7); 4096 draws of 64 hit each of them and nothing else.
    rewards = buf.data.reward.at[:7].set(np.arange(1, 8, dtype=np.float32)).at[7:].set(-1.0)
    buf = buf.replace(data=buf.data._replace(reward=rewards), index=7)
    drawn = np.concatenate(
        [np.asarray(buf.sample(64, k).reward) for k in jax.random.split(jax.random.PRNGKey(1), 64)]
    )
    assert set(drawn.tolist()) == set(range(1, 8))
    # With replacement: one batch of 64 from 7 transitions repeats some.
    assert len(set(np.asarray(buf.sample(64, jax.random.PRNGKey(2)).reward).tolist())) <= 7
    # The draw is a static knob: another compiled group; both train and evaluate.
    rejax_values = jax_learners.check_values("dqn", TINY_DQN)
    assert jax_learners.static_key("dqn", values) != jax_learners.static_key("dqn", rejax_values)
    r = comp.run([values], [0, 1])
    assert r["out"]["spl"].shape == (1, 2, 1) and (r["out"]["episodes"] > 0).all()


def test_random_search_space_has_schedules_and_few_compiled_groups():
    cands = jax_tune.draw("ppo", 32, 2, seed=0)
    assert len(cands) == 32 and cands == jax_tune.draw("ppo", 32, 2, seed=0)
    assert {c["lr_schedule"] for c in cands} == {"constant", "linear"}
    assert len({jax_learners.static_key("ppo", c) for c in cands}) <= 2
    assert len({c["learning_rate"] for c in cands}) == 32


def test_tuner_set_fixes_a_value_and_keeps_the_other_draws(tmp_path, monkeypatch):
    seen = {}

    def fake_tune(algo, suite, budget, candidates, seeds, tasks, **kwargs):
        seen["candidates"] = candidates
        raise SystemExit(0)  # the draw is what is under test

    monkeypatch.setattr(jax_tune, "tune", fake_tune)
    with pytest.raises(SystemExit):
        jax_tune.main([
            "--algo", "dqn", "--suite", "v2", "--budget", "1000", "--trials", "32",
            "--set", 'replay_sample="with_replacement"', "--set", "gamma=0.9",
            "--out", str(tmp_path / "t.json"), "--hyperparams", str(tmp_path / "hp.json"),
        ])  # fmt: skip
    drawn = jax_tune.draw("dqn", 32, 2, seed=0)
    got = seen["candidates"]
    assert [c["replay_sample"] for c in got] == ["with_replacement"] * 32
    assert [c["gamma"] for c in got] == [0.9] * 32
    rest = [{k: v for k, v in c.items() if k not in ("replay_sample", "gamma")} for c in got]
    assert rest == [{k: v for k, v in c.items() if k not in ("replay_sample", "gamma")}
                    for c in drawn]  # fmt: skip
    with pytest.raises(jax_learners.JaxLearnerError, match=r"replay_sample: 'x'"):
        jax_tune.main(["--algo", "dqn", "--budget", "1000", "--set", "replay_sample=x",
                       "--out", str(tmp_path / "t.json")])  # fmt: skip


def test_tuner_writes_every_trial_and_merges_the_best(tmp_path, monkeypatch):
    hp = tmp_path / "v2.json"
    hp.write_text(json.dumps({"learners": {"q_assist": {"by_budget": {"30000": {"x": 1}}}}}))
    # One static group over every candidate, tiny shapes (the space's draws cost more).
    monkeypatch.setattr(
        jax_tune,
        "space",
        lambda algo, rng: (
            dict(TINY_PPO),
            {
                "learning_rate": float(rng.uniform(1e-4, 3e-3)),
                "lr_schedule": ["constant", "linear"][int(rng.integers(2))],
            },
        ),
    )
    out = tmp_path / "trials.json"
    rec = jax_tune.main([
        "--algo", "ppo", "--suite", "v1", "--tasks", "tune-gen-easy-1000", "--budget", "1024",
        "--trials", "3", "--seeds", "2", "--hyperparams", str(hp), "--out", str(out),
    ])  # fmt: skip
    data = json.loads(out.read_text())
    assert data == json.loads(json.dumps(rec))
    assert [t["number"] for t in data["trials"]] == [0, 1, 2] and data["seeds"] == [100, 101]
    for t in data["trials"]:
        scores = t["final_score"]["tune-gen-easy-1000"]
        assert len(scores) == 2 and t["objective"] == pytest.approx(np.mean(scores))
        assert t["curves"]["tune-gen-easy-1000"]["env_steps"][-1] == 1024
    best = max(data["trials"], key=lambda t: t["objective"])
    assert data["best_value"] == best["objective"]
    merged = json.loads(hp.read_text())["learners"]
    assert merged["q_assist"] == {"by_budget": {"30000": {"x": 1}}}  # kept
    entry = merged["jax_ppo"]["by_budget"]["1024"]
    assert entry["status"] == "tuned" and entry["objective"] == best["objective"]
    assert entry["values"] == data["trials"][data["best_trial"]]["values"]
    assert entry["trials"] == str(out) and entry["n_trials"] == 3


def two_static_draws(monkeypatch) -> None:
    """A search space of tiny PPO nets whose static knob (``net_arch``) takes two values."""
    monkeypatch.setattr(
        jax_tune,
        "space",
        lambda algo, rng: (
            {**TINY_PPO, "net_arch": [[8], [16]][int(rng.integers(2))]},
            {"learning_rate": float(rng.uniform(1e-4, 3e-3))},
        ),
    )


def test_tuner_resumes_a_stopped_search_from_its_saved_groups(tmp_path, monkeypatch):
    # Two static groups (net_arch drawn per group) on two tasks: four compiled groups.
    two_static_draws(monkeypatch)
    argv = [
        "--algo", "ppo", "--suite", "v1", "--tasks", "tune-gen-easy-1000,tune-gen-medium-1001",
        "--budget", "512", "--trials", "4", "--seeds", "2", "--groups", "2",
        "--sampler-seed", "3",
    ]  # fmt: skip
    whole = jax_tune.main([*argv, "--out", str(tmp_path / "a" / "t.json"),
                           "--hyperparams", str(tmp_path / "a" / "hp.json")])  # fmt: skip
    assert whole["resumed_groups"] == 0
    assert not (tmp_path / "a" / "t.json.parts").exists()  # removed once on record

    # A stop during the second task: its first group's outcome is not saved.
    calls = []
    run = jax_learners.Compiled.run

    def stopping(self, candidates, seeds):
        calls.append(self.task.id)
        if self.task.id == "tune-gen-medium-1001":
            raise KeyboardInterrupt
        return run(self, candidates, seeds)

    # Its parts directory under a study's -pending directory: the page names it in progress.
    out, hp = tmp_path / "b" / "t.json", tmp_path / "b" / "hp.json"
    pdir = tmp_path / "study-pending" / "jax_tune-ppo-512"
    argv = [*argv, "--parts", str(pdir)]
    monkeypatch.setattr(jax_learners.Compiled, "run", stopping)
    with pytest.raises(KeyboardInterrupt):
        jax_tune.main([*argv, "--out", str(out), "--hyperparams", str(hp)])
    parts = sorted(pdir.glob("*--*.json"))
    assert [p.name.split("--")[0] for p in parts] == ["tune-gen-easy-1000"] * 2
    assert not out.exists() and not hp.exists()
    man = json.loads((pdir / "study.json").read_text())
    assert (man["kind"], man["learners"], man["budget"], man["runs"], man["finished"]) == (
        "jax_tune",
        ["jax_ppo"],
        512,
        4,
        False,
    )
    assert man["command"].startswith("python -m sixaxis_avoid.benchmark.jax_tune --algo ppo")
    assert man["wall_time_s_total"] > 0
    (p,) = report_pending.sets_in_progress(tmp_path / "study")
    assert (p["kind"], p["made"], p["of"], p["budgets"]) == ("jax_tune", 2, 4, [512])
    # --status reads the same progress from the files, training and writing nothing.
    before = {f.name: f.read_bytes() for f in pdir.iterdir()}
    calls.clear()
    st = jax_tune.main([*argv, "--out", str(out), "--hyperparams", str(hp), "--status"])
    assert calls == [] and {f.name: f.read_bytes() for f in pdir.iterdir()} == before
    assert [(r["task"], r["group"], r["status"]) for r in st["groups"]] == [
        ("tune-gen-easy-1000", 0, "done"),
        ("tune-gen-easy-1000", 1, "done"),
        ("tune-gen-medium-1001", 0, "not started"),
        ("tune-gen-medium-1001", 1, "not started"),
    ]
    assert (st["done"], st["not_started"], st["other_files"]) == (2, 2, 0)
    assert st["cpu_s"] == pytest.approx(sum(r["cpu_s"] for r in st["groups"][:2]))
    assert st["cpu_s"] > 0
    # Asked in the other mode, the same files are not this search's groups, and it says so.
    other = jax_tune.main([*argv, "--out", str(out), "--save-state", "--status"])
    assert (other["done"], other["not_started"], other["other_files"]) == (0, 4, 2)
    assert (
        "the JAX search for jax_ppo at 512 (4 candidates x 2 seeds x 2 tuning tasks), 2 of 4 "
        f"compiled groups in `{pdir}`" in report_pending.in_progress_sentence([p])
    )

    # The same command again trains only what is missing, and records what a whole run does.
    calls.clear()
    monkeypatch.setattr(
        jax_learners.Compiled,
        "run",
        lambda self, c, s: calls.append(self.task.id) or run(self, c, s),
    )
    # The read-back groups' own wall times are theirs, not the search's: on a cluster they
    # overlap. Made long here, they stay in the task's times but not in the search's wall
    # time, which is the commands' (the manifest's so far plus this command's).
    for f in parts:
        d = json.loads(f.read_text())
        f.write_text(json.dumps({**d, "group_wall_s": d["group_wall_s"] + 1e5}))
    earlier = json.loads((pdir / "study.json").read_text())["wall_time_s_total"]
    t0 = time.perf_counter()
    again = jax_tune.main([*argv, "--out", str(out), "--hyperparams", str(hp)])
    took = time.perf_counter() - t0
    assert calls == ["tune-gen-medium-1001"] * 2 and again["resumed_groups"] == 2
    assert_same_trials(whole, again)
    assert again["wall_time_basis"] == "commands"
    assert earlier < again["wall_time_s"] <= earlier + took
    assert sum(t["wall_s"] for t in again["per_task_timing"]) > 2e5
    assert not pdir.exists()  # the parts and the manifest go once the search is on record

    # A saved outcome from another search (its identity differs) is trained again, not read.
    calls.clear()
    monkeypatch.setattr(jax_learners.Compiled, "run", stopping)
    with pytest.raises(KeyboardInterrupt):
        jax_tune.main([*argv, "--out", str(out), "--hyperparams", str(hp)])
    part = sorted(pdir.glob("*--*.json"))[0]
    data = json.loads(part.read_text())
    part.write_text(json.dumps({**data, "ident": "0" * 64}))
    wall = json.loads((pdir / "study.json").read_text())["wall_time_s_total"]
    calls.clear()
    with pytest.raises(KeyboardInterrupt):
        jax_tune.main([*argv, "--out", str(out), "--hyperparams", str(hp)])
    assert calls == ["tune-gen-easy-1000", "tune-gen-medium-1001"]
    # Each command adds its wall time to the manifest's.
    assert json.loads((pdir / "study.json").read_text())["wall_time_s_total"] > wall


def test_run_group_records_read_by_the_report(tmp_path):
    suite = load_suite("quick")
    task = suite.tasks[0]
    specs = runner.plan_runs(suite, ["jax_ppo"], seeds=[0, 1], tasks=[task])
    for s in specs:
        s["budget"], s["checkpoints"] = 1024, [256, 1024]
        s["hyperparams"] = {**s["hyperparams"], **TINY_PPO}
    assert {s["family"] for s in specs} == {"jax"}
    assert len(jax_runs.groups(specs)) == 1
    records = jax_runs.run_group(specs)
    assert [r["spec"]["seed"] for r in records] == [0, 1]
    for r in records:
        res = r["result"]
        assert [p["env_steps"] for p in res["curve"]] == [256, 1024]
        assert res["env_steps"] == 1024 and res["score"] == res["curve"][-1]["score"]
        assert len(res["paths"]) == len(task.eval_targets) and r["host"]["machine"]
        # One record layout (runner.run_record) for every learner, with JAX's versions added.
        assert r["host"]["versions"]["jax"] and r["host"]["versions"]["numpy"]
        for path, length in zip(res["paths"], res["path_lengths"]):
            assert (path is None) == (length is None)
        runner.write_run(tmp_path, r)
    runner.write_manifest(tmp_path, {"learners": ["jax_ppo"], "tasks": [task.id]})
    a = report.analyse(tmp_path, reps=50)
    assert a["learners"] == ["jax_ppo"] and a["seeds"] == [0, 1]
    assert a["per"]["jax_ppo"]["score_mean"] == pytest.approx(
        np.mean([r["result"]["score"] for r in records])
    )
    assert learners.resolve("jax_dqn") is jax_runs.JaxDQN
    assert learners.family_of(learners.resolve("jax_ppo")) == "jax"
    assert "jax_ppo" not in learners.BUILTIN  # the default study does not run it
    with pytest.raises(ValueError, match="differ in more than their seed"):
        jax_runs.run_group([specs[0], {**specs[1], "budget": 2048}])


def test_a_group_trained_in_pieces_goes_on_from_its_saved_state(tmp_path, monkeypatch):
    suite = load_suite("v2")
    task = suite.tuning_tasks[3]  # the goal task: several evaluation targets
    values = [
        jax_learners.check_values("ppo", {**TINY_PPO, "learning_rate": lr}) for lr in (1e-3, 3e-3)
    ]
    comp = jax_learners.Compiled("ppo", task, values[0], 4096, [512, 1024, 4096])
    whole = comp.run(values, [0, 1])
    assert whole["resumes"] == 0
    # 64 iterations in pieces of at most 64 / 7 -> 10, and a save after every one.
    monkeypatch.setattr(jax_state, "STATE_EVERY_S", 0.0)
    monkeypatch.setattr(jax_state, "STATE_PIECES", 7)
    state = tmp_path / "g.state.npz"
    pieces = comp.run(values, [0, 1], state=state, ident="a")
    assert pieces["resumes"] == 0 and not state.exists()  # gone once the group is done

    # A stop in the third piece (the first of the last checkpoint's segment) keeps the state.
    advance, calls = comp._piece_executables[(2, 2)]["advance"], []

    def stopping(*args):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return advance(*args)

    comp._piece_executables[(2, 2)]["advance"] = stopping
    with pytest.raises(KeyboardInterrupt):
        comp.run(values, [0, 1], state=state, ident="a")
    assert state.exists()
    comp._piece_executables[(2, 2)]["advance"] = lambda *args: calls.append(1) or advance(*args)
    calls.clear()
    again = comp.run(values, [0, 1], state=state, ident="a")
    # It went on from the state after 2 pieces: 7 pieces in all (segments of 8, 8 and 48
    # iterations in pieces of 8, 8, 10, 10, 10, 10, 8), 5 of them left.
    assert again["resumes"] == 1 and len(calls) == 5 and not state.exists()
    assert again["train_cpu_s"] > 0
    for key in whole["out"]:
        assert np.array_equal(pieces["out"][key], again["out"][key]), key
    same = jax.tree_util.tree_map(
        lambda x, y: np.array_equal(np.asarray(x), np.asarray(y)), pieces["params"], again["params"]
    )
    assert all(jax.tree_util.tree_leaves(same))
    # The pieces train what one call trains, up to float rounding.
    close = jax.tree_util.tree_map(
        lambda x, y: np.allclose(np.asarray(x), np.asarray(y), atol=1e-5),
        whole["params"],
        pieces["params"],
    )
    assert all(jax.tree_util.tree_leaves(close))

    # A state saved by another training (another ident) is not gone on from.
    comp._piece_executables[(2, 2)]["advance"] = stopping
    calls.clear()
    with pytest.raises(KeyboardInterrupt):
        comp.run(values, [0, 1], state=state, ident="a")
    comp._piece_executables[(2, 2)]["advance"] = lambda *args: calls.append(1) or advance(*args)
    calls.clear()
    other = comp.run(values, [0, 1], state=state, ident="b")
    assert other["resumes"] == 0 and len(calls) == 7


def test_search_with_save_state_gives_its_groups_a_state_file_and_an_identity_apart(
    tmp_path, monkeypatch
):
    seen = []
    monkeypatch.setattr(
        jax_learners, "train_group", lambda *job: seen.append(job) or {"stub": True}
    )
    task = load_suite("v2").tuning_tasks[0]
    values = [jax_learners.check_values("ppo", TINY_PPO)]
    parts = tmp_path / "parts"
    job = ("ppo", task, values, [0], 512, [512])
    plain_path, plain = jax_learners.group_part(parts, job)
    piece_path, piece = jax_learners.group_part(parts, job, pieces=True)
    assert plain != piece and plain_path != piece_path

    def dispatch(jobs):
        for k, j in enumerate(jobs):
            seen.append(j)
            yield k, {"env_steps": [512], "success": [[0.0]], "spl": [[0.0]],
                      **dict.fromkeys(("compile_s", "train_wall_s", "train_cpu_s",
                                       "group_wall_s", "group_cpu_s"), 0.0)}  # fmt: skip

    jax_learners.train_candidates("ppo", [task], values, [0], 512, [512], parts=parts,
                                  dispatch=dispatch, save_state=True)  # fmt: skip
    (j,) = seen
    assert j[:6] == job and j[6] == (str(piece_path.resolve().with_suffix(".state.npz")), piece)
    assert piece_path.exists()  # the outcome, saved under the pieces' identity
    seen.clear()
    jax_learners.train_candidates("ppo", [task], values, [0], 512, [512], parts=parts,
                                  dispatch=dispatch)  # fmt: skip
    assert seen[0] == job  # one call, no state; the pieces' outcome is not read for it


def test_tuner_with_save_state_goes_on_from_inside_a_stopped_group(tmp_path, monkeypatch):
    monkeypatch.setattr(jax_tune, "space", lambda algo, rng: (
        TINY_PPO, {"learning_rate": float(rng.uniform(1e-4, 3e-3))}))  # fmt: skip
    monkeypatch.setattr(jax_state, "STATE_EVERY_S", 0.0)
    argv = [
        "--algo", "ppo", "--suite", "v2", "--tasks", "tune-gen-easy-1000", "--budget", "1024",
        "--trials", "2", "--seeds", "2", "--groups", "1", "--save-state",
    ]  # fmt: skip
    whole = jax_tune.main([*argv, "--out", str(tmp_path / "a" / "t.json"),
                           "--hyperparams", str(tmp_path / "a" / "hp.json")])  # fmt: skip
    assert whole["per_task_timing"][0]["state_resumes"] == 0

    # A stop right after the group's second save: its state is kept beside the parts.
    save, saves = jax_state.save_state, []

    def save_then_stop(*args):
        save(*args)
        saves.append(1)
        if len(saves) == 2:
            raise KeyboardInterrupt

    pdir = tmp_path / "parts"
    argv = [*argv, "--parts", str(pdir), "--out", str(tmp_path / "b" / "t.json"),
            "--hyperparams", str(tmp_path / "b" / "hp.json")]  # fmt: skip
    monkeypatch.setattr(jax_state, "save_state", save_then_stop)
    with pytest.raises(KeyboardInterrupt):
        jax_tune.main(argv)
    assert [p.name[-10:] for p in pdir.glob("*--*")] == [".state.npz"]
    st = jax_tune.main([*argv, "--status"])
    (g,) = st["groups"]
    # --status reads how far the stopped group got from its state, without its arrays.
    assert (g["status"], g["checkpoints"], g["resumes"]) == ("saved part way", 12, 0)
    assert g["checkpoints_done"] * 1000 + g["iterations_past"] > 0 and g["cpu_s"] > 0
    if g["checkpoints_done"]:
        assert g["env_steps"] == load_suite("v2").checkpoints(1024)[g["checkpoints_done"] - 1]
    buf = io.StringIO()
    jax_tune.print_status(st, buf)
    assert "1 compiled groups in" in buf.getvalue() and "saved part way" in buf.getvalue()
    monkeypatch.setattr(jax_state, "save_state", save)
    again = jax_tune.main(argv)
    assert again["per_task_timing"][0]["state_resumes"] == 1
    assert_same_trials(whole, again)
    assert not pdir.exists()  # the state goes with its group, the parts with the search


def test_a_search_split_by_seed_reads_whole_groups_back_and_saves_each_seed(tmp_path, monkeypatch):
    # Two static groups on two tasks, as above; the first task's groups are saved whole by
    # a search stopped in the second task, then the same search goes on split by seed.
    two_static_draws(monkeypatch)
    pdir = tmp_path / "study-pending" / "jax_tune-ppo-512"
    argv = [
        "--algo", "ppo", "--suite", "v1", "--tasks", "tune-gen-easy-1000,tune-gen-medium-1001",
        "--budget", "512", "--trials", "4", "--seeds", "2", "--groups", "2",
        "--sampler-seed", "3", "--parts", str(pdir), "--out", str(tmp_path / "t.json"),
        "--hyperparams", str(tmp_path / "hp.json"),
    ]  # fmt: skip
    run, calls = jax_learners.Compiled.run, []

    def stopping_at(n):
        def call(self, candidates, seeds):
            calls.append((self.task.id, list(seeds)))
            if len(calls) == n:
                raise KeyboardInterrupt
            return run(self, candidates, seeds)

        return call

    monkeypatch.setattr(jax_learners.Compiled, "run", stopping_at(3))
    with pytest.raises(KeyboardInterrupt):
        jax_tune.main(argv)
    assert calls[-1] == ("tune-gen-medium-1001", [100, 101])  # the first two were saved whole

    split = [*argv, "--split-seeds"]
    st = jax_tune.main([*split, "--status"])
    assert [(r["task"], r["group"], r["seed"], r["status"]) for r in st["groups"]] == [
        ("tune-gen-easy-1000", 0, None, "done"),
        ("tune-gen-easy-1000", 1, None, "done"),
        ("tune-gen-medium-1001", 0, 100, "not started"),
        ("tune-gen-medium-1001", 0, 101, "not started"),
        ("tune-gen-medium-1001", 1, 100, "not started"),
        ("tune-gen-medium-1001", 1, 101, "not started"),
    ]
    assert (st["groups_done"], st["groups_total"]) == (2, 4)

    # Stopped after one seed of the first group left: that seed is saved with its group's
    # identity, and the page counts its group only once every seed is in.
    calls.clear()
    monkeypatch.setattr(jax_learners.Compiled, "run", stopping_at(2))
    with pytest.raises(KeyboardInterrupt):
        jax_tune.main(split)
    assert calls == [("tune-gen-medium-1001", [100]), ("tune-gen-medium-1001", [101])]
    st = jax_tune.main([*split, "--status"])
    assert [r["status"] for r in st["groups"]][2:] == ["done"] + ["not started"] * 3
    assert (st["done"], st["groups_done"]) == (3, 2)
    seed_part = json.loads(sorted(pdir.glob("tune-gen-medium-1001--*.json"))[0].read_text())
    assert seed_part["seed"] == 100 and len(seed_part["spl"][0]) == 1
    assert seed_part["group_ident"] != seed_part["ident"]
    (p,) = report_pending.sets_in_progress(tmp_path / "study")
    assert (p["made"], p["of"]) == (2, 4)
    buf = io.StringIO()
    jax_tune.print_status(st, buf)
    assert "(4 of them one seed of a group split by seed)" in buf.getvalue()
    assert "2 of 4 groups done" in buf.getvalue()

    # The same command trains the three seeds left, one compiled group each.
    calls.clear()
    monkeypatch.setattr(jax_learners.Compiled, "run", stopping_at(0))
    done = jax_tune.main(split)
    assert calls == [("tune-gen-medium-1001", [101]), ("tune-gen-medium-1001", [100]),
                     ("tune-gen-medium-1001", [101])]  # fmt: skip
    assert done["resumed_groups"] == 2 and not pdir.exists()
    assert done["wall_time_s"] >= seed_part["group_wall_s"]
    for tr in done["trials"]:
        assert all(len(v) == 2 for v in tr["final_score"].values())
        assert all(len(c["score"]) == 2 for c in tr["curves"].values())
    # Each seed of a split group is what that seed alone trains, seed by seed.
    medium = load_suite("v1").tuning_tasks[1]
    members = [done["trials"][i]["values"] for i in (0, 2)]  # group 0: trials 0 and 2
    for k, seed in enumerate([100, 101]):
        alone = jax_learners.train_group("ppo", medium, members, [seed], 512,
                                         load_suite("v1").checkpoints(512))  # fmt: skip
        for j, i in enumerate((0, 2)):
            assert done["trials"][i]["curves"][medium.id]["score"][k] == alone["spl"][j][0]


def test_split_by_seed_leaves_groups_saved_whole_or_part_way_whole(tmp_path):
    task = load_suite("v2").tuning_tasks[0]
    values = [
        jax_learners.check_values("ppo", {**TINY_PPO, "net_arch": arch})
        for arch in ([8], [16], [32])
    ]
    args = ("ppo", [task], values, [100, 101, 102], 512, [512], tmp_path)
    whole = jax_learners.plan_groups(*args, save_state=True)
    assert [p.split for p in whole] == [None] * 3
    # Group 0 saved whole, group 1 saved part way (a training state): both go on whole.
    whole[0].part.write_text(json.dumps({"ident": whole[0].ident}))
    whole[1].state.write_bytes(b"a state")
    split = jax_learners.plan_groups(*args, save_state=True, split_seeds=True)
    assert [(p.group, p.split) for p in split] == [(0, None), (1, None), (2, 0), (2, 1), (2, 2)]
    assert split[:2] == whole[:2]
    for k, p in enumerate(split[2:]):
        assert p.job[3] == [[100, 101, 102][k]] and p.group_ident == whole[2].ident
        assert p.ident != whole[2].ident and p.state.name.endswith(".state.npz")
    # Without a parts directory there is nothing to split into.
    assert [p.split for p in jax_learners.plan_groups(*args[:-1], split_seeds=True)] == [None] * 3

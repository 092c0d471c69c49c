"""The learner benchmark's parts: suites, learners (a user's too), Algorithm 2 through the
core, statistics, tuning, the command line."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
import sixaxis_avoid as sa
from _helpers import deep_run_env_steps
from sixaxis_avoid.benchmark import __main__ as cli
from sixaxis_avoid.benchmark import execute_run, load_suite, plan_runs, resolve, stats
from sixaxis_avoid.benchmark import hyperparams as hpmod
from sixaxis_avoid.benchmark.algorithm2 import algorithm2
from sixaxis_avoid.benchmark.learners import LearnerError, spl
from sixaxis_avoid.benchmark.longer import fmt_ci
from sixaxis_avoid.benchmark.runner import task_of
from sixaxis_avoid.benchmark.tasks import SuiteError


def write_suite(tmp_path, **changes):
    raw = json.loads(load_suite("quick").path.read_text())
    raw.update(changes)
    p = tmp_path / "s.json"
    p.write_text(json.dumps(raw))
    return p


# -- suites -----------------------------------------------------------------------------------


def test_shipped_suites_load_and_their_tasks_build():
    for name in ("quick", "v1"):
        suite = load_suite(name)
        suite.check_disjoint()
        assert len(suite.seeds) >= 2
        kinds = {t.kind for t in suite.tasks}
        assert kinds == {"scenario", "generated", "goal"}, name
        for t in suite.tasks + suite.tuning_tasks:
            d = t.describe()
            assert len(d["targets"]) == len(d["optimal_lengths"]) >= 1
            assert all(n >= 1 for n in d["optimal_lengths"])
    v1 = load_suite("v1")
    assert len(v1.seeds) >= 10
    levels = {t.spec["level"] for t in v1.tasks if t.kind == "generated"}
    assert levels == {"easy", "medium", "hard"}
    # Graded: harder levels have more clutter.
    density = {t.spec["level"]: t.describe()["density"] for t in v1.tasks if t.kind == "generated"}
    assert density["easy"] < density["medium"] < density["hard"]


def test_goal_task_targets_are_fixed_reachable_and_not_the_start():
    t = load_suite("v1").task("goal-paper_simple")
    again = load_suite("v1").task("goal-paper_simple")
    assert t.eval_targets == again.eval_targets
    assert len(set(t.eval_targets)) == len(t.eval_targets) == 8
    start = tuple(t.scenario.start)
    for cell in t.eval_targets:
        assert cell != start and sa.shortest_path(t.world(cell)) is not None


def test_bad_suites_name_the_field(tmp_path):
    with pytest.raises(SuiteError, match="unknown"):
        load_suite("no-such-suite")
    bad = write_suite(tmp_path, tasks=[{"id": "x", "kind": "maze"}])
    with pytest.raises(SuiteError, match=r"tasks\[0\]\.kind"):
        load_suite(bad)
    bad = write_suite(tmp_path, tasks=[{"id": "x", "kind": "generated"}])
    with pytest.raises(SuiteError, match=r"tasks\[0\]\.seed"):
        load_suite(bad)
    overlap = write_suite(
        tmp_path,
        tuning={
            "seeds": [1],
            "tasks": [{"id": "t", "kind": "scenario", "scenario": "paper_simple"}],
        },
    )
    with pytest.raises(SuiteError, match="disjoint"):
        load_suite(overlap).check_disjoint()


# -- learners ---------------------------------------------------------------------------------


def test_spl():
    assert spl(None, 5) == 0.0
    assert spl([(0, 0, 0)] * 6, 5) == 1.0
    assert spl([(0, 0, 0)] * 11, 5) == 0.5


def test_runs_go_to_the_cores_seed_by_seed(tmp_path):
    from sixaxis_avoid.benchmark import runner

    suite = load_suite("quick")
    specs = plan_runs(suite, ["bfs", "q_assist"], seeds=[2, 0])
    assert [s["seed"] for s in specs[:2]] == [2, 0]  # planned learner, task, seed
    order = runner.seed_major(specs)
    n = len(specs) // 2
    assert {s["seed"] for s in order[:n]} == {2} and {s["seed"] for s in order[n:]} == {0}
    assert order[:n] == [s for s in specs if s["seed"] == 2]  # otherwise in planned order
    # run_study hands them over in that order (here in-process, one after another), and
    # skips the finished ones.
    got: list[int] = []
    bfs = [s for s in specs if s["learner"] == "bfs"]
    runner.run_study(bfs[:1], tmp_path, use_ray=False, progress=False)
    runner.run_study(
        bfs, tmp_path, use_ray=False, progress=False, on_result=lambda r: got.append(r["spec"])
    )
    assert got == [s for s in runner.seed_major(bfs) if s is not bfs[0]]


def test_resolve_builtin_and_user_learners():
    assert resolve("ppo").family == "deep" and resolve("q_assist").family == "native"
    assert resolve("bench_user_learner:ScriptedBFS").__name__ == "ScriptedBFS"
    with pytest.raises(LearnerError, match="not built in"):
        resolve("sarsa")
    with pytest.raises(LearnerError, match="cannot import"):
        resolve("no_such_module_xyz:Learner")
    with pytest.raises(LearnerError, match="not a class"):
        resolve("json:dumps")


def test_user_learner_runs_and_its_steps_are_counted():
    suite = load_suite("quick")
    spec = plan_runs(
        suite, ["bench_user_learner:ScriptedBFS"], seeds=[0], tasks=[suite.task("paper_simple")]
    )[0]
    rec = execute_run(spec)
    res = rec["result"]
    assert res["env_steps"] == spec["budget"] and res["score"] == 1.0
    # It walks the 9-move optimum: the first episode reaches the target at step 9.
    assert res["first_success"] == {"env_steps": 9, "episode": 0}
    assert res["episodes"] == spec["budget"] // 9
    assert [p["env_steps"] for p in res["curve"]][:-1] == [
        c for c in spec["checkpoints"] if c <= spec["budget"]
    ][: len(res["curve"]) - 1]
    assert res["convergence"] == {"env_steps": res["curve"][0]["env_steps"]}


def test_native_learner_curve_is_the_core_run():
    """The native learner's final path and step count are sixaxis_avoid.train's."""
    suite = load_suite("quick")
    task = suite.task("gen-easy-0")
    spec = plan_runs(suite, ["q_assist"], seeds=[3], tasks=[task])[0]
    res = execute_run(spec)["result"]
    core = sa.train(task.scenario, seed=3, assist=True, episodes=spec["hyperparams"]["episodes"])
    assert res["env_steps"] == core.total_steps
    assert res["paths"][0] == (None if core.path is None else [list(c) for c in core.path])
    assert res["core_converged_episode"] == core.converged_episode
    assert len(res["curve"]) >= 3


def test_deep_learner_is_deterministic_per_seed():
    suite = load_suite("quick")
    spec = plan_runs(suite, ["dqn"], seeds=[1], tasks=[suite.task("paper_simple")])[0]
    assert execute_run(spec)["result"] == execute_run(spec)["result"]


def test_a_budget_is_a_cap_on_whole_iterations():
    from sixaxis_avoid.benchmark.learners import whole_iterations

    assert whole_iterations(30_000, 1024) == 29_696  # 29 PPO rollouts of 16 x 64
    assert whole_iterations(30_000, 1) == 30_000 and whole_iterations(30_000, 8) == 30_000
    assert whole_iterations(30_001, 8) == 30_000
    assert whole_iterations(500, 1024) == 1024  # one iteration alone is larger: it runs
    # An SB3 run ends on the last whole rollout within its budget: 2 envs x 64 steps on a
    # budget of 300 env steps trains two rollouts (256 steps), not three (384).
    suite = load_suite("quick")
    spec = plan_runs(suite, ["ppo"], seeds=[0], tasks=[suite.task("paper_simple")])[0]
    spec = {
        **spec,
        "budget": 300,
        "checkpoints": [300],
        "hyperparams": {**spec["hyperparams"], "n_envs": 2, "n_steps": 64, "batch_size": 64},
    }
    assert execute_run(spec)["result"]["env_steps"] == 256


@pytest.mark.parametrize(
    "learner, task_id",
    [("ppo", "paper_simple"), ("dqn", "paper_simple"), ("dqn", "goal-paper_simple")],
)
def test_sb3_learners_train_on_the_native_vec_env_as_on_dummy_vec_env(learner, task_id):
    """The SB3 learners train on the native SixAxisVecEnv (the run file says so), and
    training on it is the same as on the DummyVecEnv of ctx.make_env envs they used before:
    the same network weights, curve (greedy paths at the checkpoints), step and episode
    counts and first success."""
    import torch
    from sixaxis_avoid.benchmark.learners import RunContext
    from stable_baselines3.common.vec_env import DummyVecEnv

    class DummyContext(RunContext):
        def make_vec_env(self, n_envs, **kw):
            return DummyVecEnv([lambda: self.make_env(**kw)] * n_envs)

    suite = load_suite("quick")
    spec = plan_runs(suite, [learner], seeds=[1], tasks=[suite.task(task_id)], budget_scale=3)[0]
    trained = {}
    for cls in (RunContext, DummyContext):
        model = resolve(learner)(spec["hyperparams"])
        ctx = cls(task_of(spec), 1, spec["budget"], model.hyperparams, spec["checkpoints"], model)
        model.learn(ctx)
        ctx.finish()
        trained[model.vec_env] = (model, ctx)
    (native, c1), (dummy, c2) = trained["SixAxisVecEnv"], trained["DummyVecEnv"]
    assert c1.env_steps == c2.env_steps == deep_run_env_steps(spec) <= spec["budget"]
    assert c1.episodes == c2.episodes > 0
    first = [
        c.first_success and {k: c.first_success[k] for k in ("env_steps", "episode")}
        for c in (c1, c2)
    ]
    assert first[0] == first[1]
    untimed = [
        [{k: p[k] for k in ("env_steps", "score", "paths")} for p in c.points] for c in (c1, c2)
    ]
    assert untimed[0] == untimed[1] and len(untimed[0]) >= 3
    weights = native.model.policy.state_dict()
    assert weights.keys() == dummy.model.policy.state_dict().keys()
    for name, w in dummy.model.policy.state_dict().items():
        assert torch.equal(weights[name], w), name
    # Training changed the weights (the comparison above is not of two fresh networks).
    fresh = resolve(learner)(spec["hyperparams"])
    ctx = RunContext(task_of(spec), 1, 0, fresh.hyperparams, [], fresh)
    fresh.learn(ctx)
    assert any(not torch.equal(weights[k], w) for k, w in fresh.model.policy.state_dict().items())
    assert execute_run(spec)["result"]["vec_env"] == "SixAxisVecEnv"


# -- Algorithm 2 through the core ---------------------------------------------------------------


def test_algorithm2_native_is_the_core_plan():
    s = sa.Scenario("replan_clutter")
    ours = algorithm2(s, seed=0, learner="qlearning", episodes=2000, assist=True)
    core = sa.plan(s, seed=0, episodes=2000, assist=True)
    assert (ours.success, ours.replans, ours.path) == (core.success, core.replans, core.path)


def test_algorithm2_bfs_runs_through_the_core_loop():
    s = sa.Scenario("replan_clutter")
    r = algorithm2(s, seed=0, learner="bfs")
    assert r.success and r.replans >= 1


def test_algorithm2_user_learner_matches_bfs_through_the_core():
    """A user's learner that returns BFS paths gives the core's BFS result: the loop is the
    core's, round 0 reuses the run's path, re-plans retrain a fresh learner."""
    suite = load_suite("quick")
    task_spec = {"id": "replan_clutter", "kind": "scenario", "scenario": "replan_clutter"}
    spec = plan_runs(suite, ["bench_user_learner:ScriptedBFS"], seeds=[0])[0]
    spec["task"] = task_spec
    spec["max_replans"] = 20
    alg2 = execute_run(spec)["result"]["algorithm2"]
    core = sa.plan(sa.Scenario("replan_clutter"), seed=0, learner="bfs", max_replans=20)
    assert alg2["success"] == core.success
    assert alg2["replans"] == core.replans >= 1
    assert alg2["added_obstacles"] == [list(c) for c in core.added_obstacles]


# -- statistics ---------------------------------------------------------------------------------


def test_aggregates_on_known_scores():
    rng = np.random.default_rng(0)
    good = np.clip(rng.normal(0.8, 0.05, size=(10, 4)), 0, 1)
    bad = np.clip(rng.normal(0.2, 0.05, size=(10, 4)), 0, 1)
    a = stats.aggregates({"good": good, "bad": bad}, reps=200)
    g = a["learners"]["good"]
    assert g["iqm_ci"][0] <= g["iqm"] <= g["iqm_ci"][1]
    assert abs(g["mean"] - good.mean()) < 1e-12
    assert a["poi"]["good,bad"]["p"] == 1.0 and a["poi"]["bad,good"]["p"] == 0.0
    assert g["profile"][0] == 1.0 and a["learners"]["bad"]["profile"][-1] == 0.0
    # Seeded: the same intervals again.
    assert stats.aggregates({"good": good, "bad": bad}, reps=200) == a
    # Each learner and pair draws from its own stream: a third learner's runs move nobody
    # else's interval, profile band or probability of improvement.
    mid = np.clip(rng.normal(0.5, 0.2, size=(10, 4)), 0, 1)
    b = stats.aggregates({"mid": mid, "good": good, "bad": bad}, reps=200)
    assert b["learners"]["good"] == g and b["learners"]["bad"] == a["learners"]["bad"]
    assert b["poi"]["good,bad"] == a["poi"]["good,bad"]
    assert stats.aggregates({"good": good}, reps=200)["learners"]["good"] == g
    assert g["seeds"] == 10 and "[" in fmt_ci(g, "iqm")


def test_one_seed_per_task_is_reported_without_an_interval():
    # A stratified bootstrap over one run per task resamples nothing: its "CI" is the point.
    one = stats.aggregates({"x1": np.array([[0.0, 1.0, 0.5]]), "long": np.ones((1, 3))}, reps=50)
    g = one["learners"]["x1"]
    assert g["seeds"] == 1 and g["iqm_ci"][0] == g["iqm_ci"][1]
    assert fmt_ci(g, "mean") == "0.50 (1 seed: no CI)"
    # The IQM figure draws no bar for it and says so in its title.
    from sixaxis_avoid.benchmark.report import iqm_figure_title

    assert iqm_figure_title({"learners": ["x1", "long"], "agg": one}).endswith(
        "; x1, long: 1 seed, point only"
    )
    ten = stats.aggregates({"x1": np.ones((2, 3))}, reps=50)
    assert "point only" not in iqm_figure_title({"learners": ["x1"], "agg": ten})


def test_report_header_names_every_command_that_filled_the_study():
    from sixaxis_avoid.benchmark.report import provenance, report_command, study_commands

    one = {"command": "run A", "date": "D", "machine": "M"}
    assert study_commands(one) == ["run A"] and provenance(one) == "Run D on M"
    many = {**one, "command": "run C", "commands": ["run A", "run B", "run C"]}
    assert study_commands(many) == ["run A", "run B", "run C"]
    assert provenance(many).startswith("Filled by 3 `run` commands")
    assert provenance(many).endswith("the last ended D on M")
    timed = {**one, "wall_time_s_total": 3042.4}
    assert provenance(timed) == "Run D on M in 51 min of wall time"
    assert provenance({**many, "wall_time_s_total": 600.0}).endswith(
        "the last ended D on M; the commands took 10 min of wall time in all"
    )
    a = {"manifest": {"suite": {"name": "v1"}}, "results_dir": "docs/results/v1"}
    assert report_command(a).endswith("report --results docs/results/v1")
    a["longer"] = [{"dir": "x4"}, {"dir": "x10"}]
    assert report_command(a).endswith("--results docs/results/v1 --longer x4 --longer x10")


def test_report_says_which_machines_the_runs_ran_on():
    from sixaxis_avoid.benchmark.report import run_machines

    def run(machine):
        return {"host": {} if machine is None else {"machine": machine}}

    assert run_machines([run(None), run(None)]) == ""  # files from before the field
    assert run_machines([run("AMD EPYC"), run("AMD EPYC")]) == "Every run ran on AMD EPYC."
    mixed = run_machines([run("AMD EPYC"), run("Intel Xeon"), run("AMD EPYC"), run(None)])
    assert mixed.startswith("Runs per machine: AMD EPYC: 2; Intel Xeon: 1; not recorded")
    assert "compare its runs from one machine" in mixed


def test_a_run_records_its_machine_and_versions():
    from sixaxis_avoid.benchmark.runner import execute_run, machine

    suite = load_suite("quick")
    rec = execute_run(plan_runs(suite, ["bfs"], seeds=[0])[0])
    assert rec["host"]["machine"] == machine() and "cores" in machine()
    assert rec["host"]["versions"]["sixaxis_avoid"] and "numpy" in rec["host"]["versions"]


def test_a_longer_figure_name_stays_short_with_many_changes():
    from sixaxis_avoid.benchmark.longer import figure_name

    one = {"scale": 10.0, "learners": {"ppo": {"changed": {"lr_schedule": "linear"}}}}
    assert figure_name(one) == "longer_x10_ppo_lr_schedule_linear"
    many = {k: 0.000294916935807158 for k in ("learning_rate", "gamma", "batch_size", "buffer")}
    a = {"scale": 1.0, "learners": {"qrdqn": {"changed": many}}}
    b = {"scale": 1.0, "learners": {"qrdqn": {"changed": {**many, "gamma": 0.5}}}}
    assert len(figure_name(a)) <= 60 and figure_name(a) != figure_name(b)
    assert figure_name(a).startswith("longer_x1_qrdqn_")


def test_curve_on_is_a_step_function():
    curve = [{"env_steps": 10, "score": 0.5}, {"env_steps": 100, "score": 1.0}]
    got = stats.curve_on(np.array([1, 10, 50, 100, 1000]), curve)
    assert got.tolist() == [0.0, 0.5, 0.5, 1.0, 1.0]


def test_plateau_reads_each_run_at_a_quarter_half_and_end():
    from sixaxis_avoid.benchmark.stats import plateau

    def run(learner, curve):
        pts = [{"env_steps": x, "score": y} for x, y in curve]
        return {"spec": {"learner": learner}, "result": {"curve": pts}}

    runs = [
        run("flat", [(10, 1.0), (50, 1.0), (100, 1.0)]),  # optimal from the start
        run("late", [(10, 0.0), (50, 0.0), (80, 0.5), (100, 1.0)]),  # rises after half
        run("late", [(10, 0.0), (30, 1.0), (100, 1.0)]),  # flat after a quarter
        run("lost", [(10, 0.0), (30, 1.0), (70, 0.5), (100, 0.0)]),  # found, then lost
    ]
    got = plateau(runs, ["flat", "late", "lost"])
    assert got["flat"] == {
        "runs": 1, "quarter": 1.0, "half": 1.0, "end": 1.0, "changed_late": 0.0,
        "best": 1.0, "fell_from_best": 0.0,
    }  # fmt: skip
    assert got["late"]["runs"] == 2
    assert got["late"]["quarter"] == pytest.approx(0.0)  # 25 steps: both still at 0
    assert got["late"]["half"] == pytest.approx(0.5)  # 50 steps: 0 and 1
    assert got["late"]["end"] == pytest.approx(1.0)
    assert got["late"]["changed_late"] == pytest.approx(0.5)
    assert got["late"]["best"] == 1.0 and got["late"]["fell_from_best"] == 0.0
    assert got["lost"] == {
        "runs": 1, "quarter": 0.0, "half": 1.0, "end": 0.0, "changed_late": 1.0,
        "best": 1.0, "fell_from_best": 1.0,
    }  # fmt: skip


def test_dqn_search_space_keeps_the_replay_ratio_at_most_one_half():
    import optuna

    for learner in ("dqn", "qrdqn"):  # one study per learner, as `tune` makes them
        study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
        for _ in range(40):
            hp = hpmod.suggest(study.ask(), learner)
            assert hp["gradient_steps"] / hp["train_freq"] <= 0.5
            assert hp["gradient_steps"] >= 1 and hp["train_freq"] >= 2


def test_qrdqn_search_space_is_bounded_in_compute():
    import optuna

    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=1))
    drawn = set()
    for _ in range(60):
        hp = hpmod.suggest(study.ask(), "qrdqn")
        assert max(hp["net_arch"]) <= 128 and hp["batch_size"] <= 128
        assert hp["n_quantiles"] in (10, 25)
        drawn.add((tuple(hp["net_arch"]), hp["batch_size"], hp["n_quantiles"]))
    assert len(drawn) >= 8  # the bound narrows the space; it does not pin it
    dqn = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=1))
    nets = {tuple(hpmod.suggest(dqn.ask(), "dqn")["net_arch"]) for _ in range(60)}
    assert (256, 256) in nets  # DQN's space keeps its widest net


# -- hyperparameters and tuning -----------------------------------------------------------------


def test_shipped_hyperparams_are_tuned_with_provenance_and_run_reads_the_file(tmp_path):
    data = hpmod.load("v1")
    assert data["status"] == "tuned" and "PLACEHOLDER" not in data["note"]
    tuning_tasks = {t.id for t in load_suite("v1").tuning_tasks}
    reported = {t.id for t in load_suite("v1").tasks}
    for lr in hpmod.TUNABLE:
        assert hpmod.status_for(data, lr) == "tuned"
        t = data["learners"][lr]["tuning"]
        assert t["command"].startswith("python -m sixaxis_avoid.benchmark tune --suite v1")
        assert t["trials"] >= 6 and 0.0 < t["best_value"] <= 1.0
        assert set(t["tasks"]) == tuning_tasks and not tuning_tasks & reported
    suite = load_suite("quick")
    spec = plan_runs(suite, ["ppo"], seeds=[0])[0]
    assert spec["hyperparams_status"] == "tuned"
    assert (
        spec["hyperparams"]["learning_rate"] == data["learners"]["ppo"]["values"]["learning_rate"]
    )
    hp_file = tmp_path / "hp.json"
    hpmod.record_tuning(hp_file, "ppo", {"ent_coef": 0.123}, {"command": "x", "trials": 1})
    spec = plan_runs(suite, ["ppo"], seeds=[0], hyperparams=hp_file)[0]
    assert spec["hyperparams_status"] == "tuned"
    assert spec["hyperparams"]["ent_coef"] == 0.123
    assert "PLACEHOLDER" not in json.loads(hp_file.read_text())["note"]


def test_tune_writes_the_chosen_values_with_command_and_trials(tmp_path):
    out = tmp_path / "hp.json"
    argv = [
        "tune", "--suite", "quick", "--learners", "a2c", "--trials", "2", "--no-ray",
        "--no-progress", "--out", str(out), "--log-dir", str(tmp_path / "log"),
    ]  # fmt: skip
    assert cli.main(argv) == 0
    data = json.loads(out.read_text())
    entry = data["learners"]["a2c"]
    assert entry["status"] == "tuned" and entry["tuning"]["trials"] == 2
    assert entry["tuning"]["command"].startswith("python -m sixaxis_avoid.benchmark tune")
    assert entry["tuning"]["tasks"] == ["tune-gen-medium-1000"]
    assert 0.0 <= entry["tuning"]["best_value"] <= 1.0
    assert {"learning_rate", "n_steps", "n_envs"} <= set(entry["values"])


# -- command line -------------------------------------------------------------------------------


def test_cli_list_and_errors(capsys):
    assert cli.main(["list", "--suite", "quick", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert [t["id"] for t in listed["tasks"]] == [t.id for t in load_suite("quick").tasks]
    assert set(listed["learners"]) == {
        "q_assist",
        "q_plain",
        "q_paper",
        "bfs",
        "dqn",
        "qrdqn",
        "ppo",
        "a2c",
    }
    assert cli.main(["run", "--suite", "quick", "--learners", "sarsa", "--no-ray"]) == 2
    assert "sarsa" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        cli.main(["run", "--budget-scale", "0"])
    assert cli.parse_seeds("3") == [0, 1, 2] and cli.parse_seeds("4,7") == [4, 7]
    assert cli.parse_seeds("0,") == [0] and cli.parse_seeds(" 5, ") == [5]
    for bad, says in (("0", "seed 0 alone is --seeds 0,"), ("two", "'two'"), ("1,-2", "'1,-2'")):
        with pytest.raises(SystemExit, match=says):
            cli.parse_seeds(bad)


def test_regenerated_report_keeps_sections_other_scripts_own(tmp_path):
    from sixaxis_avoid.benchmark.report import keep_other_sections

    out = tmp_path / "B.md"
    out.write_text(
        "old\n<!-- benchmark-aggregate:begin -->\nold table\n<!-- benchmark-aggregate:end -->\n"
        "<!-- jax-twin:begin -->\n## JAX twin\nkept\n<!-- jax-twin:end -->\n"
    )
    new = "new\n<!-- benchmark-aggregate:begin -->\nnew table\n<!-- benchmark-aggregate:end -->\n"
    text = keep_other_sections(out, new)
    assert "new table" in text and "old table" not in text
    assert text.endswith("<!-- jax-twin:begin -->\n## JAX twin\nkept\n<!-- jax-twin:end -->\n")
    assert keep_other_sections(tmp_path / "missing.md", new) == new


# -- SB3 PPO with rejax's implementation ------------------------------------------------------


def test_ppo_implementation_rejax_is_one_preset_and_v2_uses_it_with_jax_ppos_values():
    """The hyperparameter ``implementation: rejax`` is rejax 0.1.3's PPO in SB3 (LeCun init,
    actor and critic clipped each on its own, truncation as termination, value clipping at
    clip_range); suite v2's SB3 PPO at 30k runs jax_ppo's values with it, and a setting that
    contradicts the preset is an error."""
    from sixaxis_avoid.benchmark.learners import (
        PPO_IMPLEMENTATIONS,
        check_implementation,
        expand_implementation,
    )

    hp = expand_implementation("ppo", {"clip_range": 0.3, "implementation": "rejax"})
    assert hp == {
        "clip_range": 0.3,
        "init": "lecun",
        "grad_clip": "per_network",
        "bootstrap_truncated": False,
        "clip_range_vf": 0.3,
    }
    assert expand_implementation("ppo", {"init": "lecun"}) == {"init": "lecun"}  # no preset
    assert check_implementation("ppo", {}) == PPO_IMPLEMENTATIONS["sb3"]
    with pytest.raises(LearnerError, match="contradicts implementation 'rejax'"):
        expand_implementation("ppo", {"implementation": "rejax", "init": "orthogonal"})
    with pytest.raises(LearnerError, match="implementation: 'cleanrl'"):
        expand_implementation("ppo", {"implementation": "cleanrl"})
    with pytest.raises(LearnerError, match="init: 'xavier'"):
        check_implementation("ppo", {"init": "xavier"})
    data = json.loads(hpmod.hyperparams_path("v2").read_text())["learners"]
    ppo = data["ppo"]["by_budget"]["30000"]["values"]
    jax = data["jax_ppo"]["by_budget"]["30000"]["values"]
    assert ppo.pop("implementation") == "rejax"
    # jax_ppo's values in SB3's names (SB3's MlpPolicy is tanh, as jax_ppo's activation).
    assert ppo == {k: v for k, v in jax.items() if k != "activation"}
    assert jax["activation"] == "tanh"
    suite = load_suite("v2")
    task = [suite.task("paper_simple")]
    spec = plan_runs(suite, ["ppo"], seeds=[0], tasks=task, hyperparams="v2", budgets=[30000])
    assert spec[0]["hyperparams"]["implementation"] == "rejax"


def test_ppo_rejax_settings_reach_the_sb3_model():
    """``implementation: rejax`` builds SB3 PPO with LeCun-initialised layers (zero biases,
    variance 1/fan_in, truncated at 2 standard deviations), one Adam whose two parameter
    groups (actor, critic) are clipped each on its own with SB3's joint clip off, SB3's value
    clipping, and a VecEnv whose infos carry no TimeLimit.truncated flag."""
    import torch
    from sixaxis_avoid.benchmark.learners import RunContext, lecun_init

    suite = load_suite("quick")
    spec = plan_runs(suite, ["ppo"], seeds=[0], tasks=[suite.task("paper_simple")])[0]
    hp = {**spec["hyperparams"], "n_envs": 2, "n_steps": 64, "batch_size": 64}
    hp.update(implementation="rejax", clip_range=0.3, max_grad_norm=0.5)
    learner = resolve("ppo")(hp)
    ctx = RunContext(task_of(spec), 0, 0, learner.hyperparams, [], learner)
    learner.learn(ctx)
    model = learner.model
    assert model.max_grad_norm == float("inf")
    assert model.clip_range_vf(1.0) == 0.3
    assert type(model.get_env()).__name__ == "TruncationAsTermination"
    opt = model.policy.optimizer
    assert type(opt).__name__ == "GroupClippedAdam" and len(opt.param_groups) == 2
    grouped = [p for g in opt.param_groups for p in g["params"]]
    assert {id(p) for p in grouped} == {id(p) for p in model.policy.parameters()}
    critic = {id(p) for p in model.policy.value_net.parameters()}
    assert critic <= {id(p) for p in opt.param_groups[1]["params"]}
    assert model.policy.ortho_init is False  # LeCun instead (checked below on fresh layers)
    net = torch.nn.Sequential(torch.nn.Linear(13, 256), torch.nn.Tanh(), torch.nn.Linear(256, 6))
    lecun_init(net)
    for m in (net[0], net[2]):
        std = (1.0 / m.in_features) ** 0.5 / 0.87962566103423978
        assert torch.all(m.bias == 0)
        assert m.weight.abs().max() <= 2 * std + 1e-6
        # variance 1/fan_in (jax's lecun_normal), within sampling error
        assert abs(float(m.weight.detach().var()) * m.in_features - 1.0) < 0.15
    # SB3's own: orthogonal weights, the policy head at gain 0.01.
    plain = resolve("ppo")({**hp, "implementation": "sb3", "clip_range_vf": None})
    plain.learn(RunContext(task_of(spec), 0, 0, plain.hyperparams, [], plain))
    assert plain.model.max_grad_norm == 0.5
    assert plain.model.policy.action_net.weight.abs().max() < 0.05
    assert type(plain.model.policy.optimizer) is torch.optim.Adam


def test_a_replan_round_whose_obstacles_block_the_target_or_start_has_no_path():
    """Algorithm 2 with a deep learner: when a re-plan round's new obstacles leave its target
    or its start blocked (the core's scenario check names the field ``target`` or
    ``start``), that round has no path and nothing is trained (Algorithm 2 fails there)
    instead of the error ending the whole study. Any other invalid field still raises."""
    from sixaxis_avoid.benchmark.learners import Learner, RetrainPerRound, RunContext

    class Untrained(Learner):
        name = "untrained"

        def learn(self, ctx):  # pragma: no cover - a blocked round trains nothing
            raise AssertionError("a round with a blocked target is not trained")

        def greedy_path(self, world):  # pragma: no cover
            raise AssertionError("no path is asked for after a refused round")

    base = load_suite("v2").task("paper_simple-50mm").scenario
    d = base.to_dict()
    t = d["target"]

    class Round:
        """A re-plan round as the core hands it over: its fields, and the core's check of
        them (here the real check of this dict: an obstacle next to the target, within the
        96 mm terminal_safe_distance on the 50 mm grid)."""

        def __init__(self, obstacle, **fields):
            self.d = {**d, "obstacles": [*d["obstacles"], obstacle], **fields}
            self.start, self.target = d["start"], d["target"]
            self.obstacles = self.d["obstacles"]

        def validate(self):
            sa.Scenario.from_dict(self.d)

    ctx = RunContext(SimpleNamespace(scenario=base), 0, 1000, {}, [], Untrained())
    s0 = d["start"]
    # A path cell next to the target, then next to the start (jax_dqn at 300k met the
    # second on gen-medium-0-50mm): no env, no path.
    for cell, field in (([t[0] + 1, *t[1:]], "target"), ([s0[0] + 1, *s0[1:]], "start")):
        got = RetrainPerRound(ctx.learner, ctx).learn_path(Round(cell), 0)
        assert got["path"] is None and got["total_steps"] == 0
        assert got["reason"].startswith("the points added so far leave no env to learn in")
        assert f"`{field}`" in got["reason"] and "terminal_safe_distance" in got["reason"]
    with pytest.raises(sa.ScenarioError, match="terminal_safe_distance"):
        RetrainPerRound(ctx.learner, ctx).learn_path(
            Round([t[0] + 1, *t[1:]], terminal_safe_distance=-1.0), 0
        )
    # The JAX learners' rounds (jax_runs) refuse the same worlds before compiling anything.
    from sixaxis_avoid.benchmark.jax_runs import _Replan

    replan = _Replan("dqn", SimpleNamespace(scenario=base), {}, 1000, path=[])
    for cell, field in (([t[0] + 1, *t[1:]], "target"), ([s0[0] + 1, *s0[1:]], "start")):
        got = replan.learn_path(Round(cell), 0)
        assert got["path"] is None and got["total_steps"] == 0 and f"`{field}`" in got["reason"]


def test_dqn_implementation_rejax_runs_train_freq_envs_and_v2_uses_it_with_jax_dqns_values():
    """``implementation: rejax`` for SB3 DQN: LeCun init, truncation as termination, no HER,
    and rejax's ``train_freq`` envs stepped once between update phases (SB3 gets n_envs =
    train_freq, train_freq 1); suite v2's SB3 DQN at 30k runs jax_dqn's values with it."""
    from sixaxis_avoid.benchmark.learners import (
        DQN,
        DQN_IMPLEMENTATIONS,
        check_implementation,
        expand_implementation,
    )

    hp = DQN().expand_hyperparams(
        {"train_freq": 16, "gradient_steps": 4, "implementation": "rejax"}
    )
    assert (hp["n_envs"], hp["train_freq"], hp["gradient_steps"]) == (16, 1, 4)
    assert {k: hp[k] for k in DQN_IMPLEMENTATIONS["rejax"]} == DQN_IMPLEMENTATIONS["rejax"]
    assert DQN().expand_hyperparams({"train_freq": 16}) == {"train_freq": 16}  # SB3's own
    assert check_implementation("dqn", {}) == DQN_IMPLEMENTATIONS["sb3"]
    with pytest.raises(LearnerError, match="n_envs: 4 with train_freq_as_envs"):
        DQN().expand_hyperparams({"n_envs": 4, "train_freq_as_envs": True})
    with pytest.raises(LearnerError, match="her: 'yes' is not one of"):
        check_implementation("dqn", {"her": "yes"})
    with pytest.raises(LearnerError, match="contradicts implementation 'rejax'"):
        expand_implementation("dqn", {"implementation": "rejax", "her": True})
    data = json.loads(hpmod.hyperparams_path("v2").read_text())["learners"]
    dqn = data["dqn"]["by_budget"]["30000"]["values"]
    jax = data["jax_dqn"]["by_budget"]["30000"]["values"]
    assert dqn.pop("implementation") == "rejax"
    # jax_dqn's values in SB3's names (SB3's DQN is ReLU, as jax_dqn's activation).
    assert dqn == {k: v for k, v in jax.items() if k != "activation"}
    assert jax["activation"] == "relu"


def test_dqn_rejax_implementation_trains_on_a_goal_task_without_her(tmp_path):
    """The preset reaches the model: 16 native envs with train_freq 1, plain replay on a goal
    task; and its init gives LeCun weights, zero biases and a target net that copies them."""
    from sixaxis_avoid.benchmark.learners import DQN, RunContext

    task = load_suite("v2").task("goal-paper_simple")
    hp = {**DQN.defaults, "implementation": "rejax", "train_freq": 16, "gradient_steps": 1,
          "learning_starts": 0, "buffer_size": 2000}  # fmt: skip
    learner = DQN(hp)
    ctx = RunContext(task, 0, 640, learner.hyperparams, [640], learner)
    learner.learn(ctx)
    model = learner.model
    assert model.n_envs == 16 and model.train_freq.frequency == 1
    assert type(model.replay_buffer).__name__ == "DictReplayBuffer"  # not HerReplayBuffer
    assert learner.vec_env == "SixAxisVecEnv"
    assert type(model.env).__name__ == "TruncationAsTermination"  # no bootstrap on truncation
    # The init on a fresh model: LeCun weights, zero biases, the target net a copy.
    fresh = type(model)("MultiInputPolicy", model.env, seed=1, device="cpu")
    learner.after_model({"init": "lecun"}, fresh)
    q, target = fresh.policy.q_net, fresh.policy.q_net_target
    for (name, a), b in zip(q.named_parameters(), target.parameters()):
        assert (a == b).all()
        if name.endswith("bias"):
            assert (a == 0).all()


def test_dqn_squared_loss_is_half_the_squared_td_error_where_sb3s_is_huber():
    """``loss: squared`` (rejax's ``optax.l2_loss``) replaces SB3 DQN's Huber loss: on the
    same replay sample, the recorded loss is half the mean squared TD error against the
    target net's max, and it differs from SB3's own where TD errors pass 1."""
    import torch
    from sixaxis_avoid.benchmark.learners import squared_error_updates
    from sixaxis_avoid.sb3 import SixAxisVecEnv
    from stable_baselines3 import DQN as SB3DQN
    from stable_baselines3.common.logger import Logger

    vec = SixAxisVecEnv(4, seed=0, reward_scale=1e-4, max_episode_steps=50)
    model = SB3DQN("MlpPolicy", vec, learning_starts=10_000, seed=0, device="cpu")
    model.set_logger(Logger(None, []))
    model.learn(400)  # fills the replay buffer, no update yet

    def expected(batch):
        with torch.no_grad():
            next_q = model.q_net_target(batch.next_observations).max(dim=1).values
            target = batch.rewards + (1 - batch.dones) * model.gamma * next_q.reshape(-1, 1)
            q = torch.gather(model.q_net(batch.observations), 1, batch.actions.long())
            return float(0.5 * ((q - target) ** 2).mean()), float((q - target).abs().max())

    np.random.seed(7)  # noqa: NPY002 - SB3 replay buffers sample from the global RNG
    want, worst = expected(model.replay_buffer.sample(32))
    model.learning_rate, model.lr_schedule = 0.0, lambda _: 0.0  # measure, do not move
    np.random.seed(7)  # noqa: NPY002 - SB3 replay buffers sample from the global RNG
    model.train(1, 32)
    huber = model.logger.name_to_value["train/loss"]
    squared_error_updates(model)
    np.random.seed(7)  # noqa: NPY002 - SB3 replay buffers sample from the global RNG
    model.train(1, 32)
    assert model.logger.name_to_value["train/loss"] == pytest.approx(want, rel=1e-5)
    assert worst > 1 and huber < want  # the rewards scaled by 1e-4 still give TD errors > 1


def bfs_run_command(tmp_path, monkeypatch, at_call, act):
    """A `run` command of the quick suite's bfs runs (2 seeds, in-process) into
    ``tmp_path/bfs``, with ``act(out_dir)`` called as its run number ``at_call`` starts:
    ``(out_dir, argv, the specs run so far, the real execute_run)``."""
    from sixaxis_avoid.benchmark import runner

    out = tmp_path / "bfs"
    argv = ["run", "--suite", "quick", "--learners", "bfs", "--seeds", "2", "--no-ray"]
    argv += ["--no-progress", "--out-dir", str(out)]
    real, calls = runner.execute_run, []

    def hooked(spec):
        calls.append(spec)
        if len(calls) == at_call:
            act(out)
        return real(spec)

    monkeypatch.setattr(runner, "execute_run", hooked)
    return out, argv, calls, real


def test_a_stopped_run_command_keeps_its_wall_time_and_the_next_one_adds_to_it(
    tmp_path, monkeypatch
):
    """`run` rewrites study.json after each finished run (finished: false), so a command
    stopped part way (here by an interrupt in its third run) leaves its runs and its wall time
    on record; the same command again runs only the rest, adds its own wall time and ends
    with finished: true."""
    from sixaxis_avoid.benchmark import runner

    def interrupt(_out):
        raise KeyboardInterrupt

    out, argv, _, real = bfs_run_command(tmp_path, monkeypatch, 3, interrupt)
    with pytest.raises(KeyboardInterrupt):
        cli.main(argv)
    stopped = json.loads((out / "study.json").read_text())
    assert stopped["finished"] is False and stopped["ran_now"] == 2
    assert stopped["skipped_now"] == 0 and len(list((out / "runs").glob("*.json"))) == 2
    assert 0 < stopped["wall_time_s_now"] == stopped["wall_time_s_total"]

    monkeypatch.setattr(runner, "execute_run", real)
    assert cli.main(argv) == 0
    done = json.loads((out / "study.json").read_text())
    total = done["runs"]
    assert done["finished"] is True and done["skipped_now"] == 2
    assert done["ran_now"] == total - 2 and len(list((out / "runs").glob("*.json"))) == total
    assert done["wall_time_s_total"] == pytest.approx(
        stopped["wall_time_s_total"] + done["wall_time_s_now"]
    )
    assert done["commands"] == stopped["commands"] and len(done["commands"]) == 1


def test_a_run_command_stopped_on_request_finishes_its_run_and_exits_75(tmp_path, monkeypatch):
    """`touch OUT_DIR/STOP` during a command's second run: that run finishes and writes its
    file, no other starts, study.json says finished: false, the request file is removed and
    the status is 75 (sysexits' EX_TEMPFAIL); a stale request at a command's start is
    removed, and the same command then runs the rest."""
    from sixaxis_avoid.benchmark import runner

    def ask_to_stop(out):
        (out / runner.STOP_FILE).touch()

    out, argv, calls, _ = bfs_run_command(tmp_path, monkeypatch, 2, ask_to_stop)
    assert cli.main(argv) == runner.EXIT_STOPPED == 75
    stopped = json.loads((out / "study.json").read_text())
    assert stopped["finished"] is False and stopped["ran_now"] == 2 and len(calls) == 2
    assert len(list((out / "runs").glob("*.json"))) == 2
    assert not (out / runner.STOP_FILE).exists()

    (out / runner.STOP_FILE).touch()  # left over: not a request to this command
    assert cli.main(argv) == 0
    done = json.loads((out / "study.json").read_text())
    assert done["finished"] is True and done["skipped_now"] == 2
    assert done["ran_now"] == done["runs"] - 2 and not (out / runner.STOP_FILE).exists()

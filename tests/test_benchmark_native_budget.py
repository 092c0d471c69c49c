"""The tabular learners on a budget axis in env steps (benchmark v2): the switch in
``runner.budget_of``, one core run per evaluation target with the curve from its
checkpoints, and v1's specs unchanged."""

from __future__ import annotations

import numpy as np
import sixaxis_avoid as sa
from sixaxis_avoid.benchmark import runner
from sixaxis_avoid.benchmark.learners import split_budget
from sixaxis_avoid.benchmark.tasks import load_suite


def axis_suite():
    suite = load_suite("quick")
    suite.budgets = {"axis": [3000, 8000], "checkpoints": 4}
    return suite


def test_split_budget_sums_to_the_budget():
    assert split_budget(10, 3) == [4, 3, 3]
    assert sum(split_budget(1_000_001, 8)) == 1_000_001


def test_v1_specs_are_unchanged_by_the_axis_switch():
    suite = load_suite("v1")
    specs = runner.plan_runs(suite, ["q_assist", "q_paper"], seeds=[0])
    assert len(specs) == 2 * len(suite.tasks)
    for s in specs:
        assert s["hyperparams"] == {"episodes": 10_000}
        assert "budget_axis" not in s
        assert runner.run_key(s) == f"{s['task']['id']}__{s['learner']}__s0"


def test_an_axis_gives_native_runs_the_budget_and_the_env_step_schedule():
    suite = axis_suite()
    task = suite.task("paper_simple")
    specs = runner.plan_runs(suite, ["q_assist", "q_paper", "bfs"], seeds=[0], tasks=[task])
    native = [s for s in specs if s["learner"] == "q_assist"]
    assert [s["budget"] for s in native] == [3000, 8000]
    for s in native:
        assert s["hyperparams"]["max_env_steps"] == s["budget"]
        assert s["hyperparams"]["epsilon_schedule"] == "env_steps"
        assert s["checkpoints"][-1] == s["budget"]
    (paper,) = [s for s in specs if s["learner"] == "q_paper"]
    assert (
        paper["hyperparams"]["episodes"] == 10_000
        and "epsilon_schedule" not in paper["hyperparams"]
    )
    assert paper["max_replans"] == suite.algorithm2["native"]
    keys = [runner.run_key(s) for s in specs]
    assert len(set(keys)) == len(keys)
    assert "paper_simple__q_assist__s0__b3000" in keys


def test_a_goal_run_spends_the_budget_over_its_targets_in_one_run_each():
    suite = axis_suite()
    task = suite.task("goal-paper_simple")
    (spec,) = runner.plan_runs(suite, ["q_assist"], seeds=[1], tasks=[task], budgets=[8000])
    rec = runner.execute_run(spec)
    res = rec["result"]
    assert res["env_steps"] == 8000
    steps = [p["env_steps"] for p in res["curve"]]
    assert steps == sorted(steps) and steps[-1] == 8000
    assert set(spec["checkpoints"]) <= set(steps)
    # The final paths are those of one budget-capped core run per target (4000 steps each).
    for t, got in zip(task.eval_targets, res["paths"]):
        r = sa.train(
            task.world(t),
            seed=1,
            assist=True,
            episodes=4000,
            max_env_steps=4000,
            epsilon_schedule="env_steps",
        )
        assert got == (None if r.path is None else [list(c) for c in r.path])
    # Until the first target's run ends, the second target has no path.
    first_half = [p for p in res["curve"] if p["env_steps"] <= 4000]
    assert first_half and all(p["success"] <= 0.5 for p in first_half)
    times = [p["wall_time_s"] for p in rec["timing"]["curve"]]
    assert times == sorted(times)
    assert np.isfinite(rec["timing"]["cpu_time_s"])

"""Benchmark v2: the suite (distinct learner worlds, finer grids, the budget axis), its runs'
specs, the statistics for near-binary outcomes and the v2 report (docs/BENCHMARKS.md)."""

from __future__ import annotations

import json

import pytest
import sixaxis_avoid as sa
from sixaxis_avoid.benchmark import load_suite, plan_runs, runner
from sixaxis_avoid.benchmark.tasks import SuiteError, Task

# -- suite v2 ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def v2():
    return load_suite("v2")


def test_v2_has_the_design_tasks_and_budget_axis(v2):
    assert v2.major_version == 2
    assert v2.budgets["axis"] == [30000, 100000, 300000, 1000000]
    assert len(v2.seeds) == 10
    ids = [t.id for t in v2.tasks]
    assert "paper_simple" in ids and "paper_complex" not in ids and "replan_clutter" in ids
    for level in ("easy", "medium", "hard"):
        gen = [t for t in v2.tasks if t.group == f"generated:{level}"]
        assert len(gen) == 5, level
        assert len({t.spec["seed"] for t in gen}) == 5
    assert [t.id for t in v2.tasks if t.is_goal] == ["goal-paper_simple"]
    # Tuning shares no world with the reported tasks (also checked on loading).
    v2.check_disjoint()
    assert not {t.learner_world for t in v2.tuning_tasks} & {t.learner_world for t in v2.tasks}


def test_finer_grid_tasks_are_regridded_solvable_and_bigger(v2):
    coarse = v2.task("paper_simple")
    sizes = {}
    for tid, cell_mm in (("paper_simple-50mm", 50.0), ("paper_simple-25mm", 25.0)):
        t = v2.task(tid)
        d = t.describe()
        assert d["cell_mm"] == cell_mm and t.group == f"paper@{cell_mm:g}mm"
        path = sa.shortest_path(t.scenario)
        assert path is not None  # solvable (BFS)
        # The same physical path at a finer grid: optimum scales with 100 / cell_mm.
        assert d["optimal_lengths"] == [coarse.optimal_lengths[0] * round(100 / cell_mm)]
        sizes[cell_mm] = d["states"]
    assert sizes == {50.0: 13 * 17 * 15, 25.0: 25 * 33 * 29}  # 3315 and 23925 states
    gen = v2.task("gen-medium-0-50mm")
    assert gen.describe()["states"] == 3315 and sa.shortest_path(gen.scenario) is not None
    assert gen.learner_world != v2.task("gen-medium-0").learner_world


def test_bad_cell_mm_names_the_task_and_value():
    t = Task("x", "scenario", {"scenario": "paper_simple", "cell_mm": 30})
    with pytest.raises(SuiteError, match=r"task 'x': cell_mm 30"):
        _ = t.scenario


def test_v1_has_a_duplicated_learner_world_and_v2_refuses_one(tmp_path):
    v1 = load_suite("v1")  # v1 predates the check: it loads
    with pytest.raises(SuiteError, match="'paper_simple' and 'paper_complex'"):
        v1.check_distinct_worlds()
    # The two differ in their raw terminal safe distance (0.96, 0.95), not in blocked cells.
    a, b = v1.task("paper_simple"), v1.task("paper_complex")
    assert a.scenario.terminal_safe_distance != b.scenario.terminal_safe_distance
    assert list(a.blocked_states) == list(b.blocked_states)
    raw = json.loads(load_suite("v2").path.read_text())
    raw["tasks"].insert(1, {"id": "paper_complex", "kind": "scenario", "scenario": "paper_complex"})
    p = tmp_path / "dup.json"
    p.write_text(json.dumps(raw))
    with pytest.raises(SuiteError, match="'paper_simple' and 'paper_complex'"):
        load_suite(p)


def test_learner_world_sees_rewards_step_cap_and_goal():
    base = Task("a", "scenario", {"scenario": "paper_simple"})
    # A reward or the episode's step cap changes what the learner sees.
    for field in ("rewards", "learning"):
        s = json.loads(base.scenario.to_json())
        if field == "rewards":
            s["rewards"]["step_penalty"] += 1.0
        else:
            s["learning"]["max_steps_per_episode"] += 1
        t = Task("b", "scenario", {"scenario": "paper_simple"})
        t.__dict__["scenario"] = sa.Scenario.from_json(json.dumps(s))
        assert t.learner_world != base.learner_world, field
    # The learning seed does not (each run sets its own), nor do the planning settings.
    s = json.loads(base.scenario.to_json())
    s["learning"]["seed"] = 7
    s["planning"]["max_replans"] = 3
    t = Task("c", "scenario", {"scenario": "paper_simple"})
    t.__dict__["scenario"] = sa.Scenario.from_json(json.dumps(s))
    assert t.learner_world == base.learner_world
    goal = Task("g", "goal", {"scenario": "paper_simple", "eval_targets": 1, "target_seed": 0})
    assert goal.learner_world != base.learner_world


# -- run specs on the budget axis -------------------------------------------------------------


def test_plan_runs_one_run_per_budget_with_the_budget_in_the_file_name(v2, tmp_path):
    tasks = [v2.task("paper_simple"), v2.task("goal-paper_simple")]
    specs = plan_runs(
        v2, ["dqn", "bfs"], seeds=[0, 1], tasks=tasks, hyperparams=tmp_path / "none.json"
    )
    assert len(specs) == 2 * 2 * 2 * 4
    dqn = [s for s in specs if s["learner"] == "dqn"]
    assert sorted({s["budget"] for s in dqn}) == v2.budgets["axis"]
    for s in dqn:  # the goal task gets the same total budget
        assert s["budget"] == s["budget_axis"] and s["checkpoints"][-1] == s["budget"]
        assert s["hyperparams_status"] == "untuned"  # no by_budget entry at all
    keys = [runner.run_key(s) for s in specs]
    assert len(set(keys)) == len(keys)
    assert runner.run_key(dqn[0]).endswith(f"__b{dqn[0]['budget']}")
    # A subset of the axis; a budget off the axis is refused by value.
    sub = plan_runs(v2, ["dqn"], seeds=[0], tasks=tasks[:1], budgets=[100000],
                    hyperparams=tmp_path / "none.json")  # fmt: skip
    assert [s["budget"] for s in sub] == [100000]
    with pytest.raises(ValueError, match="12345 is not on"):
        plan_runs(v2, ["dqn"], seeds=[0], tasks=tasks[:1], budgets=[12345])
    # v1 specs are unchanged: no axis, no budget in the file name.
    v1 = load_suite("v1")
    s1 = plan_runs(v1, ["dqn"], seeds=[0], tasks=[v1.task("paper_simple")])[0]
    assert "budget_axis" not in s1 and runner.run_key(s1) == "paper_simple__dqn__s0"
    with pytest.raises(ValueError, match="no budget axis"):
        plan_runs(v1, ["dqn"], budgets=[30000])


def test_plan_runs_takes_the_values_tuned_at_each_budget(v2, tmp_path):
    hp = tmp_path / "hp.json"
    hp.write_text(json.dumps({"learners": {"dqn": {"by_budget": {
        "100000": {"values": {"learning_rate": 0.00042}, "status": "tuned",
                   "trials": "docs/results/v2-tuning/dqn-100000.json", "objective": 0.9},
    }}}}))  # fmt: skip
    specs = plan_runs(v2, ["dqn"], seeds=[0], tasks=[v2.task("paper_simple")], hyperparams=hp)
    by = {s["budget"]: s for s in specs}
    assert by[100000]["hyperparams"]["learning_rate"] == 0.00042
    assert by[100000]["hyperparams_status"] == "tuned"
    for b in (30000, 300000, 1000000):  # never reused from another budget
        assert by[b]["hyperparams_status"] == "untuned"
        assert by[b]["hyperparams"]["learning_rate"] != 0.00042

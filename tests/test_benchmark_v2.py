"""Benchmark v2: the suite (distinct learner worlds, finer grids, the budget axis), its runs'
specs, the statistics for near-binary outcomes and the v2 report (docs/BENCHMARKS.md)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import sixaxis_avoid as sa
from sixaxis_avoid.benchmark import load_suite, plan_runs, runner, stats
from sixaxis_avoid.benchmark.tasks import SuiteError, Task

# -- suite v2 ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def v2():
    return load_suite("v2")


def test_v2_has_the_design_tasks_and_budget_axis(v2):
    assert v2.major_version == 2
    assert v2.budgets["axis"] == [30000, 100000, 300000, 1000000, 3000000, 10000000]
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
    # By default every budget of the axis but its best_only tail (10M: named when wanted).
    assert len(specs) == 2 * 2 * 2 * 5
    dqn = [s for s in specs if s["learner"] == "dqn"]
    assert sorted({s["budget"] for s in dqn}) == v2.budgets["axis"][:-1]
    assert v2.budgets["best_only"] == [10000000]
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
    top = plan_runs(v2, ["dqn"], seeds=[0], tasks=tasks[:1], budgets=[10000000],
                    hyperparams=tmp_path / "none.json")  # fmt: skip
    assert [s["budget"] for s in top] == [10000000]
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


# -- statistics -------------------------------------------------------------------------------


def test_wilson_interval_of_known_counts():
    w = stats.wilson(7, 10)  # the textbook example: 0.397 .. 0.892
    assert (round(w["lo"], 4), round(w["hi"], 4)) == (0.3968, 0.8922)
    assert stats.wilson(0, 10)["lo"] == 0.0 and stats.wilson(0, 10)["hi"] > 0.27
    assert stats.wilson(10, 10)["hi"] == 1.0 and stats.wilson(10, 10)["lo"] < 0.73
    with pytest.raises(ValueError, match="successes 11 of trials 10"):
        stats.wilson(11, 10)


def test_iqm_rule_and_kaplan_meier_median():
    assert not stats.iqm_shown(np.array([0.0] * 6 + [1.0] * 2 + [0.5] * 2))  # 80% at 0 or 1
    assert stats.iqm_shown(np.array([0.0] * 5 + [1.0] * 2 + [0.5] * 3))  # 70%
    # 3 of 5 reach at 10, 20, 30; 2 censored at 100: S = 0.8, 0.6, 0.4 -> median 30.
    t, e = np.array([10, 20, 30, 100, 100]), np.array([1, 1, 1, 0, 0], bool)
    assert stats.km_median(t, e) == 30.0
    assert stats.km_median(t, np.array([1, 1, 0, 0, 0], bool)) is None  # beyond the budget
    # A censored run leaves the risk set: S drops by 1/2 at 30 (2 at risk) -> 0.8*0.75*0.5.
    ts, s = stats.kaplan_meier(np.array([10, 20, 25, 30, 40]), np.array([1, 1, 0, 1, 0], bool))
    assert list(ts) == [10, 20, 30] and np.allclose(s, [0.8, 0.6, 0.3])


def test_headline_budget_is_the_first_plateau_of_the_best():
    rows = {
        1: {"a": {"mean": 0.1, "mean_ci": [0.0, 0.2]}},
        2: {"a": {"mean": 0.8, "mean_ci": [0.7, 0.9]}},
        3: {"a": {"mean": 0.85, "mean_ci": [0.8, 0.9]}},
    }
    h = stats.headline_budget(rows, ["a"])
    assert h["budget"] == 2 and h["plateaued"]
    rows[3]["a"]["mean"] = 0.95  # still rising at the end: the largest, not plateaued
    h = stats.headline_budget(rows, ["a"])
    assert h["budget"] == 3 and not h["plateaued"]


# -- the v2 report on synthetic runs ----------------------------------------------------------

AXIS = [1000, 10000, 100000]
TASKS = ["paper_simple", "gen-easy-0", "goal-paper_simple"]


def synthetic_outcome(learner, task, seed, budget):
    """(score, success, targets, first env steps at SPL >= 0.95 or None)."""
    targets = 8 if task.startswith("goal") else 1
    if learner == "bfs":
        return 1.0, 1.0, targets, 0
    if learner == "alpha":
        if budget == 1000:
            return 0.0, 0.0, targets, None
        if task == "paper_simple" or (task == "gen-easy-0" and seed < 7):
            return 1.0, 1.0, targets, budget // 2
        if task == "goal-paper_simple":
            return 0.7, 0.75, targets, None
        return 0.0, 0.0, targets, None
    # beta: exactly 0 or 1 everywhere, half of paper_simple from 10k on
    if budget >= 10000 and task == "paper_simple" and seed < 5:
        return 1.0, 1.0, targets, budget // 2
    return 0.0, 0.0, targets, None


def write_synthetic_study(tmp_path):
    raw = json.loads(load_suite("v2").path.read_text())
    raw["name"] = "v2-synthetic"
    raw["budgets"] = {"axis": AXIS, "checkpoints": 4}
    raw["tasks"] = [t for t in raw["tasks"] if t["id"] in TASKS]
    raw["tuning"] = {"seeds": [100], "tasks": []}
    raw["hyperparams"] = str(tmp_path / "hp.json")
    (tmp_path / "hp.json").write_text(json.dumps({"learners": {"alpha": {"by_budget": {
        "10000": {"values": {}, "status": "tuned", "objective": 0.875,
                  "trials": "docs/results/v2-tuning/alpha-10000.json"}}}}}))  # fmt: skip
    suite_path = tmp_path / "suite.json"
    suite_path.write_text(json.dumps(raw))
    out = tmp_path / "study"
    for lr in ("alpha", "beta", "bfs"):
        for t in raw["tasks"]:
            for seed in range(10):
                for b in AXIS:
                    score, success, n, first = synthetic_outcome(lr, t["id"], seed, b)
                    curve = (
                        [{"env_steps": 0, "score": score, "success": success}]
                        if lr == "bfs"
                        else [
                            {"env_steps": x, "score": score if first and x >= first else 0.0,
                             "success": success if first and x >= first else 0.0}
                            for x in (b // 10, b // 2, b)
                        ]
                    )  # fmt: skip
                    curve[-1].update(score=score, success=success)
                    spec = {
                        "suite": raw["name"], "learner": lr, "seed": seed,
                        "family": "reference" if lr == "bfs" else "deep",
                        "task": {k: v for k, v in t.items()},
                        "budget": 0 if lr == "bfs" else b, "budget_axis": b,
                        "hyperparams_status": "n/a" if lr == "bfs"
                        else ("tuned" if (lr, b) == ("alpha", 10000) else "untuned"),
                        **({"hyperparams": {"implementation": "rejax"}} if lr == "beta" else {}),
                    }  # fmt: skip
                    record = {
                        "spec": spec,
                        "result": {"score": score, "success": success, "curve": curve,
                                   "optimal_lengths": [9] * n, "env_steps": spec["budget"]},
                        "host": {"machine": "synthetic CPU, 2 cores"},
                    }  # fmt: skip
                    if (lr, b, seed, t["id"]) == ("beta", 1000, 0, "paper_simple"):
                        record["result"]["env_steps"] = 1500  # one run over its budget
                    runner.write_run(out, record)
    (out / "study.json").write_text(json.dumps({
        "suite": raw, "learners": ["alpha", "beta", "bfs"], "tasks": TASKS,
        "command": "python -m sixaxis_avoid.benchmark run --suite v2-synthetic",
        "commands": ["python -m sixaxis_avoid.benchmark run --suite v2-synthetic"],
        "date": "2026-12-03 12:00 UTC", "machine": "synthetic CPU, 2 cores",
        "wall_time_s_total": 60.0,
    }))  # fmt: skip
    return suite_path, out


def test_v2_report_on_synthetic_runs(tmp_path):
    from sixaxis_avoid.benchmark.report_v2 import write_report_v2

    suite_path, out = write_synthetic_study(tmp_path)
    assert len(list((out / "runs").glob("*.json"))) == 3 * 3 * 10 * 3  # budget in the name
    md = tmp_path / "BENCHMARKS.md"
    history = tmp_path / "BENCHMARKS-v1.md"
    history.write_text(
        "# v1\n\n<!-- benchmark-aggregate:begin -->\nold\n<!-- benchmark-aggregate:end -->\n"
    )
    # The old page's v1 section moved to the history page: not kept; another owner's is.
    md.write_text("old\n\n<!-- benchmark-aggregate:begin -->\nx\n<!-- benchmark-aggregate:end -->"
                  "\n\n<!-- jax-twin:begin -->\nkept\n<!-- jax-twin:end -->\n")  # fmt: skip
    a = write_report_v2(out, md, reps=100, suite=str(suite_path), history=history)
    assert a["budgets"] == AXIS and a["ranked"] == ["alpha", "beta"] and a["reference"] == ["bfs"]
    at = a["per_budget"][10000]["learners"]
    # 10 + 7 single targets and 6 of 8 goal targets in each of 10 runs: 77 of 100.
    w = at["alpha"]["success"]
    assert (w["successes"], w["trials"]) == (77, 100)
    assert (round(w["lo"], 3), round(w["hi"], 3)) == (0.678, 0.842)
    assert at["alpha"]["mean"] == pytest.approx((10 + 7 + 10 * 0.7) / 30)
    # alpha: 20 of 30 scores at 0 or 1 (IQM shown); beta: all (IQM hidden).
    assert at["alpha"]["iqm_shown"] and not at["beta"]["iqm_shown"]
    assert at["beta"]["degenerate"] == 1.0
    # 17 of 30 runs reach SPL >= 0.95 at 5000 steps; the others are censored at 10k.
    s = at["alpha"]["steps_to"]
    assert (s["reached"], s["runs"], s["median"]) == (17, 30, 5000.0)
    # Best at the largest budget: alpha only (beta's interval is far below); it jumps from
    # 1k to 10k and is flat from 10k to 100k: the headline budget is 10k.
    assert a["best"] == ["alpha"]
    assert a["headline"]["budget"] == 10000 and a["headline"]["plateaued"]
    over = [{"learner": "beta", "budget": 1000, "runs": 1, "of": 30, "max_env_steps": 1500}]
    assert a["over_budget"] == over
    text = md.read_text()
    assert "## Headline (10k env steps)" in text and "have plateaued" in text
    assert "benchmark-aggregate" not in text and "<!-- jax-twin:begin -->\nkept" in text
    assert "<!-- benchmark-headline:begin -->" in text
    assert "0.770 [0.678, 0.842] (77/100)" in text
    assert "— (100% of scores 0 or 1)" in text  # beta's IQM hidden
    assert "5000 [" in text and "(17/30 reached)" in text
    assert "| alpha | 10k | tuned | `docs/results/v2-tuning/alpha-10000.json` | 0.875 |" in text
    assert "| alpha | 1000 | **untuned** |" in text
    assert "bfs (reference, not ranked)" in text and "| bfs | 10k | n/a |" in text
    assert "| alpha | 0.000 (all equal) ✗ | 0.800 [" in text  # no zero-width "interval"
    assert "270 runs: 3 learners x 3 tasks x 10 seeds x 3 budgets" in text
    assert "beta at 1000: 1 of 30 runs, up to 1500." in text
    assert "**Implementation**: beta runs with `implementation: rejax`" in text
    assert "| generated:easy | 1 | 0.700, 0.700 [0.397, 0.892] (7/10) |" in text  # per group
    assert "[BENCHMARKS-v1.md](BENCHMARKS-v1.md)" in text
    assert (tmp_path / "figures" / "bench-v2" / "bench_v2_curves.png").stat().st_size > 0
    assert (tmp_path / "figures" / "bench-v2" / "bench_v2_profiles.png").stat().st_size > 0


def test_v2_headline_sits_where_every_ranked_learner_ran(tmp_path):
    """A learner missing from the largest budget (a study still running) does not drop out
    of the ranking: the headline moves to the largest budget every ranked learner ran, and
    the page names what was not run."""
    from sixaxis_avoid.benchmark.report_v2 import write_report_v2

    suite_path, out = write_synthetic_study(tmp_path)
    # beta's 100k runs are in progress: 12 of its 30 sit beside the study, committed part
    # way (study-pending/), and count nowhere until merged.
    pending = tmp_path / "study-pending" / "beta-100000"
    (pending / "runs").mkdir(parents=True)
    for i, f in enumerate(sorted((out / "runs").glob("*__beta__*__b100000.json"))):
        if i < 12:
            (pending / "runs" / f.name).write_text(f.read_text())
        f.unlink()
    cmd = "python -m sixaxis_avoid.benchmark run --learners beta --budgets 100000"
    (pending / "study.json").write_text(json.dumps({
        "command": cmd, "learners": ["beta"], "runs": 30, "finished": False,
        "wall_time_s_total": 5400.0}))  # fmt: skip
    md = tmp_path / "BENCHMARKS.md"
    a = write_report_v2(out, md, reps=100, suite=str(suite_path))
    assert a["common_budgets"] == [1000, 10000]
    assert a["missing_budgets"] == {"beta": [100000]}
    (p,) = a["in_progress"]
    assert (p["made"], p["of"], p["budgets"], p["finished"]) == (12, 30, [100000], False)
    assert (
        f"beta at 100k, 12 of 30 runs in `{pending}` (1.5 h of wall time so far)." in md.read_text()
    )
    # alpha is best at 10k; its plateau is checked at 100k, which only alpha ran (flat there).
    assert a["best"] == ["alpha"] and a["headline"]["budget"] == 10000
    assert a["headline"]["plateaued"]
    text = md.read_text()
    assert "## Headline (10k env steps)" in text
    assert "mean SPL at the next budget (100k) lies inside" in text
    assert "Not every learner ran at 100k; the plateau is the best learners' own" in text
    assert "Not run yet: beta at 100k." in text
    # 270 runs less beta's 30 at 100k: no longer a product of learners, tasks, seeds, budgets.
    assert (
        "240 runs: 3 learners, 3 tasks, 3 budgets; 8 of the 9 learner-budget pairs run "
        "(*Score by budget*), 10 seeds per task at 8." in text
    )
    head = text.split("<!-- benchmark-headline:begin -->")[1].split("<!-- benchmark-head")[0]
    assert "| alpha |" in head and "| beta |" in head
    # Without alpha's 100k runs too, nothing after 10k can show the plateau.
    for f in (out / "runs").glob("*__alpha__*__b100000.json"):
        f.unlink()
    a = write_report_v2(out, md, reps=100, suite=str(suite_path))
    assert a["headline"]["budget"] == 10000 and not a["headline"]["plateaued"]
    assert "The plateau is not shown" in md.read_text()


def test_v2_best_only_budget_is_run_by_the_best_learners_alone(tmp_path):
    """A budget the suite marks best_only (the axis's tail) is the best learners' plateau
    check: a learner that is not among the best is not missing there, and its tuning row
    there is not listed; a best learner that has not run it is."""
    from sixaxis_avoid.benchmark.report_v2 import write_report_v2

    suite_path, out = write_synthetic_study(tmp_path)
    raw = json.loads(suite_path.read_text())
    raw["budgets"]["best_only"] = [AXIS[-1]]
    suite_path.write_text(json.dumps(raw))
    for f in (out / "runs").glob("*__beta__*__b100000.json"):
        f.unlink()
    md = tmp_path / "BENCHMARKS.md"
    a = write_report_v2(out, md, reps=100, suite=str(suite_path))
    assert a["common_budgets"] == [1000, 10000] and a["best"] == ["alpha"]
    assert a["missing_budgets"] == {}
    assert a["headline"]["budget"] == 10000 and a["headline"]["plateaued"]
    text = md.read_text()
    assert "Not run yet" not in text and "Not every learner ran at every budget" not in text
    assert "| alpha | 100k |" in text and "| beta | 100k |" not in text
    assert "`budgets.best_only`" in text  # Statistics says what the budget is for
    # Nothing lacking: the cluster example runs the best learners at the axis's end, on the
    # seeds the ranking compares (10 here).
    assert "--learners alpha --seeds 10 --budgets 100000 " in text
    assert "the best learners' (alpha) runs at 100k env steps, 10 seeds" in text
    assert "Budget axis (env steps): 1000, 10k, 100k (100k for the best learners only" in text
    # alpha falls on paper_simple at 100k: not plateaued at 10k, and the page says where.
    for f in (out / "runs").glob("paper_simple__alpha__*__b100000.json"):
        r = json.loads(f.read_text())
        r["result"]["score"] = r["result"]["success"] = 0.0
        f.write_text(json.dumps(r))
    a = write_report_v2(out, md, reps=100, suite=str(suite_path))
    assert a["headline"]["budget"] == 10000 and not a["headline"]["plateaued"]
    text = md.read_text()
    assert "the headline sits at the largest budget at which every ranked learner ran, 10k" in text
    assert "At 10k: alpha's mean at 100k, 0.467, lies outside its interval here, 0.800 [" in text
    assert "most of all on paper_simple (1.000 here, 0.000 there)." in text
    # Without alpha's runs there, the best learner has not run it: the page says so, and
    # the headline stays at the last budget every ranked learner ran, not at the axis's end.
    for f in (out / "runs").glob("*__alpha__*__b100000.json"):
        f.unlink()
    a = write_report_v2(out, md, reps=100, suite=str(suite_path))
    assert a["missing_budgets"] == {"alpha": [100000]}
    assert a["headline"]["budget"] == 10000 and not a["headline"]["plateaued"]
    text = md.read_text()
    assert "Not run yet: alpha at 100k." in text
    # The cluster example is what the study lacks first.
    assert "--learners alpha --seeds 10 --budgets 100000 " in text
    assert "what the study lacks first: alpha at 100k env steps (10 seeds" in text
    assert "the headline sits at the largest budget at which every ranked learner ran, 10k" in text
    assert "At 10k:" not in text  # no best learner ran past it: nothing to say where
    # While the budget before it is not one every ranked learner ran, the best learners there
    # are not known, so nobody lacks the best_only budget yet (alpha has not run it either).
    for f in (out / "runs").glob("*__beta__*__b10000.json"):
        f.unlink()
    a = write_report_v2(out, md, reps=100, suite=str(suite_path))
    assert a["common_budgets"] == [1000]
    assert a["missing_budgets"] == {"beta": [10000]}
    text = md.read_text()
    assert "Not run yet: beta at 10k." in text
    assert "| alpha | 100k |" not in text  # nor is its tuning row listed
    assert "--learners beta --seeds 10 --budgets 10000 " in text


def test_v2_best_only_must_be_the_axis_tail(tmp_path):
    raw = json.loads(load_suite("v2").path.read_text())
    for bad in ([30000], [1000000], raw["budgets"]["axis"]):
        raw["budgets"]["best_only"] = bad
        p = tmp_path / "s.json"
        p.write_text(json.dumps(raw))
        with pytest.raises(SuiteError, match=r"budgets\.best_only"):
            load_suite(p)
    raw["budgets"]["best_only"] = []
    raw["budgets"]["axis"] = [100000, 30000]
    p.write_text(json.dumps(raw))
    with pytest.raises(SuiteError, match=r"budgets\.axis \[100000, 30000\]"):
        load_suite(p)


def test_v2_runs_line_names_seeds_per_learner_and_budget():
    """Where the deep learners run 5 seeds and the others 10, the line says so instead of
    multiplying learners, tasks, seeds and budgets into a count the runs do not fill."""
    from sixaxis_avoid.benchmark.report_v2 import runs_line

    def run(learner: str, budget: int, seed: int) -> dict:
        return {"spec": {"learner": learner, "seed": seed, "budget": budget,
                         "budget_axis": budget}}  # fmt: skip

    runs = [run("a", b, s) for b in (10, 100) for s in range(10) for _ in range(2)]
    assert runs_line(runs, 1, 2, 2) == "40 runs: 1 learners x 2 tasks x 10 seeds x 2 budgets"
    runs += [run("d", b, s) for b in (10, 100) for s in range(5) for _ in range(2)]
    assert runs_line(runs, 2, 2, 2) == (
        "60 runs: 2 learners, 2 tasks, 2 budgets; 4 of the 4 learner-budget pairs run "
        "(*Score by budget*), 10 seeds per task at 2, 5 at 2"
    )


def test_v2_report_before_any_run_says_so(tmp_path):
    from sixaxis_avoid.benchmark.__main__ import main

    md = tmp_path / "B.md"
    argv = ["report", "--suite", "v2", "--results", str(tmp_path / "none"), "--out", str(md),
            "--history", str(tmp_path / "missing.md")]  # fmt: skip
    assert main(argv) == 0
    text = md.read_text()
    assert "No results of suite v2 yet" in text
    assert "| paper_simple-25mm | paper@25mm | 25x33x29 | 23925 | 25 |" in text
    assert "| (none yet) | — | **untuned** |" in text or "**untuned**" in text


def test_v1_report_is_the_history_page_and_links_the_current_one(tmp_path, monkeypatch):
    """A v1 study's report (by default docs/BENCHMARKS-v1.md) names its own --out in its
    command and links docs/BENCHMARKS.md; here on a slice of the committed v1 results."""
    import shutil
    from pathlib import Path

    from sixaxis_avoid.benchmark.__main__ import main

    src = Path(__file__).resolve().parent.parent / "docs" / "results" / "v1"
    study = tmp_path / "docs" / "results" / "v1"
    (study / "runs").mkdir(parents=True)
    manifest = json.loads((src / "study.json").read_text())
    manifest["learners"], manifest["tasks"] = ["bfs", "q_assist"], ["paper_simple", "gen-easy-0"]
    (study / "study.json").write_text(json.dumps(manifest))
    for lr in manifest["learners"]:
        for t in manifest["tasks"]:
            for seed in (0, 1):
                name = f"{t}__{lr}__s{seed}.json"
                shutil.copy(src / "runs" / name, study / "runs" / name)
    monkeypatch.chdir(tmp_path)
    assert main(["report", "--results", "docs/results/v1", "--reps", "100"]) == 0
    text = (tmp_path / "docs" / "BENCHMARKS-v1.md").read_text()
    assert "report --results docs/results/v1 --out docs/BENCHMARKS-v1.md\n" in text
    assert "the current benchmark is [BENCHMARKS.md](BENCHMARKS.md)" in text
    assert not (tmp_path / "docs" / "BENCHMARKS.md").exists()


def test_jax_runs_are_labelled_tuned_or_untuned_by_their_budget(tmp_path):
    """A JAX learner's run at an axis budget records whether values were tuned at that budget
    (like the SB3 learners), never "n/a"; with by_budget values at B it takes them."""
    import json as _json

    from sixaxis_avoid.benchmark import load_suite, plan_runs

    suite = load_suite("v2")
    hp = tmp_path / "hp.json"
    hp.write_text(
        _json.dumps(
            {
                "learners": {
                    "jax_ppo": {
                        "by_budget": {
                            "30000": {"values": {"learning_rate": 0.01}, "status": "tuned"}
                        }
                    }
                }
            }
        )
    )
    task = [suite.task("paper_simple")]
    at30, at100 = (
        plan_runs(suite, ["jax_ppo"], seeds=[0], tasks=task, hyperparams=hp, budgets=[b])[0]
        for b in (30_000, 100_000)
    )
    assert at30["hyperparams_status"] == "tuned" and at30["hyperparams"]["learning_rate"] == 0.01
    assert at100["hyperparams_status"] == "untuned"
    assert at100["hyperparams"]["learning_rate"] != 0.01
    assert at30["family"] == "jax" and at30["budget"] == 30_000


def test_a_package_hyperparameter_file_is_named_by_its_repository_path(tmp_path, monkeypatch):
    from sixaxis_avoid.benchmark import hyperparams as hpmod

    # The page names the file the same way from any working directory (it once printed
    # "../wt-ci/python/...", the path from the worktree the report ran in).
    monkeypatch.chdir(tmp_path)
    shown = hpmod.display_path(hpmod.hyperparams_path("v2"))
    assert shown.endswith("sixaxis_avoid/benchmark/hyperparams/v2.json")
    assert not shown.startswith("..") and not shown.startswith("/")
    # Any other file: relative to the working directory.
    assert hpmod.display_path(tmp_path / "mine.json") == "mine.json"


def test_compute_section_sums_the_runs_and_counts_each_trials_file_once(monkeypatch):
    """The page's *Compute* rows: a learner's runs add up per budget, its tuning time comes
    from its own trials file, and a learner run with another's values (SB3 DQN with
    jax_dqn's) has no tuning time of its own."""
    import json

    from sixaxis_avoid.benchmark import report_compute as rc
    from sixaxis_avoid.benchmark import report_v2
    from sixaxis_avoid.benchmark.hyperparams import HYPERPARAMS_DIR

    def run(learner, family, wall, cpu):
        return {"spec": {"learner": learner, "family": family, "budget": 30000},
                "timing": {"run_wall_time_s": wall, "wall_time_s": wall, "cpu_time_s": cpu},
                "result": {"env_steps": 30000}}  # fmt: skip

    runs = [run("dqn", "deep", 1800.0, 900.0), run("dqn", "deep", 1800.0, 900.0),
            run("jax_dqn", "jax", 360.0, 36.0)]  # fmt: skip
    text = "\n".join(report_v2.compute_rows({"suite": load_suite("v2"), "runs": runs}))
    root = HYPERPARAMS_DIR.parents[3]
    trials = json.loads((root / "docs/results/v2-tuning/jax_dqn-30000.json").read_text())
    tw, tc = trials["wall_time_s"] / 3600, trials["cpu_time_s"] / 3600
    assert "| dqn | 30k | — | — | 1.00 | 0.50 |" in text
    assert f"| jax_dqn | 30k | {tw:.2f} | {tc:.2f} | 0.10 | 0.01 |" in text
    # The family's tuning: every jax_dqn search of the record (each budget's file once).
    record = json.loads((HYPERPARAMS_DIR / "v2.json").read_text())["learners"]["jax_dqn"]
    files = {e["trials"] for e in record["by_budget"].values()}
    all_tw = sum(json.loads((root / f).read_text())["wall_time_s"] for f in files) / 3600
    assert f"jax {all_tw + 0.1:.2f} h wall" in text and "deep 1.00 h wall, 0.50 h CPU" in text
    # The JAX part's goal (2 h wall on this machine): stated with the runs still to come.
    goal = "**Goal for the JAX part** (its learners' tuning and runs at every budget, on this "
    assert f"{goal}machine): 2.00 h of wall time. Not met: {all_tw + 0.1:.2f} h wall" in text
    # Why it is not met: the env steps trained (the searches' trials and seeds, the runs)
    # over the CPU time, and the least wall time both cores would need for them.
    tc_all = sum(json.loads((root / f).read_text())["cpu_time_s"] for f in files) + 36.0
    steps = sum(rc.tuning_env_steps(json.loads((root / f).read_text())) for f in files) + 30000
    first = json.loads((root / "docs/results/v2-tuning/jax_dqn-30000.json").read_text())
    assert (
        rc.tuning_env_steps(first)
        == sum(
            c["env_steps"][-1] * len(first["seeds"])
            for t in first["trials"]
            for c in t["curves"].values()
        )
        > 32 * 3 * 20000
    )  # 32 trials x 3 seeds, five tasks of close to 30k env steps
    assert (
        f"trained {steps / 1e6:,.0f}M env steps so far" in text
        and f"in {tc_all / 3600:.2f} core-hours: {steps / tc_all:,.0f} env steps per core-second"
        in text
        and f"that work alone takes {tc_all / 2 / 3600:.2f} h" in text
    )
    later = {"suite": load_suite("v2"), "runs": runs, "missing_budgets": {"jax_dqn": [1000000]}}
    assert "with jax_dqn at 1.00M still to run." in "\n".join(report_v2.compute_rows(later))

    monkeypatch.setattr(rc, "JAX_GOAL_S", 1e9)  # a goal this study meets
    met = "\n".join(report_v2.compute_rows({"suite": load_suite("v2"), "runs": runs}))
    assert "of wall time. Met: " in met and "still to run" not in met


def test_twin_agreement_compares_each_jax_learner_with_its_sb3_twin():
    """The study's JAX-against-SB3 check: both means on the seeds both ran, the difference
    with its interval, overlap, and the tasks an exact permutation test sets apart."""
    from sixaxis_avoid.benchmark.twins import twin_agreement, twin_rows

    def run(lr, task, seed, score, budget=100):
        return {"spec": {"learner": lr, "task": {"id": task}, "seed": seed, "budget": budget},
                "result": {"score": score}}  # fmt: skip

    tasks = ["t1", "t2", "t3"]
    runs = []
    for s in range(5):
        runs += [run("jax_ppo", t, s, 1.0) for t in tasks]
        # ppo: equal on t1 and t2, all 0 on t3 (5 vs 5: exact p = 2/252).
        runs += [run("ppo", "t1", s, 1.0), run("ppo", "t2", s, 1.0), run("ppo", "t3", s, 0.0)]
        runs += [run("jax_dqn", t, s, 0.5) for t in tasks]  # dqn never ran: no dqn row
    runs.append(run("jax_ppo", "t1", 7, 0.0))  # a seed ppo lacks is left out
    a = {"budgets": [100], "tasks": tasks, "runs": runs,
         "per_budget": {100: {"complete": ["jax_ppo", "ppo", "jax_dqn"]}}}  # fmt: skip
    rows = twin_agreement(a, reps=500)
    assert [(r["jax"], r["sb3"], r["budget"]) for r in rows] == [("jax_ppo", "ppo", 100)]
    r = rows[0]
    assert r["seeds"] == [0, 1, 2, 3, 4]
    assert r["jax_mean"] == pytest.approx(1.0) and r["sb3_mean"] == pytest.approx(2 / 3)
    assert r["diff"] == pytest.approx(1 / 3) and r["diff_ci"] == pytest.approx([1 / 3, 1 / 3])
    assert not r["overlap"]
    assert [(p["task"], round(p["p"], 4)) for p in r["parting"]] == [("t3", round(2 / 252, 4))]
    text = "\n".join(twin_rows(rows))
    assert "| jax_ppo | ppo | 100 | 5 | 1.000 (all equal) | 0.667 (all equal) |" in text
    assert "| **no** | t3 (1.00 vs 0.00, p 0.008) |" in text
    # Mixed outcomes: overlapping intervals, no task set apart.
    for x in runs:
        if x["spec"]["learner"] == "ppo" and x["spec"]["task"]["id"] == "t3":
            x["result"]["score"] = float(x["spec"]["seed"] % 2)
        if x["spec"]["learner"] == "jax_ppo" and x["spec"]["task"]["id"] == "t3":
            x["result"]["score"] = float(x["spec"]["seed"] < 3)
    r = twin_agreement(a, reps=500)[0]
    assert r["overlap"] and r["parting"] == [] and r["diff_ci"][0] < 0 < r["diff_ci"][1]
    text = "\n".join(twin_rows([r]))
    assert "| yes | none |" in text and "Where they part" not in text
    assert twin_rows([]) == []


def test_twin_rows_say_when_intervals_overlap_but_the_difference_excludes_zero():
    """Overlapping 95% intervals are the weaker test: a row whose difference's interval
    excludes 0 is not called plain agreement, and the page names it under the table."""
    from sixaxis_avoid.benchmark.twins import agree_label, twin_rows

    base = {"jax": "jax_dqn", "sb3": "dqn", "budget": 100000, "seeds": [0, 1, 2, 3, 4],
            "jax_mean": 0.596, "jax_ci": [0.553, 0.640], "sb3_mean": 0.679,
            "sb3_ci": [0.635, 0.715], "diff": -0.083, "diff_ci": [-0.137, -0.025],
            "overlap": True, "parting": [], "sb3_runs": None}  # fmt: skip
    assert agree_label(base) == "intervals overlap; the difference's excludes 0"
    assert agree_label({**base, "diff_ci": [-0.1, 0.02]}) == "yes"
    assert agree_label({**base, "diff_ci": [0.0, 0.048]}) == "yes"  # 0 at the edge is held
    assert agree_label({**base, "overlap": False}) == "**no**"
    same = {**base, "budget": 30000, "diff": 0.005, "diff_ci": [-0.049, 0.06]}
    text = "\n".join(twin_rows([same, base]))
    assert "| -0.083 [-0.137, -0.025] | intervals overlap; the difference's excludes 0 |" in text
    assert (
        "**Where they part**: jax_dqn against dqn at 100k (difference -0.083 [-0.137, -0.025], "
        "intervals overlap). With 2 rows, about 0.1 whose" in text
    )


def test_the_implementation_line_names_each_implementation_with_its_own_note():
    """SB3 PPO on rejax's implementation (borrowed values) and on SB3's own (its own
    search's values) are told apart: each gets its own note, a learner without notes none."""
    from sixaxis_avoid.benchmark.report_setups import IMPLEMENTATION_NOTES, implementation_line

    line = implementation_line({"ppo": ["rejax", "sb3"], "beta": ["rejax"]})
    assert line.startswith("**Implementation**: ppo runs with `implementation: rejax` (")
    assert f"`implementation: rejax` ({IMPLEMENTATION_NOTES['ppo']['rejax']})" in line
    assert f"`implementation: sb3` ({IMPLEMENTATION_NOTES['ppo']['sb3']})" in line
    assert "SB3's own PPO" in IMPLEMENTATION_NOTES["ppo"]["sb3"]
    assert line.endswith("; beta runs with `implementation: rejax`.")


def test_tuning_changes_name_the_budgets_where_a_learners_values_change():
    """A plateau mark between two budgets whose runs came from different searches (SB3 PPO
    on its own values at 300k, on jax_ppo's at 1M) is named; one source along the axis, or
    a budget the learner did not run, is not."""
    from sixaxis_avoid.benchmark.report_setups import tuning_changes, tuning_changes_line

    borrowed = ["jax_ppo's tuned values and rejax's implementation (not tuned for SB3)"]

    def g(status, impl):
        return {"status": status, "implementation": impl}

    a = {
        "learners": ["ppo", "jax_ppo", "dqn"],
        "budgets": [100_000, 300_000, 1_000_000],
        "per_budget": {
            100_000: {"learners": {"ppo": g(borrowed, ["rejax"]), "jax_ppo": g(["tuned"], []),
                                   "dqn": g(["tuned"], ["rejax"])}},
            300_000: {"learners": {"ppo": g(["tuned"], ["sb3"]), "jax_ppo": g(["tuned"], []),
                                   "dqn": g(["tuned"], ["rejax"])}},
            1_000_000: {"learners": {"ppo": g(borrowed, ["rejax"]), "jax_ppo": g(["tuned"], [])}},
        },
    }  # fmt: skip
    changes = tuning_changes(a)
    assert [(c["learner"], c["budgets"]) for c in changes] == [
        ("ppo", [100_000, 300_000]),
        ("ppo", [300_000, 1_000_000]),
    ]
    line = tuning_changes_line(changes)
    assert line.startswith("**Hyperparameters change along the axis**")
    assert "ppo from 300k (tuned; implementation sb3) to 1.00M (jax_ppo's tuned values" in line
    assert "jax_ppo from" not in line and "dqn" not in line
    assert tuning_changes_line([]) == ""


def test_twin_check_uses_the_replaced_runs_where_sb3_runs_on_its_own_values():
    """Where SB3 PPO's runs in the study are on its own search's values, the check of the two
    implementations compares jax_ppo with SB3 PPO's replaced runs on jax_ppo's values (kept
    beside the study); without those on every task the budget is named and not compared."""
    from sixaxis_avoid.benchmark.borrow import borrowed_status
    from sixaxis_avoid.benchmark.twins import twin_agreement, twin_rows

    def run(lr, task, seed, score, status):
        return {"spec": {"learner": lr, "task": {"id": task}, "seed": seed, "budget": 100,
                         "hyperparams_status": status},
                "result": {"score": score}}  # fmt: skip

    tasks, borrowed = ["t1", "t2"], borrowed_status("jax_ppo")
    runs = [run("jax_ppo", t, s, 1.0, "tuned") for t in tasks for s in range(3)]
    runs += [run("ppo", t, s, 0.0, "tuned") for t in tasks for s in range(3)]
    old = [run("ppo", t, s, 1.0, borrowed) for t in tasks for s in range(3)]
    other = [run("ppo", t, s, 0.5, borrowed) for t in tasks for s in range(3)]
    for r in other:
        r["spec"]["budget"] = 300  # another budget's replaced runs do not stand in
    a = {"budgets": [100], "tasks": tasks, "runs": runs,
         "per_budget": {100: {"complete": ["jax_ppo", "ppo"]}},
         "replaced": [{"dir": "v2-replaced/ppo-100", "runs": old},
                      {"dir": "v2-replaced/ppo-300", "runs": other}]}  # fmt: skip
    (r,) = twin_agreement(a, reps=200)
    assert r["sb3_runs"] == "v2-replaced/ppo-100" and r["sb3_mean"] == pytest.approx(1.0)
    assert r["overlap"] and r["seeds"] == [0, 1, 2]
    text = "\n".join(twin_rows([r]))
    assert "| jax_ppo | ppo (its runs on jax_ppo's values that the study replaced, " in text
    # Replaced runs that miss a task do not stand in: the budget is named, not compared.
    a["replaced"][0]["runs"] = [x for x in old if x["spec"]["task"]["id"] == "t1"]
    (r,) = twin_agreement(a, reps=200)
    assert r == {"jax": "jax_ppo", "sb3": "ppo", "budget": 100, "skipped": ["tuned"]}
    text = "\n".join(twin_rows([r]))
    assert "Not compared: ppo at 100 runs on other values than jax_ppo's (tuned)" in text
    assert "| jax_ppo | ppo |" not in text
    # SB3 runs on the twin's values are compared as they are.
    for x in runs:
        x["spec"]["hyperparams_status"] = borrowed if x["spec"]["learner"] == "ppo" else "tuned"
    (r,) = twin_agreement(a, reps=200)
    assert r["sb3_runs"] is None and r["sb3_mean"] == pytest.approx(0.0)


def test_replaced_runs_line_compares_the_study_runs_with_those_they_replaced():
    """The headline names a learner's runs that a re-run on other values replaced: their
    mean and success, and the study's runs against them on the same tasks and seeds."""
    from sixaxis_avoid.benchmark.report_setups import replaced_at, replaced_line

    def run(task, seed, score, status, budget=300):
        return {"spec": {"learner": "ppo", "task": {"id": task}, "seed": seed, "budget": budget,
                         "hyperparams_status": status},
                "result": {"score": score, "success": score, "optimal_lengths": [5]}}  # fmt: skip

    tasks = ["t1", "t2"]
    now = [run(t, s, 0.0 if (t, s) in {("t1", 0), ("t1", 1)} else 1.0, "tuned")
           for t in tasks for s in range(3)]  # fmt: skip
    before = [run(t, s, 0.0 if (t, s) == ("t2", 2) else 1.0, "borrowed") for t in tasks
              for s in range(3)]  # fmt: skip
    elsewhere = [run(t, s, 0.0, "borrowed", budget=100) for t in tasks for s in range(3)]
    a = {"runs": now, "tasks": tasks,
         "replaced": [{"dir": "v2-replaced/ppo-300", "runs": before},
                      {"dir": "v2-replaced/ppo-100", "runs": elsewhere}]}  # fmt: skip
    (r,) = replaced_at(a, 300, reps=200)
    assert (r["learner"], r["dir"], r["status"], r["runs"]) == (
        "ppo",
        "v2-replaced/ppo-300",
        ["borrowed"],
        6,
    )
    assert r["mean"] == pytest.approx(5 / 6) and r["success"] == (5, 6)
    assert (r["higher_now"], r["higher_before"]) == (1, 2)
    assert r["diff"] == pytest.approx(4 / 6 - 5 / 6)
    line = replaced_line([r], 300)
    assert line.startswith("**Replaced runs**: ppo's 6 runs at 300 on borrowed, which its ")
    assert (
        "score -0.167 against them on the same tasks and seeds (higher in 1 of the 6 pairs, "
        "lower in 2, equal in the rest)" in line
    )
    assert replaced_line([], 300) == "" and replaced_at({**a, "replaced": []}, 300) == []


def test_near_best_counts_the_candidates_within_one_run_of_the_best(tmp_path):
    """The tuning record's *near the best*: candidates within 1 / (seeds x tasks) of the best
    objective, the best included, of those scored (a trial without an objective is not)."""
    from sixaxis_avoid.benchmark.report_compute import near_best

    f = tmp_path / "t.json"
    trials = [{"objective": x} for x in (1.0, 0.94, 0.9334, 0.93, 0.5)] + [{"objective": None}]
    f.write_text(json.dumps({"seeds": [0, 1, 2], "tasks": list("abcde"), "trials": trials}))
    assert near_best(str(f)) == (3, 5)  # 1.0, 0.94 and 0.9334 lie within 1/15 of 1.0
    f.write_text(json.dumps({"seeds": [], "tasks": ["a"], "trials": trials}))
    assert near_best(str(f)) is None
    assert near_best(str(tmp_path / "missing.json")) is None


def test_v2_headline_names_a_set_in_progress_when_every_budget_ran(tmp_path):
    """A set still under way beside a study in which every learner ran every budget (here a
    search of SB3's own, its log directory) is named under the headline all the same."""
    from sixaxis_avoid.benchmark.report_v2 import write_report_v2

    suite_path, out = write_synthetic_study(tmp_path)
    log_dir = tmp_path / "study-pending" / "sb3_tune-beta-10000"
    (log_dir / "runs").mkdir(parents=True)
    (log_dir / "study.json").write_text(json.dumps({
        "command": "python -m sixaxis_avoid.benchmark.sb3_tune --learner beta --budget 10000",
        "learners": ["beta"], "budget": 10000, "kind": "sb3_tune", "candidates": 3,
        "seeds": [100, 101], "tasks": ["t1"], "runs": 6, "finished": False,
        "wall_time_s_total": 1800.0}))  # fmt: skip
    md = tmp_path / "BENCHMARKS.md"
    a = write_report_v2(out, md, reps=100, suite=str(suite_path))
    assert a["missing_budgets"] == {} and len(a["in_progress"]) == 1
    text = md.read_text()
    assert "Not every learner ran at every budget" not in text
    head = text.split("## Headline")[1].split("<!-- benchmark-headline:begin -->")[0]
    assert head.count("In progress, committed part way beside the study") == 1
    assert f"0 of 6 runs in `{log_dir}` (0.5 h of wall time so far)." in head

"""The learner benchmark end to end: the quick suite on a local Ray, on a simulated two-node
Ray cluster (same per-run results), resume, and the report from its result files."""

from __future__ import annotations

import json
import shutil

import pytest
import ray
from _helpers import deep_run_env_steps
from sixaxis_avoid.benchmark import load_suite, plan_runs, runner
from sixaxis_avoid.benchmark.learners import BUILTIN
from sixaxis_avoid.benchmark.report import write_report

LEARNERS = list(BUILTIN)


@pytest.fixture(scope="module")
def suite():
    return load_suite("quick")


@pytest.fixture(scope="module")
def specs(suite):
    return plan_runs(suite, LEARNERS)


@pytest.fixture(scope="module")
def local(tmp_path_factory, specs):
    """The quick suite on a local Ray (2 CPUs)."""
    out = tmp_path_factory.mktemp("bench-local")
    res = runner.run_study(specs, out, num_cpus=2, progress=False)
    assert not res["failures"], res["failures"]
    assert not ray.is_initialized(), "run_study left the Ray it started running"
    runner.write_manifest(
        out,
        {
            "command": "pytest",
            "suite": load_suite("quick").raw,
            "learners": LEARNERS,
            "tasks": [t.id for t in load_suite("quick").tasks],
            "seeds": sorted({s["seed"] for s in specs}),
            "runs": res["runs"],
            "wall_time_s_total": res["wall_time_s"],
            "ray": "local",
        },
    )
    return out, {r["key"]: r for r in runner.load_runs(out)}


def test_quick_suite_every_run_has_a_sane_result(local, specs, suite):
    _, runs = local
    assert len(runs) == len(specs) == len(LEARNERS) * len(suite.tasks) * len(suite.seeds)
    assert {runner.run_key(s) for s in specs} == set(runs)
    for r in runs.values():
        res, spec = r["result"], r["spec"]
        assert r["spec_hash"] == runner.spec_hash(spec)
        assert 0.0 <= res["score"] <= res["success"] <= 1.0
        assert len(res["paths"]) == len(res["optimal_lengths"])
        steps = [p["env_steps"] for p in res["curve"]]
        assert steps == sorted(steps) and steps[-1] == res["env_steps"]
        assert res["curve"][-1]["score"] == res["score"]
        for p, opt in zip(res["paths"], res["optimal_lengths"]):
            if p is not None:
                assert len(p) - 1 >= opt
        if res["first_success"] is not None:
            assert res["first_success"]["env_steps"] <= res["env_steps"]
            assert r["timing"]["first_success"]["wall_time_s"] >= 0
        if res["convergence"] is not None:
            assert res["score"] > 0 and res["convergence"]["env_steps"] <= res["env_steps"]
        if spec["family"] == "deep":
            assert res["env_steps"] == deep_run_env_steps(spec) <= spec["budget"]
            assert res["vec_env"] == "SixAxisVecEnv"  # the SB3 learners' native VecEnv
        if spec["task"]["kind"] == "goal":
            assert "algorithm2" not in res and len(res["paths"]) == spec["task"]["eval_targets"]
        else:
            alg2 = res["algorithm2"]
            assert isinstance(alg2["success"], bool) and 0 <= alg2["replans"] <= alg2["max_replans"]
            assert (alg2["failure"] is None) == alg2["success"]
        if spec["learner"] == "bfs":
            assert res["score"] == 1.0 and res["env_steps"] == 0
    # With the quick budget the tabular learner still finds the optimum somewhere.
    assert any(
        r["result"]["score"] == 1.0 for r in runs.values() if r["spec"]["learner"] == "q_assist"
    )


def test_two_node_cluster_gives_the_same_results(local, specs, tmp_path):
    from ray.cluster_utils import Cluster

    _, runs = local
    cluster = Cluster(
        initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False}
    )
    try:
        cluster.add_node(num_cpus=1)
        cluster.wait_for_nodes()
        res = runner.run_study(specs, tmp_path, address=cluster.address, progress=False)
    finally:
        cluster.shutdown()
    assert not res["failures"], res["failures"]
    remote = {r["key"]: r for r in runner.load_runs(tmp_path)}
    assert set(remote) == set(runs)
    assert len({r["host"]["ray_node"] for r in remote.values()}) == 2, "one node did all"
    for key, r in remote.items():
        assert r["result"] == runs[key]["result"], key


def test_progress_counts_finished_and_failed_runs_as_they_come(specs, tmp_path):
    """`on_progress` gets the counts so far after each run, a failed one included (here a
    learner no worker can import): what `run` writes into study.json during a command."""
    bfs = [s for s in specs if s["learner"] == "bfs"][:2]
    broken = {**bfs[1], "learner": "no_such_module_here:Learner"}
    seen: list[dict] = []
    res = runner.run_study([bfs[0], broken], tmp_path, num_cpus=1, progress=False,
                           on_progress=seen.append)  # fmt: skip
    assert [(c["ran"], len(c["failures"])) for c in seen] in ([(1, 0), (1, 1)], [(0, 1), (1, 1)])
    assert res["ran"] == 1 and res["skipped"] == 0 and res["runs"] == 2
    assert [k for k, _ in res["failures"]] == [runner.run_key(broken)]
    assert seen[-1]["failures"] == res["failures"]
    assert all(a["wall_time_s"] <= b["wall_time_s"] for a, b in zip(seen, seen[1:]))
    assert not ray.is_initialized()


def test_a_stop_request_lets_the_running_runs_finish_and_hands_out_no_more(specs, tmp_path):
    """`touch OUT_DIR/STOP` while a study runs on Ray (2 CPUs): runs are handed out only as
    CPUs free up, so when the first run's file lands (and the stop is asked for) exactly two
    runs had been handed out; the other one finishes and writes its file, no third starts, and
    the same call later runs only the rest."""
    bfs = [s for s in specs if s["learner"] == "bfs"][:5]
    assert len(bfs) == 5

    def ask_to_stop(_record):
        (tmp_path / runner.STOP_FILE).touch()

    res = runner.run_study(bfs, tmp_path, num_cpus=2, progress=False, on_result=ask_to_stop)
    assert res["stopped"] is True and res["ran"] == 2 and not res["failures"]
    assert len(list((tmp_path / "runs").glob("*.json"))) == 2
    assert not (tmp_path / runner.STOP_FILE).exists(), "the stop request was left behind"
    assert not ray.is_initialized()
    again = runner.run_study(bfs, tmp_path, num_cpus=2, progress=False)
    assert (again["skipped"], again["ran"], again["stopped"]) == (2, 3, False)


def test_resume_skips_finished_runs(local, specs, tmp_path):
    out, runs = local
    shutil.copytree(out / "runs", tmp_path / "runs")
    again = runner.run_study(specs, tmp_path, use_ray=False, progress=False)
    assert again["skipped"] == len(specs) and again["ran"] == 0
    # A lost file and a file of another spec are run again, and only they.
    lost = tmp_path / "runs" / "paper_simple__q_assist__s0.json"
    lost.unlink()
    stale = tmp_path / "runs" / "gen-easy-0__bfs__s1.json"
    rec = json.loads(stale.read_text())
    rec["spec_hash"] = "something-else"
    stale.write_text(json.dumps(rec))
    again = runner.run_study(specs, tmp_path, use_ray=False, progress=False)
    assert (again["skipped"], again["ran"]) == (len(specs) - 2, 2)
    for p in (lost, stale):
        got = json.loads(p.read_text())
        assert got["result"] == runs[p.stem]["result"]
    assert not list((tmp_path / "runs").glob(".*.tmp")), "a temporary file was left behind"


def test_report_from_the_quick_suite(local, tmp_path):
    out, _ = local
    md = tmp_path / "BENCHMARKS.md"
    a = write_report(out, md, reps=100)
    text = md.read_text()
    for want in ("IQM", "Probability of improvement", "Performance profiles", "| q_assist |"):
        assert want in text
    # Each deep learner's values come with the tuning study that chose them.
    assert "tuned: `python -m sixaxis_avoid.benchmark tune --suite v1" in text
    assert "pending a tuning run" not in text
    assert "## Did the curves plateau?" in text and "core-hours" in text
    for name in ("bench_curves.png", "bench_profiles.png", "bench_iqm.png"):
        png = tmp_path / "figures" / "bench" / name
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"figures/bench/{name}" in text
    agg = a["agg"]["learners"]
    assert agg["bfs"]["iqm"] == 1.0 and agg["bfs"]["iqm_ci"] == [1.0, 1.0]
    for lr, s in agg.items():
        assert s["iqm_ci"][0] <= s["iqm"] <= s["iqm_ci"][1], lr
        assert abs(s["optimality_gap"] - (1 - s["mean"])) < 1e-9, lr


def test_longer_budgets_beside_the_quick_suite(local, tmp_path, capsys):
    """`run --budget-scale` into a second directory, filled by two commands (the manifest keeps
    both and the union of their learners), then `report --longer` sets it beside the study."""
    from sixaxis_avoid.benchmark.__main__ import main

    out, runs = local
    longer = tmp_path / "x3"
    common = ["run", "--suite", "quick", "--budget-scale", "3", "--no-ray", "--no-progress"]
    assert main([*common, "--learners", "ppo", "--out-dir", str(longer)]) == 0
    dqn = ["--learners", "dqn", "--seeds", "1", "--set", "dqn.lr_schedule=linear"]
    assert main([*common, *dqn, "--out-dir", str(longer)]) == 0
    manifest = json.loads((longer / "study.json").read_text())
    assert manifest["learners"] == ["ppo", "dqn"] and manifest["seeds"] == [0, 1]
    assert len(manifest["commands"]) == 2 and "--learners dqn" in manifest["commands"][1]
    for r in runner.load_runs(longer):
        base = runs[r["key"]]["spec"]["budget"]
        assert r["spec"]["budget"] == 3 * base
        assert r["result"]["env_steps"] == deep_run_env_steps(r["spec"]) <= 3 * base

    md = tmp_path / "BENCHMARKS.md"
    a = write_report(out, md, reps=100, longer=longer)
    text = md.read_text()
    (lo,) = a["longer"]
    assert list(lo["learners"]) == ["ppo", "dqn"] and lo["scale"] == 3.0
    assert lo["learners"]["ppo"]["seeds"] == [0, 1] and lo["learners"]["dqn"]["seeds"] == [0]
    # x1 is the reported study's own runs on the same seeds; the longer side is the new runs.
    ppo = lo["learners"]["ppo"]
    x1 = [runs[f"{t}__ppo__s{s}"]["result"]["score"] for t in a["tasks"] for s in (0, 1)]
    assert ppo["agg"]["learners"]["x1"]["mean"] == pytest.approx(sum(x1) / len(x1))
    p = ppo["poi_long_over_x1"]
    assert 0.0 <= p["ci"][0] <= p["p"] <= p["ci"][1] <= 1.0
    assert ppo["agg"]["learners"]["best"]["mean"] >= ppo["agg"]["learners"]["long"]["mean"]
    # A --set override is named with the section; ppo ran as tuned.
    assert lo["learners"]["dqn"]["changed"] == {"lr_schedule": "linear"}
    assert lo["learners"]["ppo"]["changed"] == {}
    assert '## Longer budgets (x3, dqn: `lr_schedule`="linear")' in text
    # Deep learners not run longer get a cost estimate from their own x1 run time.
    assert set(lo["not_run"]) == {"a2c", "qrdqn"}
    assert "| ppo | 2 | 900 |" in text
    assert manifest["commands"][1] in text
    assert "With every deep budget x3 (*Longer budgets* below): **ppo** IQM" in text
    assert f"report --results {out} --longer {longer}" in text
    name = "longer_x3_dqn_lr_schedule_linear.png"  # named by its scale and change
    png = tmp_path / "figures" / "bench" / name
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"figures/bench/{name}" in text
    # Several longer studies, one section each: here PPO's untuned defaults at x2.
    plain = tmp_path / "x2-defaults"
    flags = ["--learners", "ppo", "--seeds", "1", "--hyperparams", "defaults"]
    assert (
        main([*common[:3], "--budget-scale", "2", *common[5:], *flags, "--out-dir", str(plain)])
        == 0
    )
    a = write_report(out, md, reps=100, longer=[longer, plain])
    text = md.read_text()
    second = a["longer"][1]["learners"]["ppo"]
    assert a["longer"][1]["scale"] == 2.0 and second["status"] == "defaults"
    assert second["changed"]["learning_rate"] == "default"  # SB3's own, not the tuned value
    assert "## Longer budgets (x2, ppo: untuned defaults)" in text
    assert "ppo's values here against the tuned ones" in text
    assert (tmp_path / "figures" / "bench" / "longer_x2_ppo_untuned_defaults.png").exists()
    assert f"--longer {longer} --longer {plain}" in text
    # Same budgets, other hyperparameters: a variant, not a "longer" study.
    variant = tmp_path / "x1-variant"
    flags = ["--learners", "ppo", "--seeds", "1", "--set", "ppo.n_epochs=3"]
    assert main([*common[:3], "--budget-scale", "1", *common[5:], *flags, "--out-dir",
                 str(variant)]) == 0  # fmt: skip
    a = write_report(out, md, reps=100, longer=[longer, variant])
    text = md.read_text()
    assert a["longer"][1]["scale"] == 1.0
    assert "## Same budgets, other hyperparameters (ppo: `n_epochs`=3)" in text
    assert "At the same budgets with other hyperparameters (*Same budgets" in text
    assert "| P(variant > x1) |" in text and "| core-hours x1 → variant |" in text
    assert "## Longer budgets (x1" not in text
    # A directory without results is a clear error, not a traceback.
    (tmp_path / "empty").mkdir()
    rc = main(
        ["report", "--results", str(out), "--out", str(md), "--longer", str(tmp_path / "empty")]
    )
    assert rc == 2 and "no result files" in capsys.readouterr().err


def test_run_flags_set_overrides_and_reject_bad_ones(suite):
    from sixaxis_avoid.benchmark.__main__ import main, parse_sets
    from sixaxis_avoid.benchmark.learners import LearnerError

    assert parse_sets(["ppo.lr_schedule=linear", "ppo.n_envs=4", "dqn.net_arch=[8, 8]"]) == {
        "ppo": {"lr_schedule": "linear", "n_envs": 4},
        "dqn": {"net_arch": [8, 8]},
    }
    for bad in ("ppo=1", "ppo.lr", ".x=1"):
        with pytest.raises(SystemExit, match=r"LEARNER\.KEY=VALUE"):
            parse_sets([bad])
    with pytest.raises(SystemExit, match="'a2c' is not one of --learners"):
        main(["run", "--suite", "quick", "--learners", "ppo", "--set", "a2c.n_envs=2"])
    # A schedule it does not know fails the run with the field and the value named.
    (spec,) = plan_runs(
        suite, ["ppo"], seeds=[0], tasks=[suite.task("paper_simple")],
        overrides={"ppo": {"lr_schedule": "cosine"}},
    )  # fmt: skip
    with pytest.raises(LearnerError, match="lr_schedule: 'cosine'"):
        runner.execute_run(spec)


def test_longer_only_report_beside_a_partial_x1_study(local, tmp_path, capsys):
    """`report --longer-only`: the x1 side holds just the learners compared, with more seeds of
    one learner than of another; each is compared on all of its own seeds."""
    from sixaxis_avoid.benchmark.__main__ import main

    out, runs = local
    x1 = tmp_path / "x1"
    (x1 / "runs").mkdir(parents=True)
    for key, r in runs.items():
        if r["spec"]["learner"] == "ppo" or (
            r["spec"]["learner"] == "dqn" and r["spec"]["seed"] == 0
        ):
            shutil.copy(out / "runs" / f"{key}.json", x1 / "runs" / f"{key}.json")
    manifest = json.loads((out / "study.json").read_text())
    runner.write_manifest(x1, {**manifest, "learners": ["ppo", "dqn"], "command": "pytest x1"})
    longer = tmp_path / "x2"
    flags = ["--suite", "quick", "--budget-scale", "2", "--no-ray", "--no-progress"]
    assert main(["run", *flags, "--learners", "ppo,dqn", "--out-dir", str(longer)]) == 0
    md = tmp_path / "docs" / "LONGER.md"
    argv = ["report", "--longer-only", "--results", str(x1), "--longer", str(longer)]
    assert main([*argv, "--out", str(md), "--reps", "100"]) == 0
    text = md.read_text()
    assert text.startswith("# Learner benchmark: longer budgets")
    assert (
        "## Longer budgets (x2)" in text and "| ppo | 2 | 600 |" in text and "| dqn | 1 |" in text
    )
    assert f"report --longer-only --results {x1} --longer {longer} --out {md}" in text
    assert "## Per task" not in text  # the x1 study's own tables are not repeated here
    assert "Not run with a longer budget here: a2c, qrdqn" in text
    png = tmp_path / "docs" / "figures" / "bench" / "longer_x2.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and "figures/bench/longer_x2.png" in text
    (section,) = json.loads((png.parent / "longer_summary.json").read_text())
    assert section["ppo"]["seeds"] == [0, 1] and section["dqn"]["seeds"] == [0]
    x1_scores = [
        runs[f"{t}__ppo__s{s}"]["result"]["score"] for t in manifest["tasks"] for s in (0, 1)
    ]
    assert section["ppo"]["aggregates"]["x1"]["mean"] == pytest.approx(sum(x1_scores) / 6)
    # A second study at the same scale with one change: its own section and figure.
    lin = tmp_path / "x2-lin"
    sets = ["--learners", "ppo", "--set", "ppo.lr_schedule=linear"]
    assert main(["run", *flags, *sets, "--out-dir", str(lin)]) == 0
    assert main([*argv, "--longer", str(lin), "--out", str(md), "--reps", "100"]) == 0
    text = md.read_text()
    assert '## Longer budgets (x2, ppo: `lr_schedule`="linear")' in text
    assert "figures/bench/longer_x2_ppo_lr_schedule_linear.png" in text
    assert (png.parent / "longer_x2_ppo_lr_schedule_linear.png").exists()
    # Without a longer study there is nothing to write: a clear error, not a traceback.
    assert main(["report", "--longer-only", "--results", str(x1), "--out", str(md)]) == 2
    assert "--longer-only needs at least one --longer DIR" in capsys.readouterr().err

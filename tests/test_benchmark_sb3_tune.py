"""``sb3_tune``: SB3's PPO and DQN searched on their own at one budget of a budget axis:
the draws and the twin's values scored as benchmark runs without re-plans, every trial on
record, a stopped search resumed, the best recorded (docs/BENCHMARKS.md, *How to run*)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sixaxis_avoid.benchmark import runner, sb3_tune
from sixaxis_avoid.benchmark.jax_values import check_values
from sixaxis_avoid.benchmark.learners import resolve
from sixaxis_avoid.benchmark.tasks import SUITES_DIR, load_suite

TINY = {
    "ppo": {"n_envs": 2, "n_steps": 100, "batch_size": 50, "n_epochs": 1, "net_arch": [16, 16],
            "max_episode_steps": 100},
    "dqn": {"net_arch": [16, 16], "batch_size": 16, "buffer_size": 1000, "learning_starts": 100,
            "train_freq": 4, "gradient_steps": 1, "max_episode_steps": 50,
            "target_update_interval": 100},
}  # fmt: skip


@pytest.fixture(params=["ppo", "dqn"])
def setup(request, tmp_path, monkeypatch):
    learner = request.param
    quick = json.loads((SUITES_DIR / "quick.json").read_text())
    suite = {**quick, "name": "sb3-tune-test", "budgets": {"axis": [400], "checkpoints": 2}}
    path = tmp_path / "suite.json"
    path.write_text(json.dumps(suite))
    # Two tiny draws (the space's draws are sized for the study, not for a test).
    monkeypatch.setattr(
        sb3_tune,
        "draw",
        lambda algo, trials, groups, seed: [
            check_values(algo, {**TINY[algo], "learning_rate": lr}) for lr in (3e-4, 1e-3)[:trials]
        ],
    )
    hp = tmp_path / "v2.json"
    values = check_values(learner, {**TINY[learner], "learning_rate": 2e-3})
    twin = {"values": values, "status": "tuned", "n_trials": 32, "seeds": [100],
            "tasks": ["tune-gen-medium-1000"]}  # fmt: skip
    hp.write_text(json.dumps({"learners": {f"jax_{learner}": {"by_budget": {"400": twin}}}}))
    return learner, path, hp


def test_the_search_scores_draws_and_twin_resumes_and_records(setup, tmp_path):
    learner, suite_path, hp = setup
    out = tmp_path / f"{learner}-400.json"
    argv = ["--learner", learner, "--suite", str(suite_path), "--budget", "400", "--trials", "2",
            "--seeds", "2", "--hyperparams", str(hp), "--out", str(out), "--no-ray"]  # fmt: skip
    a = sb3_tune.main(argv)
    assert [t["name"] for t in a["trials"]] == ["trial0", "trial1", "twin"]
    assert [t["values"]["implementation"] for t in a["trials"]] == ["sb3", "sb3", "rejax"]
    assert a["seeds"] == [100, 101] and a["tasks"] == ["tune-gen-medium-1000"]
    log_dir = tmp_path / f"{learner}-400.json.runs"
    runs = runner.load_runs(log_dir)
    assert len(runs) == 3 * 2 and a["runs"] == 6 and a["resumed_runs"] == 0
    defaults = dict(resolve(learner).defaults)
    overrides = load_suite(str(suite_path)).raw["overrides"][learner]
    for t in a["trials"]:
        scores = t["final_score"]["tune-gen-medium-1000"]
        assert len(scores) == 2 and t["objective"] == pytest.approx(np.mean(scores))
        mine = [r for r in runs if r["spec"]["tag"] == t["name"]]
        assert sorted(r["result"]["score"] for r in mine) == sorted(scores)
        for r in mine:
            # Exactly the candidate over the defaults, at the budget, without re-plans.
            assert r["spec"]["hyperparams"] == {**defaults, **overrides, **t["values"]}
            assert r["spec"]["max_replans"] == 0 and r["spec"]["budget"] == 400
            assert r["result"]["algorithm2"]["replans"] == 0
        assert t["curves"]["tune-gen-medium-1000"]["env_steps"][-1] <= 400
    best = max(a["trials"], key=lambda t: (t["objective"], -t["number"]))
    assert a["best_trial"] == best["number"] and a["wall_time_s"] > 0 and a["cpu_time_s"] > 0

    # Stopped midway (a run lost): the same command runs that one only, with the same trials.
    lost = next((log_dir / "runs").glob("trial1__*.json"))
    lost.unlink()
    b = sb3_tune.main([*argv, "--record"])
    assert b["resumed_runs"] == 5 and b["trials"] == a["trials"]
    assert b["wall_time_s"] > a["wall_time_s"]  # the calls' wall times add up
    entry = json.loads(hp.read_text())["learners"][learner]["by_budget"]["400"]
    assert entry["values"] == best["values"] and entry["status"] == "tuned"
    assert entry["best_candidate"] == best["name"] and entry["n_trials"] == 3
    assert entry["objective"] == best["objective"] and entry["trials"] == str(out)


def test_a_budget_off_the_axis_and_an_unknown_implementation_are_refused(setup, tmp_path):
    learner, suite_path, hp = setup
    argv = ["--learner", learner, "--suite", str(suite_path), "--hyperparams", str(hp),
            "--out", str(tmp_path / "t.json"), "--no-ray"]  # fmt: skip
    with pytest.raises(SystemExit, match=r"--budget: 500 is not on suite .*\[400\]"):
        sb3_tune.main([*argv, "--budget", "500"])
    with pytest.raises(SystemExit, match=r"--implementation: 'mine' is not one of rejax, sb3"):
        sb3_tune.main([*argv, "--budget", "400", "--implementation", "mine"])
    assert not (tmp_path / "t.json").exists()
